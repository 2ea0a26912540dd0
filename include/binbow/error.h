// Exceptions thrown by binbow. Every error derives from binbow::Error, so one
// catch clause is enough; the subclasses let callers react to the cause.
#pragma once

#include <functional>
#include <stdexcept>
#include <string>

namespace binbow {

// Base of every exception binbow throws.
class Error : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

// A caller passed an argument that cannot be used (wrong descriptor length,
// unknown entry id, zero branching factor, ...). The message names the argument.
class InvalidArgument : public Error {
 public:
  using Error::Error;
};

// A file could not be opened, read or written, or its content is not valid for
// the format it claims (truncated, corrupted, unsupported version, ...).
// what() is "<path>: <problem>"; both parts are also available separately.
class FileError : public Error {
 public:
  FileError(std::string path, std::string problem)
      : Error(path + ": " + problem), path_(std::move(path)), problem_(std::move(problem)) {}

  const std::string& path() const noexcept { return path_; }
  const std::string& problem() const noexcept { return problem_; }

 private:
  std::string path_;
  std::string problem_;
};

// A save that would overwrite another writer's work was refused, and
// nothing was written: another process (or thread) holds the database's
// DatabaseLock, or saved the file since this database was loaded from it
// or saved to it. Load the database again and redo the change (or wait for
// the other writer: DatabaseLock's wait).
class WriteConflict : public FileError {
 public:
  using FileError::FileError;
};

// Problems that do not make an operation fail: a save that is committed
// (it will load) but whose directory could not be flushed to disk, say.
// By default each is written to stderr as "binbow: warning: <message>";
// a handler set here receives them instead (an empty one restores the
// default). Called on the thread that met the problem; thread-safe.
using WarningHandler = std::function<void(const std::string& message)>;
void set_warning_handler(WarningHandler handler);

}  // namespace binbow
