// `binbow info FILE`: what a vocabulary (any readable format) or database holds,
// as `key: value` lines.
#include <cstdio>
#include <string>

#include "binbow/formats.h"
#include "binbow/vocabulary.h"
#include "commands.h"

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

}  // namespace

void add_info_command(CLI::App& app) {
  auto* cmd = app.add_subcommand("info", "Describe a vocabulary or database file");
  auto path = std::make_shared<std::string>();
  auto header_only = std::make_shared<bool>(false);
  cmd->add_option("FILE", *path, "Vocabulary (.bbw, DBoW2 .yml[.gz], ORBvoc.txt, ...) or database")
      ->required();
  cmd->add_flag("--header-only", *header_only,
                "Database: read the header only, without checking the whole file");
  cmd->callback([path, header_only] {
    if (print_database_info(*path, !*header_only)) return;
    const VocabularyFormat format = detect_vocabulary_format(*path);
    const Vocabulary vocabulary = load_vocabulary(*path, format);
    std::printf("format: %s\n", to_string(format));
    print_vocabulary(vocabulary);
  });
}

}  // namespace binbow::cli
