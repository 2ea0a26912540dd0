// Output paths made ready before a command starts its work (missing folders
// created, writability checked: core/output_path.h). A path that cannot be
// written is a usage error that names the option, e.g.
// "-o r1/loops.csv: cannot create the folder r1: ...".
//
// An output file given as "-" is standard output, written in place through
// descriptor 1 as /dev/stdout is (no temporary file, nothing beside it);
// the command's summary then goes to stderr (invocation.h). An output
// folder cannot be "-".
#pragma once

#include <unistd.h>

#include <exception>
#include <filesystem>
#include <string>
#include <system_error>
#include <vector>

#include <CLI/CLI.hpp>

#include "binbow/error.h"
#include "core/output_path.h"

namespace binbow::cli {

// What the help of an output file option adds.
inline constexpr const char* kOutputFileHelp =
    "; missing folders are created; - writes to standard output";
inline constexpr const char* kOutputFolderHelp = "; created with its missing parents";
// An output file that cannot be "-" (written beside other results).
inline constexpr const char* kOutputFolderParentsHelp = "; missing folders are created";

inline bool is_standard_output(const std::string& path) {
  return path == "-";
}

// The path to write for an output file as given: /dev/stdout for "-".
inline std::string output_file(const std::string& path) {
  return is_standard_output(path) ? "/dev/stdout" : path;
}

// For the outputs that stdout cannot carry beside a command's results.
inline void refuse_standard_output(const std::string& option, const std::string& path) {
  if (is_standard_output(path))
    throw CLI::ValidationError(option + " -: only one output can go to standard output; give " +
                               option + " a file name");
}

// A binary file given as "-" while standard output is a terminal: refused,
// as gzip does, rather than filling the terminal with bytes.
inline void refuse_binary_on_terminal(const std::string& option, const std::string& path,
                                      const std::string& what) {
  if (is_standard_output(path) && ::isatty(STDOUT_FILENO) == 1)
    throw CLI::ValidationError(option + " -: " + what +
                               " is binary and standard output is a terminal; redirect it "
                               "(> FILE, | gzip) or give a file name");
}

inline void prepare_output_file(const std::string& option, const std::string& path) {
  try {
    detail::prepare_output_file(output_file(path));
  } catch (const Error& e) {
    throw CLI::ValidationError(option + " " + e.what());
  }
}

inline void prepare_output_directory(const std::string& option, const std::string& path) {
  if (is_standard_output(path))
    throw CLI::ValidationError(option +
                               " -: this output is a folder of files, which cannot go to "
                               "standard output; give a folder name");
  try {
    detail::prepare_output_directory(path);
  } catch (const Error& e) {
    throw CLI::ValidationError(option + " " + e.what());
  }
}

// Output paths prepared as above, whose missing folders are removed again
// if the command fails or is interrupted before writing into them: a command
// that stops leaves no empty folder (a --report folder, -o's parents) behind.
// A folder that received a file stays.
class CreatedFolders {
 public:
  CreatedFolders() : exceptions_(std::uncaught_exceptions()) {}
  CreatedFolders(const CreatedFolders&) = delete;
  CreatedFolders& operator=(const CreatedFolders&) = delete;
  ~CreatedFolders() {
    if (std::uncaught_exceptions() <= exceptions_) return;
    for (auto folder = folders_.rbegin(); folder != folders_.rend(); ++folder)
      ::rmdir(folder->c_str());  // fails, keeping it, unless it is empty
  }

  void prepare_file(const std::string& option, const std::string& path) {
    if (!is_standard_output(path)) note_missing(std::filesystem::path(path).parent_path());
    prepare_output_file(option, path);
  }
  void prepare_directory(const std::string& option, const std::string& path) {
    if (!is_standard_output(path)) note_missing(path);
    prepare_output_directory(option, path);
  }

 private:
  // `folder` and its missing parents, outermost first.
  void note_missing(const std::filesystem::path& folder) {
    std::vector<std::string> missing;
    std::error_code error;
    std::filesystem::path p = folder.lexically_normal();
    if (!p.has_filename()) p = p.parent_path();  // "report/"
    for (; p.has_relative_path(); p = p.parent_path()) {
      if (std::filesystem::symlink_status(p, error).type() != std::filesystem::file_type::not_found)
        break;
      missing.push_back(p.string());
    }
    folders_.insert(folders_.end(), missing.rbegin(), missing.rend());
  }

  int exceptions_;
  std::vector<std::string> folders_;
};

}  // namespace binbow::cli
