// Output paths made ready before a command starts its work (missing folders
// created, writability checked: core/output_path.h). A path that cannot be
// written is a usage error that names the option, e.g.
// "-o r1/loops.csv: cannot create the folder r1: ...".
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

inline void prepare_output_file(const std::string& option, const std::string& path) {
  try {
    detail::prepare_output_file(path);
  } catch (const Error& e) {
    throw CLI::ValidationError(option + " " + e.what());
  }
}

inline void prepare_output_directory(const std::string& option, const std::string& path) {
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
    note_missing(std::filesystem::path(path).parent_path());
    prepare_output_file(option, path);
  }
  void prepare_directory(const std::string& option, const std::string& path) {
    note_missing(path);
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
