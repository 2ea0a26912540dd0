// `binbow db build` and `binbow db query`: an image database on disk (.bbdb),
// and the `binbow info` lines for such a file.
#include <cstdio>
#include <cstring>
#include <fstream>
#include <memory>
#include <string>
#include <vector>

#include "binbow/database.h"
#include "binbow/error.h"
#include "binbow/formats.h"
#include "binbow/vision/features.h"
#include "binbow/vision/image_source.h"
#include "commands.h"
#include "default_vocabulary.h"
#include "extractor_options.h"
#include "output_options.h"
#include "progress.h"

namespace binbow::cli {
namespace {

struct DbBuildArguments {
  std::string vocabulary;
  std::string output;
  std::vector<std::string> inputs;
  std::string descriptor = kDefaultDescriptor;
  int features = 0;
  unsigned levels_up = 4;
  bool no_direct_index = false;
  bool external_vocabulary = false;
};

struct DbQueryArguments {
  std::string database;
  std::string image;
  std::size_t top = 10;
  std::string descriptor = kDefaultDescriptor;
  int features = 0;
  std::string vocabulary;
};

std::unique_ptr<vision::FeatureExtractor> extractor_for(const Vocabulary& vocabulary,
                                                        const std::string& vocabulary_name,
                                                        const std::string& descriptor, int features,
                                                        bool embedded_in_database = false) {
  auto extractor = vision::make_extractor(descriptor, features);
  check_vocabulary_fits(vocabulary, vocabulary_name, descriptor, extractor->code_size(),
                        embedded_in_database);
  return extractor;
}

void run_db_build(const DbBuildArguments& arguments) {
  prepare_output_file("-o", arguments.output);
  const Vocabulary vocabulary = load_vocabulary(arguments.vocabulary);
  const auto extractor =
      extractor_for(vocabulary, arguments.vocabulary, arguments.descriptor, arguments.features);
  Database database(vocabulary, {!arguments.no_direct_index, arguments.levels_up});
  vision::ImageSource source(arguments.inputs);
  const long long known = source.size();
  Progress progress("adding images", known > 0 ? static_cast<std::size_t>(known) : 0);
  vision::Frame frame;
  std::size_t features = 0;
  while (source.next(frame)) {
    const vision::Features extracted = extractor->extract(frame.image);
    features += extracted.descriptors.rows();
    const EntryId entry = database.add(extracted.descriptors.view());
    database.set_label(entry, frame.name);
    progress.update(database.size());
  }
  progress.finish();
  if (database.size() == 0) throw InvalidArgument("db build: no images found in the inputs");
  database.save(arguments.output, !arguments.external_vocabulary);
  std::printf("%s: %zu entries, %zu features, vocabulary %s\n", arguments.output.c_str(),
              database.size(), features, vocabulary.description().c_str());
}

void run_db_query(const DbQueryArguments& arguments) {
  const Database database =
      arguments.vocabulary.empty()
          ? Database::load(arguments.database)
          : Database::load(arguments.database, load_vocabulary(arguments.vocabulary));
  const bool embedded = arguments.vocabulary.empty();
  const auto extractor =
      extractor_for(database.vocabulary(), embedded ? arguments.database : arguments.vocabulary,
                    arguments.descriptor, arguments.features, embedded);
  const vision::Features features = extractor->extract(vision::read_grey_image(arguments.image));
  BowVector bow;
  database.vocabulary().transform(features.descriptors.view(), bow);
  const auto results = database.query(bow, arguments.top);
  std::printf("rank\tentry\tfile\tscore\n");
  for (std::size_t rank = 0; rank < results.size(); ++rank) {
    const QueryResult& result = results[rank];
    std::printf("%zu\t%u\t%s\t%.6f\n", rank + 1, result.entry, database.label(result.entry).c_str(),
                result.score);
  }
}

}  // namespace

bool print_database_info(const std::string& path, bool verify) {
  char magic[8] = {};
  std::ifstream file(path, std::ios::binary);
  if (!file.read(magic, sizeof magic) || std::memcmp(magic, "BINBOWDB", 8) != 0) return false;
  const DatabaseFileInfo info = Database::inspect(path, verify);
  std::printf("kind: database\n");
  std::printf("entries: %zu\n", info.entries);
  std::printf("next_entry_id: %u\n", info.next_entry_id);
  if (info.direct_index)
    std::printf("direct_index: %u levels up\n", info.direct_index_levels_up);
  else
    std::printf("direct_index: none\n");
  std::printf("vocabulary: %s\n", info.vocabulary_description.c_str());
  std::printf("vocabulary_checksum: %08x\n", info.vocabulary_checksum);
  std::printf("vocabulary_included: %s\n", info.vocabulary_included ? "yes" : "no");
  return true;
}

void add_db_command(CLI::App& app) {
  CLI::App* db = app.add_subcommand("db", "Build and query image databases (.bbdb)");
  db->require_subcommand(1);

  auto build = std::make_shared<DbBuildArguments>();
  CLI::App* build_command =
      db->add_subcommand("build", "Add images to a new database and save it (.bbdb)");
  build_command->add_option("--vocab", build->vocabulary, "Vocabulary (any format binbow reads)")
      ->required();
  build_command->add_option("-o,--output", build->output, "Output database (.bbdb)")->required();
  add_extractor_options(build_command, build->descriptor, build->features);
  build_command
      ->add_option("--direct-index-levels-up", build->levels_up,
                   "Direct index nodes this many levels above the words (the root when more "
                   "than the vocabulary's depth)")
      ->check(CLI::Range(0, 255))  // what a .bbdb file holds
      ->capture_default_str();
  build_command->add_flag("--no-direct-index", build->no_direct_index,
                          "Do not keep the direct index (smaller file)");
  build_command->add_flag("--external-vocab", build->external_vocabulary,
                          "Store only the vocabulary's checksum, not the vocabulary");
  build_command
      ->add_option("inputs", build->inputs,
                   "Image files, directories, videos or text lists of images")
      ->required();
  build_command->callback([build] { run_db_build(*build); });

  auto query = std::make_shared<DbQueryArguments>();
  CLI::App* query_command =
      db->add_subcommand("query", "The database entries most similar to an image");
  query_command->add_option("DB", query->database, "Database (.bbdb)")->required();
  query_command->add_option("IMAGE", query->image, "Query image")->required();
  query_command->add_option("--top", query->top, "Number of results")
      ->check(CLI::Range(1, 1000000))
      ->capture_default_str();
  add_extractor_options(query_command, query->descriptor, query->features,
                        "as used to build the database");
  query_command->add_option("--vocab", query->vocabulary,
                            "Vocabulary, for databases built with --external-vocab");
  query_command->callback([query] { run_db_query(*query); });
}

}  // namespace binbow::cli
