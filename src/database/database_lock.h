// The writer lock of a database file (binbow::DatabaseLock), and the one
// path by which a database's files are named whatever link leads to them.
#pragma once

#include <optional>
#include <string>

#include "binbow/database.h"

namespace binbow::detail {

// `path` with every symbolic link on the way to its file followed (the last
// may dangle: the file is then created where it points), absolute, its
// folders canonical: a link and its target name one database, with one
// journal and one lock.
std::string resolve_database_path(const std::string& path);

// Takes the lock of the database whose resolved path is `key` for this
// thread (nested holds are counted), waiting up to `wait_seconds`; throws
// WriteConflict naming `name` when another process or thread still holds
// it, FileError when its lock file cannot be opened.
void acquire_database_lock(const std::string& key, const std::string& name, double wait_seconds);
void release_database_lock(const std::string& key) noexcept;

// Where a save of `given` writes, and the database's writer lock held while
// the save lives: a file's path with links followed (its folders made, since
// the lock file needs them), or an output written in place (/dev/stdout, a
// FIFO) as given, without a lock.
struct SaveTarget {
  explicit SaveTarget(const std::string& given);
  std::string path;
  std::optional<DatabaseLock> writer;
};

}  // namespace binbow::detail
