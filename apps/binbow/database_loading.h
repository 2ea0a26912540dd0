// How db commands open a database, in the executable (db remove) and in the
// module (db query, db add) alike.
#pragma once

#include <string>

#include "binbow/database.h"
#include "binbow/formats.h"

namespace binbow::cli {

// The database, with the --vocab given for one built with --external-vocab.
// Checked whole before use: a command is over before a background check
// would end, and must not print results from a damaged file.
inline Database load_database(const std::string& path, const std::string& vocabulary) {
  const DatabaseLoadOptions options{Verification::kBeforeReturn};
  return vocabulary.empty() ? Database::load(path, options)
                            : Database::load(path, load_vocabulary(vocabulary), options);
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

constexpr const char* kCompactHelp =
    "Write the whole database file, folding its journal into it, instead of appending the "
    "changes to the journal (<DB>.journal)";

}  // namespace binbow::cli
