#include "default_vocabulary.h"

#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <system_error>

#include <CLI/CLI.hpp>

#include "binbow/error.h"
#include "binbow/formats.h"
#include "binbow/vision/features.h"

namespace binbow::cli {
namespace fs = std::filesystem;

namespace {
std::string no_default_vocabulary(const std::string& descriptor) {
  return "binbow bundles default vocabularies for orb and brief only; pass a vocabulary of " +
         descriptor + " descriptors with --vocab FILE (build-vocab --descriptor " + descriptor +
         " trains one)";
}
}  // namespace

bool has_default_vocabulary(const std::string& descriptor) {
  return descriptor == "orb" || descriptor == "brief";
}

std::string default_vocabulary_name(const std::string& descriptor) {
  if (has_default_vocabulary(descriptor)) return descriptor + "_default.bbw";
  throw InvalidArgument(no_default_vocabulary(descriptor));
}

void check_vocabulary_given(const std::string& vocab_argument, const std::string& given) {
  const std::string& descriptor = given.empty() ? std::string(vision::kDefaultDescriptor) : given;
  if (vocab_argument.empty() && !has_default_vocabulary(descriptor))
    throw CLI::ValidationError(no_default_vocabulary(descriptor));
}

std::vector<std::string> data_directories() {
  std::vector<std::string> directories;
  if (const char* data_dir = std::getenv("BINBOW_DATA_DIR"); data_dir != nullptr && *data_dir)
    directories.push_back(fs::path(data_dir).lexically_normal().string());
  std::error_code error;
  const fs::path exe = fs::read_symlink("/proc/self/exe", error);
  if (!error)
    directories.push_back(
        (exe.parent_path() / ".." / "share" / "binbow").lexically_normal().string());
  return directories;
}

std::vector<std::string> default_vocabulary_candidates(const std::string& descriptor) {
  const std::string name = default_vocabulary_name(descriptor);
  std::vector<std::string> candidates;
  for (const std::string& directory : data_directories())
    candidates.push_back((fs::path(directory) / "vocab" / name).string());
  return candidates;
}

namespace {
std::string first_existing(const std::vector<std::string>& candidates, const std::string& what,
                           const std::string& advice) {
  std::string searched;
  for (const std::string& path : candidates) {
    std::error_code error;
    if (fs::exists(path, error)) return fs::canonical(path, error).string();
    searched += "\n  " + path;
  }
  throw InvalidArgument(what + " is not installed; " + advice + ". Searched:" + searched);
}
}  // namespace

std::string find_bundled_data(const std::string& relative, const std::string& what) {
  std::vector<std::string> candidates;
  for (const std::string& directory : data_directories())
    candidates.push_back((fs::path(directory) / relative).string());
  return first_existing(candidates, what,
                        "set BINBOW_DATA_DIR to binbow's data directory (the repository's data/)");
}

std::string default_vocabulary_path(const std::string& descriptor) {
  return first_existing(
      default_vocabulary_candidates(descriptor),
      "the default " + descriptor + " vocabulary (" + default_vocabulary_name(descriptor) + ")",
      "pass one with --vocab FILE");
}

void check_vocabulary_fits(const Vocabulary& vocabulary, const std::string& vocabulary_name,
                           const std::string& descriptor, std::size_t code_size) {
  if (vocabulary.code_size() != code_size)
    throw InvalidArgument(vocabulary_name + ": vocabulary of " +
                          std::to_string(vocabulary.code_size() * 8) + "-bit descriptors, but " +
                          descriptor + " gives " + std::to_string(code_size * 8) +
                          "-bit descriptors (--descriptor)");
  bool any_weight = false;
  for (WordId word = 0; word < vocabulary.word_count() && !any_weight; ++word)
    any_weight = vocabulary.word_weight(word) > 0;
  if (vocabulary.word_count() > 0 && !any_weight)
    std::fprintf(stderr,
                 "binbow: warning: %s: every word weighs 0 (all stop words): every image becomes "
                 "an empty bag of words and no place can be recognised; rebuild the vocabulary "
                 "('binbow build-vocab') or convert it from a file that has its weights\n",
                 vocabulary_name.c_str());
  if (!vocabulary.descriptor().empty() && vocabulary.descriptor() != descriptor) {
    throw InvalidArgument(vocabulary_name + ": the vocabulary was trained on " +
                          vocabulary.descriptor() + " descriptors, not " + descriptor +
                          ": pass --descriptor " + vocabulary.descriptor() +
                          " or a vocabulary trained on " + descriptor);
  }
}

std::string descriptor_for(const std::string& given, const Vocabulary& vocabulary) {
  if (!given.empty()) return given;
  if (!vocabulary.descriptor().empty()) return vocabulary.descriptor();
  return vision::kDefaultDescriptor;
}

std::string load_loop_vocabulary(const std::string& vocab_argument, std::string& descriptor,
                                 Vocabulary& vocabulary) {
  const std::string path =
      vocab_argument.empty()
          ? default_vocabulary_path(descriptor.empty() ? std::string(vision::kDefaultDescriptor)
                                                       : descriptor)
          : vocab_argument;
  // The extractor given is the vocabulary's when its file does not say (the
  // loader warns when it has to assume one).
  vocabulary = load_vocabulary(path, VocabularyFormat::kAuto, descriptor);
  descriptor = descriptor_for(descriptor, vocabulary);
  check_vocabulary_fits(vocabulary, path, descriptor,
                        vision::make_extractor(descriptor)->code_size());
  std::error_code error;
  const std::filesystem::path absolute = std::filesystem::absolute(path, error);
  return error ? path : absolute.string();
}

}  // namespace binbow::cli
