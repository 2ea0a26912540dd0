// `binbow info FILE`: what a vocabulary (any readable format), database or
// loop detector state holds, as `key: value` lines. `binbow info --system`:
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
#include "trained_on_option.h"
#include "vision_commands.h"

namespace binbow::cli {

namespace {

void print_vocabulary(const Vocabulary& v) {
  std::printf("kind: vocabulary\n");
  std::printf("descriptor: %s\n", v.descriptor().empty() ? "unknown" : v.descriptor().c_str());
  std::printf("descriptor_bits: %zu\n", v.code_size() * 8);
  std::printf("branching: %u\n", v.branching());
  std::printf("levels: %u\n", v.levels());
  std::printf("nodes: %zu\n", v.node_count());
  std::printf("words: %zu\n", v.word_count());
  std::printf("weighting: %s\n", to_string(v.weighting()));
  std::printf("scoring: %s\n", to_string(v.scoring()));
  std::printf("checksum: %08x\n", v.checksum());
}

// A loop detector state (.bbld): what to resume it with. False for any other
// file; only a state loads the module with the loop detector.
bool print_if_loop_state(const std::string& path, const std::string& vocab_argument) {
  // Only a regular file is opened here: a FIFO would block (the readers
  // below refuse it with a clear error).
  std::error_code error;
  if (!std::filesystem::is_regular_file(path, error)) return false;
  char magic[8] = {};
  std::ifstream in(path, std::ios::binary);
  if (!in.read(magic, sizeof magic) || std::memcmp(magic, "BINBOWLD", 8) != 0) return false;
  vision_commands().print_loop_state_info(path, vocab_argument);
  return true;
}

void print_system_info() {
  for (const CpuFeature& feature : cpu_features())
    std::printf("cpu_%s: %s\n", feature.name, feature.present ? "yes" : "no");
  std::string supported;
  for (const std::string& name : supported_hamming_kernels())
    supported += (supported.empty() ? "" : " ") + name;
  std::printf("hamming_kernels_supported: %s\n", supported.c_str());
  std::printf("hamming_kernel: %s\n", hamming_kernel_name());
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
  cmd->callback([path, header_only, vocab, descriptor, system] {
    if (*system) return print_system_info();
    if (path->empty()) throw CLI::RequiredError("FILE");
    if (!descriptor->empty()) check_known_descriptor(*descriptor);
    if (print_if_loop_state(*path, *vocab)) return;
    if (print_database_info(*path, !*header_only, *vocab, *descriptor)) return;
    // The format the loader settled on: inside a .gz it is known only after
    // decompressing (ORB-SLAM and VINS binary files are told apart by size).
    const detail::LoadedVocabulary loaded =
        load_vocabulary_trained_on(*path, VocabularyFormat::kAuto, *descriptor);
    std::printf("format: %s\n", to_string(loaded.format));
    print_vocabulary(loaded.vocabulary);
  });
}

}  // namespace binbow::cli
