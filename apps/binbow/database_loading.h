// How db commands open a database, in the executable (db remove) and in the
// module (db query, db add) alike.
#pragma once

#include <cstdio>
#include <string>

#include <CLI/CLI.hpp>

#include "binbow/database.h"
#include "binbow/error.h"
#include "binbow/formats.h"

namespace binbow::cli {

// The database, with the --vocab given for one built with --external-vocab
// (trained on `descriptor`, --descriptor, when its file does not say; see
// load_vocabulary). Checked whole before use: a command is over before a
// background check would end, and must not print results from a damaged file.
inline Database load_database(const std::string& path, const std::string& vocabulary,
                              const std::string& descriptor) {
  const DatabaseLoadOptions options{Verification::kBeforeReturn};
  return vocabulary.empty()
             ? Database::load(path, options)
             : Database::load(
                   path, load_vocabulary(vocabulary, VocabularyFormat::kAuto, descriptor), options);
}

inline std::string wait_hint(double wait_seconds) {
  if (wait_seconds <= 0) return " (--wait SECONDS waits for it)";
  char text[64];
  std::snprintf(text, sizeof text, " (after waiting %g s: a longer --wait waits longer)",
                wait_seconds);
  return text;
}

// db add and db remove append their changes to the database's journal, or
// with --compact write the whole file (folding the journal into it).
inline void save_changes(const Database& database, const std::string& path,
                         bool vocabulary_included, bool compact) {
  if (compact)
    database.save(path, vocabulary_included);
  else
    database.save_incremental(path, vocabulary_included);
}

// The database's writer lock, held by a command from before it reads the
// database until after it saves it, so that no other writer comes between.
inline DatabaseLock lock_database(const std::string& path, double wait_seconds) {
  try {
    return DatabaseLock(path, wait_seconds);
  } catch (const WriteConflict& e) {
    throw WriteConflict(e.path(), e.problem() + wait_hint(wait_seconds));
  }
}

// --wait SECONDS of the commands that change a database.
inline void add_wait_option(CLI::App* command, double& wait_seconds) {
  command
      ->add_option("--wait", wait_seconds,
                   "Seconds to wait while another process changes the database (one writer at "
                   "a time); 0 fails at once, changing nothing")
      ->check(CLI::Range(0.0, 1e9))
      ->capture_default_str();
}

constexpr const char* kCompactHelp =
    "Write the whole database file, folding its journal into it, instead of appending the "
    "changes to the journal (<DB>.journal)";

}  // namespace binbow::cli
