// Several output files that appear together or not at all: detect-loops must
// not leave a new loops.csv beside an old (or missing) run record when the
// disk fills up while the second one is written.
//
// Each file is first written to a temporary beside its target; commit()
// renames them over their targets only once all are complete, and if a
// rename fails it puts back what the earlier renames replaced. A general
// multi-file commit may later live in src/core/file_io; this is the CLI's
// own, with the same shape (stage, write, commit).
#pragma once

#include <string>
#include <vector>

namespace binbow::cli {

class StagedFiles {
 public:
  StagedFiles() = default;
  StagedFiles(const StagedFiles&) = delete;
  StagedFiles& operator=(const StagedFiles&) = delete;
  // Removes the temporaries of an uncommitted set: the targets stay as they were.
  ~StagedFiles();

  // Creates an empty temporary file in `target`'s directory, with the
  // permissions the umask gives new files, and returns its path for the
  // caller to write. Throws FileError naming `target`.
  std::string stage(const std::string& target);
  // Renames every temporary over its target, in the order staged. On failure
  // the targets keep their previous content (or stay absent) and FileError
  // names the target that could not be replaced.
  void commit();

 private:
  struct Staged {
    std::string target;
    std::string temporary;
  };
  std::vector<Staged> staged_;
};

}  // namespace binbow::cli
