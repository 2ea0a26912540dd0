// `binbow info FILE`: what a vocabulary (any readable format), database or
// loop detector state holds, as `key: value` lines (--json: one object). `binbow info --system`:
// the CPU features binbow's kernels depend on and the Hamming kernel set in use,
// so that a timing can be reported with the kernel that produced it.
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include "binbow/descriptors.h"
#include "binbow/formats.h"
#include "binbow/vocabulary.h"
#include "commands.h"
#include "formats/loader.h"
#include "info_fields.h"
#include "trained_on_option.h"
#include "vision_commands.h"

namespace binbow::cli {

namespace {

void describe_vocabulary(const Vocabulary& v, InfoFields& fields) {
  fields.add("kind", "vocabulary");
  fields.add("descriptor", v.descriptor().empty() ? "unknown" : v.descriptor());
  fields.add("descriptor_bits", v.code_size() * 8);
  fields.add("branching", v.branching());
  fields.add("levels", v.levels());
  fields.add("nodes", v.node_count());
  fields.add("words", v.word_count());
  fields.add("weighting", to_string(v.weighting()));
  fields.add("scoring", to_string(v.scoring()));
  fields.add("checksum", hex_checksum(v.checksum()));
}

// A loop detector state (.bbld): what to resume it with. False for any other
// file; only a state loads the module with the loop detector.
bool describe_if_loop_state(const std::string& path, const std::string& vocab_argument,
                            InfoFields& fields) {
  // Only a regular file is opened here: a FIFO would block (the readers
  // below refuse it with a clear error).
  std::error_code error;
  if (!std::filesystem::is_regular_file(path, error)) return false;
  char magic[8] = {};
  std::ifstream in(path, std::ios::binary);
  if (!in.read(magic, sizeof magic) || std::memcmp(magic, "BINBOWLD", 8) != 0) return false;
  vision_commands().describe_loop_state(path, vocab_argument, fields);
  return true;
}

void describe_system(InfoFields& fields) {
  for (const CpuFeature& feature : cpu_features())
    fields.add(std::string("cpu_") + feature.name, feature.present ? "yes" : "no");
  std::string supported;
  for (const std::string& name : supported_hamming_kernels())
    supported += (supported.empty() ? "" : " ") + name;
  fields.add("hamming_kernels_supported", supported);
  fields.add("hamming_kernel", hamming_kernel_name());
}

void describe(const std::string& path, bool header_only, const std::string& vocab,
              const std::string& descriptor, bool system, InfoFields& fields) {
  if (system) return describe_system(fields);
  if (path.empty()) throw CLI::RequiredError("FILE");
  if (!descriptor.empty()) check_known_descriptor(descriptor);
  if (describe_if_loop_state(path, vocab, fields)) return;
  if (describe_database(path, !header_only, vocab, descriptor, fields)) return;
  // The format the loader settled on: inside a .gz it is known only after
  // decompressing (ORB-SLAM and VINS binary files are told apart by size).
  const detail::LoadedVocabulary loaded =
      load_vocabulary_trained_on(path, VocabularyFormat::kAuto, descriptor);
  fields.add("format", to_string(loaded.format));
  describe_vocabulary(loaded.vocabulary, fields);
}

}  // namespace

void add_info_command(CLI::App& app) {
  auto* cmd =
      app.add_subcommand("info", "Describe a vocabulary, database or loop detector state file");
  auto path = std::make_shared<std::string>();
  auto header_only = std::make_shared<bool>(false);
  auto system = std::make_shared<bool>(false);
  auto vocab = std::make_shared<std::string>();
  auto descriptor = std::make_shared<std::string>();
  auto* file = cmd->add_option("FILE", *path,
                               "Vocabulary (.bbw, DBoW2 .yml[.gz], ORBvoc.txt, ...) or database");
  auto* header = cmd->add_flag("--header-only", *header_only,
                               "Database: read the header only, without checking the whole file");
  cmd->add_option("--vocab", *vocab,
                  "Loop detector state of a fixed vocabulary: that vocabulary, to check the whole "
                  "state as --resume-state does (default: the descriptor's bundled one, when it "
                  "is the state's). Database built with --external-vocab: its vocabulary, to "
                  "load it whole as db query does");
  add_trained_on_option(cmd, *descriptor,
                        "Also for a database's --vocab; a loop detector state names its own");
  cmd->add_flag("--system", *system,
                "Print the CPU features binbow uses and the Hamming kernel set in use")
      ->excludes(file)
      ->excludes(header);
  auto json = std::make_shared<bool>(false);
  cmd->add_flag("--json", *json,
                "Print the fields as one JSON object (numbers as numbers), with "
                "\"binbow_version\"");
  cmd->callback([path, header_only, vocab, descriptor, system, json] {
    InfoFields fields;
    describe(*path, *header_only, *vocab, *descriptor, *system, fields);
    fields.print(*json);
  });
}

}  // namespace binbow::cli
