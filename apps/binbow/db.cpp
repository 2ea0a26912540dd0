// `binbow db` and `db remove`: an image database on disk (.bbdb), and the
// `binbow info` lines for such a file. `db build`, `query` and `add`, which
// read images, are in db_images.cpp.
#include <cstdio>
#include <cstring>
#include <fstream>
#include <memory>
#include <string>
#include <utility>
#include <vector>

#include "binbow/database.h"
#include "binbow/error.h"
#include "commands.h"
#include "core/regular_file.h"
#include "database_loading.h"
#include "info_fields.h"
#include "invocation.h"
#include "trained_on_option.h"

namespace binbow::cli {
namespace {

struct DbRemoveArguments {
  std::string database;
  std::vector<EntryId> entries;
  std::string vocabulary;
  std::string descriptor;  // the extractor of --vocab when its file does not record it
  bool compact = false;
  double wait_seconds = 0;
};

void run_db_remove(const DbRemoveArguments& arguments) {
  const DatabaseLock writer = lock_database(arguments.database, arguments.wait_seconds);
  const bool vocabulary_included = Database::inspect(arguments.database, false).vocabulary_included;
  if (!arguments.descriptor.empty()) check_known_descriptor(arguments.descriptor);
  Database database = load_database(arguments.database, arguments.vocabulary, arguments.descriptor);
  std::vector<std::pair<EntryId, std::string>> removed;
  for (const EntryId entry : arguments.entries) {
    if (!database.contains(entry)) {
      throw InvalidArgument(arguments.database + ": no entry " + std::to_string(entry) +
                            " (never added, or removed); nothing was removed");
    }
    removed.emplace_back(entry, database.label(entry));
    database.remove(entry);
  }
  save_changes(database, arguments.database, vocabulary_included, arguments.compact);
  for (const auto& [entry, label] : removed) std::printf("removed %u\t%s\n", entry, label.c_str());
  std::printf("%s: %zu entries removed, %zu entries\n", arguments.database.c_str(), removed.size(),
              database.size());
}

}  // namespace

bool describe_database(const std::string& path, bool verify, const std::string& vocabulary,
                       const std::string& descriptor, InfoFields& fields) {
  detail::require_regular_file(path);  // a FIFO would block the read below
  char magic[8] = {};
  std::ifstream file(path, std::ios::binary);
  if (!file.read(magic, sizeof magic) || std::memcmp(magic, "BINBOWDB", 8) != 0) return false;
  const DatabaseFileInfo info = Database::inspect(path, false);
  const DatabaseJournalInfo journal = Database::inspect_journal(path);
  std::size_t entries = journal.entries;
  EntryId next_entry_id = journal.next_entry_id;
  // Checked as db query loads it, so that info never describes a database
  // that does not load. Without its vocabulary (--external-vocab) the words
  // cannot be checked: the file's sections and the journal's records are.
  if (verify &&
      (info.vocabulary_included || info.vocabulary_checksum == 0 || !vocabulary.empty())) {
    const Database database = load_database(path, vocabulary, descriptor);
    entries = database.size();
    next_entry_id = database.next_entry_id();
  } else if (verify) {
    Database::inspect(path, true);
    note(
        "%s: its vocabulary is external: the entries' words are checked with "
        "--vocab VOCABULARY\n",
        path.c_str());
  }
  fields.add("kind", "database");
  fields.add("entries", entries);
  fields.add("next_entry_id", next_entry_id);
  if (info.direct_index)
    fields.add("direct_index", std::to_string(info.direct_index_levels_up) + " levels up");
  else
    fields.add("direct_index", "none");
  fields.add("vocabulary", info.vocabulary_description);
  fields.add("vocabulary_checksum", hex_checksum(info.vocabulary_checksum));
  fields.add("vocabulary_included", info.vocabulary_included ? "yes" : "no");
  if (!journal.present) {
    fields.add("journal", "none");
  } else if (journal.superseded) {
    fields.add("journal",
               std::to_string(journal.bytes) + " bytes, superseded by the database file (ignored)");
  } else {
    fields.add("journal", std::to_string(journal.bytes) + " bytes, " +
                              std::to_string(journal.saves) +
                              " saves: " + std::to_string(journal.added) + " entries added, " +
                              std::to_string(journal.removed) + " removed, " +
                              std::to_string(journal.labels_set) + " labels set" +
                              (journal.cleared > 0 ? ", cleared" : ""));
    if (journal.torn_bytes > 0)
      fields.add("journal_torn_bytes",
                 std::to_string(journal.torn_bytes) + " (an interrupted save, dropped)");
  }
  return true;
}

void add_db_command(CLI::App& app, void (*add_image_commands)(CLI::App& db)) {
  CLI::App* db = app.add_subcommand("db", "Build, query and edit image databases (.bbdb)");
  db->require_subcommand(1);
  if (add_image_commands != nullptr) add_image_commands(*db);

  auto remove = std::make_shared<DbRemoveArguments>();
  CLI::App* remove_command = db->add_subcommand(
      "remove",
      "Remove entries from a database by id; the removals are appended to its journal "
      "(<DB>.journal), atomically (ids are not reused)");
  remove_command->add_option("DB", remove->database, "Database (.bbdb)")->required();
  remove_command
      ->add_option("ENTRY", remove->entries, "Entry ids, as db query and db add print them")
      ->required();
  remove_command->add_option("--vocab", remove->vocabulary,
                             "Vocabulary, for databases built with --external-vocab");
  add_trained_on_option(remove_command, remove->descriptor, "");
  remove_command->add_flag("--compact", remove->compact, kCompactHelp);
  add_wait_option(remove_command, remove->wait_seconds);
  remove_command->callback([remove] { run_db_remove(*remove); });
}

}  // namespace binbow::cli
