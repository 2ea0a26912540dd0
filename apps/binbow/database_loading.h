// How db commands open a database, in the executable (db remove) and in the
// module (db query, db add) alike.
#pragma once

#include <string>

#include "binbow/database.h"
#include "binbow/formats.h"

namespace binbow::cli {

// The database, with the --vocab given for one built with --external-vocab.
inline Database load_database(const std::string& path, const std::string& vocabulary) {
  return vocabulary.empty() ? Database::load(path)
                            : Database::load(path, load_vocabulary(vocabulary));
}

}  // namespace binbow::cli
