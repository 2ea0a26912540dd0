// `binbow db build`, `query` and `add`: images described into a database on
// disk (.bbdb). `db remove` and the `db` command itself are in db.cpp.
#include <cstdio>
#include <memory>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include <nlohmann/json.hpp>

#include "binbow/database.h"
#include "binbow/error.h"
#include "binbow/formats.h"
#include "binbow/vision/features.h"
#include "binbow/vision/frame_pipeline.h"
#include "binbow/vision/image_source.h"
#include "commands.h"
#include "core/output_path.h"
#include "database_loading.h"
#include "default_vocabulary.h"
#include "extractor_options.h"
#include "image_source_options.h"
#include "invocation.h"
#include "output_options.h"
#include "progress.h"
#include "query_options.h"
#include "threads_options.h"

namespace binbow::cli {
namespace {

struct DbBuildArguments {
  std::string vocabulary;
  std::string output;
  std::vector<std::string> inputs;
  std::string descriptor;  // "": the vocabulary's
  int features = 0;
  unsigned levels_up = 4;
  bool no_direct_index = false;
  bool external_vocabulary = false;
  vision::ImageSourceOptions source;
  unsigned threads = 0;
  double wait_seconds = 0;
};

// What db query and db add need to read a database and describe images for it.
struct DbArguments {
  std::string database;
  std::string descriptor;  // "": the vocabulary's
  int features = 0;
  std::string vocabulary;
  std::vector<std::string> inputs;
  vision::ImageSourceOptions source;
  unsigned threads = 0;
  bool compact = false;     // db add: a full save
  double wait_seconds = 0;  // db add: for another writer
};

struct DbQueryArguments : DbArguments {
  std::size_t top = 10;
  bool json = false;
  QueryOptions query;  // --fast and its tuning
};

std::shared_ptr<const vision::FeatureExtractor> extractor_for(const Vocabulary& vocabulary,
                                                              const std::string& vocabulary_name,
                                                              const std::string& descriptor,
                                                              int features) {
  const std::string name = descriptor_for(descriptor, vocabulary);
  auto extractor = vision::make_extractor(name, features);
  check_vocabulary_fits(vocabulary, vocabulary_name, name, extractor->code_size());
  return extractor;
}

// The extractor of --descriptor, else the one the database's vocabulary
// records, checked against that vocabulary: its own (embedded) or the --vocab given.
std::shared_ptr<const vision::FeatureExtractor> database_extractor(const Database& database,
                                                                   const DbArguments& arguments) {
  const bool embedded = arguments.vocabulary.empty();
  return extractor_for(database.vocabulary(), embedded ? arguments.database : arguments.vocabulary,
                       arguments.descriptor, arguments.features);
}

// What add_images added: the entries with their labels, and the frames
// skipped (--skip-unreadable).
struct AddedImages {
  std::vector<std::pair<EntryId, std::string>> entries;
  std::size_t skipped = 0;
};

// The frames of `inputs` described by `extractor`, read ahead on `threads`
// threads.
vision::FramePipeline described_frames(const std::vector<std::string>& inputs,
                                       const vision::ImageSourceOptions& options,
                                       std::shared_ptr<const vision::FeatureExtractor> extractor,
                                       unsigned threads) {
  vision::ImageSource source(inputs, vision::limit_for_extractor(options, *extractor));
  return vision::FramePipeline(std::move(source), std::move(extractor), {threads, 0});
}

// Adds every frame of the inputs, labelled with its name. A frame skipped as
// unreadable is added without features (it matches nothing), so that entries
// keep the frames' order and numbering, as in detect-loops.
AddedImages add_images(Database& database,
                       const std::shared_ptr<const vision::FeatureExtractor>& extractor,
                       const std::vector<std::string>& inputs,
                       const vision::ImageSourceOptions& options, unsigned threads,
                       std::size_t* features) {
  vision::FramePipeline frames = described_frames(inputs, options, extractor, threads);
  const long long known = frames.size();
  Progress progress("adding images", known > 0 ? static_cast<std::size_t>(known) : 0);
  AddedImages added;
  vision::ExtractedFrame extracted;
  while (frames.next(extracted)) {
    const vision::Frame& frame = extracted.frame;
    if (warn_if_unreadable(frame.name, frame.unreadable)) ++added.skipped;
    if (features != nullptr) *features += extracted.features.descriptors.rows();
    const EntryId entry = database.add(extracted.features.descriptors.view(), frame.name);
    added.entries.emplace_back(entry, frame.name);
    progress.update(added.entries.size());
  }
  progress.finish();
  if (options.skip_unreadable) note("skipped frames: %zu\n", added.skipped);
  return added;
}

void run_db_build(DbBuildArguments arguments) {
  check_vocabulary_given(arguments.vocabulary, arguments.descriptor);
  refuse_binary_on_terminal("-o", arguments.output, "a database");
  prepare_output_file("-o", arguments.output);
  const std::string output = output_file(arguments.output);
  Vocabulary vocabulary;
  const std::string vocabulary_path =
      load_loop_vocabulary(arguments.vocabulary, arguments.descriptor, vocabulary);
  const std::shared_ptr<const vision::FeatureExtractor> extractor =
      vision::make_extractor(arguments.descriptor, arguments.features);
  Database database(vocabulary, {!arguments.no_direct_index, arguments.levels_up});
  std::size_t features = 0;
  add_images(database, extractor, arguments.inputs, arguments.source, arguments.threads, &features);
  if (database.size() == 0) throw InvalidArgument("db build: no images found in the inputs");
  std::optional<DatabaseLock> writer;
  if (!detail::is_written_in_place(output))
    writer.emplace(lock_database(output, arguments.wait_seconds));
  database.save(output, !arguments.external_vocabulary);
  print_summary(is_standard_output(arguments.output),
                "%s: %zu entries, %zu features, vocabulary %s (%s)\n", arguments.output.c_str(),
                database.size(), features, vocabulary.description().c_str(),
                vocabulary_path.c_str());
}

void run_db_query(const DbQueryArguments& arguments) {
  const Database database =
      load_database(arguments.database, arguments.vocabulary, arguments.descriptor);
  const auto extractor = database_extractor(database, arguments);
  vision::FramePipeline frames =
      described_frames(arguments.inputs, arguments.source, extractor, arguments.threads);
  vision::ExtractedFrame extracted;
  BowVector bow;
  std::size_t skipped = 0;
  using Json = nlohmann::ordered_json;
  Json queries_json = Json::array();
  for (std::size_t queries = 0; frames.next(extracted);) {
    const vision::Frame& frame = extracted.frame;
    if (warn_if_unreadable(frame.name, frame.unreadable)) {
      ++skipped;
      continue;
    }
    database.vocabulary().transform(extracted.features.descriptors.view(), bow);
    const auto results = database.query(bow, arguments.top, kAllEntries, arguments.query);
    if (arguments.json) {
      Json ranked = Json::array();
      for (std::size_t rank = 0; rank < results.size(); ++rank)
        ranked.push_back({{"rank", rank + 1},
                          {"entry", results[rank].entry},
                          {"file", database.label(results[rank].entry)},
                          {"score", results[rank].score}});
      queries_json.push_back({{"query", frame.name}, {"results", ranked}});
      continue;
    }
    std::printf("%squery: %s\nrank\tentry\tfile\tscore\n", queries == 0 ? "" : "\n",
                frame.name.c_str());
    for (std::size_t rank = 0; rank < results.size(); ++rank) {
      const QueryResult& result = results[rank];
      std::printf("%zu\t%u\t%s\t%.6f\n", rank + 1, result.entry,
                  database.label(result.entry).c_str(), result.score);
    }
    std::fflush(stdout);
    ++queries;
  }
  if (arguments.source.skip_unreadable) note("skipped frames: %zu\n", skipped);
  if (arguments.json) {
    const Json summary = {{"binbow_version", BINBOW_VERSION},
                          {"database", arguments.database},
                          {"top", arguments.top},
                          {"skipped_frames", skipped},
                          {"queries", queries_json}};
    // Invalid UTF-8 in a file name is replaced rather than refused.
    std::printf("%s\n", summary.dump(2, ' ', false, Json::error_handler_t::replace).c_str());
    std::fflush(stdout);
  }
}

void run_db_add(const DbArguments& arguments) {
  const DatabaseLock writer = lock_database(arguments.database, arguments.wait_seconds);
  // load() checks the whole file: the header is enough here.
  const bool vocabulary_included = Database::inspect(arguments.database, false).vocabulary_included;
  Database database = load_database(arguments.database, arguments.vocabulary, arguments.descriptor);
  const auto extractor = database_extractor(database, arguments);
  const AddedImages added = add_images(database, extractor, arguments.inputs, arguments.source,
                                       arguments.threads, nullptr);
  save_changes(database, arguments.database, vocabulary_included, arguments.compact);
  for (const auto& [entry, label] : added.entries)
    std::printf("added %u\t%s\n", entry, label.c_str());
  std::printf("%s: %zu entries added, %zu entries\n", arguments.database.c_str(),
              added.entries.size(), database.size());
}

// The options db query and db add share.
void add_database_options(CLI::App* command, DbArguments& arguments,
                          const std::string& images_help) {
  command->add_option("DB", arguments.database, "Database (.bbdb)")->required();
  command->add_option("IMAGES", arguments.inputs, images_help)->required();
  add_vocabulary_extractor_options(command, arguments.descriptor, arguments.features);
  command->add_option("--vocab", arguments.vocabulary,
                      "Vocabulary, for databases built with --external-vocab");
  add_image_source_options(command, arguments.source);
  add_skip_unreadable_option(command, arguments.source);
  add_threads_option(command, arguments.threads);
}

}  // namespace

void add_db_image_commands(CLI::App& db) {
  auto build = std::make_shared<DbBuildArguments>();
  CLI::App* build_command =
      db.add_subcommand("build", "Add images to a new database and save it (.bbdb)");
  build_command->add_option("--vocab", build->vocabulary,
                            "Vocabulary (any format binbow reads); default: the bundled "
                            "data/vocab/<descriptor>_default.bbw");
  build_command
      ->add_option("-o,--output", build->output,
                   std::string("Output database (.bbdb)") + kOutputFileHelp +
                       " (the summary then goes to stderr)")
      ->required();
  add_vocabulary_extractor_options(build_command, build->descriptor, build->features);
  build_command
      ->add_option("--direct-index-levels-up", build->levels_up,
                   "Direct index nodes this many levels above the words (the root when more "
                   "than the vocabulary's depth)")
      ->check(CLI::Range(0u, kMaxDirectIndexLevelsUp))
      ->capture_default_str();
  build_command->add_flag("--no-direct-index", build->no_direct_index,
                          "Do not keep the direct index (smaller file)");
  build_command->add_flag("--external-vocab", build->external_vocabulary,
                          "Store only the vocabulary's checksum, not the vocabulary");
  build_command
      ->add_option("inputs", build->inputs,
                   "Image files, directories, videos or text lists of images; entries are "
                   "labelled with the frame names")
      ->required();
  add_image_source_options(build_command, build->source);
  add_skip_unreadable_option(build_command, build->source);
  add_threads_option(build_command, build->threads);
  add_wait_option(build_command, build->wait_seconds);
  build_command->callback([build] { run_db_build(*build); });

  auto query = std::make_shared<DbQueryArguments>();
  CLI::App* query_command = db.add_subcommand(
      "query", "The database entries most similar to each image: one table per query image");
  add_database_options(query_command, *query,
                       "Query images: files, directories, videos or text lists of images");
  query_command->add_option("--top", query->top, "Number of results per query")
      ->check(CLI::Range(1, 1000000))
      ->capture_default_str();
  add_fast_query_options(query_command, query->query);
  query_command->add_flag("--json", query->json,
                          "Print every query's results as one JSON object on stdout, after the "
                          "last query");
  query_command->callback([query] { run_db_query(*query); });

  auto add = std::make_shared<DbArguments>();
  CLI::App* add_command = db.add_subcommand(
      "add",
      "Add images to an existing database; the new entries are appended to its journal "
      "(<DB>.journal), atomically");
  add_database_options(add_command, *add,
                       "Image files, directories, videos or text lists of images; entries are "
                       "labelled with the frame names");
  add_command->add_flag("--compact", add->compact, kCompactHelp);
  add_wait_option(add_command, add->wait_seconds);
  add_command->callback([add] { run_db_add(*add); });
}

}  // namespace binbow::cli
