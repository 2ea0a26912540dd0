#include "trained_on_option.h"

#include "binbow/error.h"
#include "core/warnings.h"
#include "vision_commands.h"

namespace binbow::cli {

void add_trained_on_option(CLI::App* command, std::string& descriptor, const std::string& use) {
  command->add_option("--descriptor", descriptor,
                      "The extractor the vocabulary was trained on (orb, brief, akaze, brisk), "
                      "for files that do not record it (every format but .bbw; VINS files are "
                      "brief); without it such a file is taken for orb, with a warning" +
                          (use.empty() ? std::string() : ". " + use));
}

void check_known_descriptor(const std::string& descriptor) {
  vision_commands().descriptor_code_size(descriptor);
}

void check_descriptor_length(const std::string& descriptor, const Vocabulary& vocabulary) {
  const std::size_t code_size = vision_commands().descriptor_code_size(descriptor);
  if (code_size != vocabulary.code_size())
    throw InvalidArgument("--descriptor " + descriptor + ": " + descriptor + " gives " +
                          std::to_string(code_size * 8) + "-bit descriptors, the vocabulary has " +
                          std::to_string(vocabulary.code_size() * 8) + "-bit ones");
}

detail::LoadedVocabulary load_vocabulary_trained_on(const std::string& path,
                                                    VocabularyFormat format,
                                                    const std::string& descriptor) {
  if (!descriptor.empty()) check_known_descriptor(descriptor);
  detail::LoadedVocabulary loaded = detail::load_vocabulary_with_details(path, format, descriptor);
  if (!descriptor.empty()) check_descriptor_length(descriptor, loaded.vocabulary);
  if (!loaded.descriptor_warning.empty()) detail::warn(loaded.descriptor_warning);
  return loaded;
}

}  // namespace binbow::cli
