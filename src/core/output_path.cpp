#include "core/output_path.h"

#include <unistd.h>
#include <cerrno>
#include <cstring>
#include <filesystem>
#include <system_error>

#include "binbow/error.h"

namespace binbow::detail {
namespace {

namespace fs = std::filesystem;

// The nearest existing ancestor of `folder` (itself included) that is not a
// directory: the file that blocks creating `folder`, or empty.
fs::path blocking_file(const fs::path& folder) {
  std::error_code error;
  for (fs::path p = folder; !p.empty(); p = p.parent_path()) {
    if (fs::exists(p, error)) return fs::is_directory(p, error) ? fs::path() : p;
    if (p == p.parent_path()) break;
  }
  return {};
}

// Creates `folder` with its parents; errors name `path`, the output asked for.
void create_folder(const fs::path& folder, const std::string& path) {
  std::error_code error;
  fs::create_directories(folder, error);
  if (!error) return;
  const fs::path file = blocking_file(folder);
  if (!file.empty()) {
    throw FileError(path, "cannot create the folder " + folder.string() + ": " + file.string() +
                              " is a file, not a folder; remove it or choose another path");
  }
  throw FileError(path, "cannot create the folder " + folder.string() + ": " + error.message() +
                            "; choose another path");
}

void check_writable(const fs::path& folder, const std::string& path) {
  if (::access(folder.c_str(), W_OK | X_OK) == 0) return;
  throw FileError(path, "cannot write into the folder " + folder.string() + ": " +
                            std::strerror(errno) +
                            "; choose another path or make the folder writable");
}

}  // namespace

void prepare_output_file(const std::string& path) {
  if (path.empty()) throw InvalidArgument("an output file name is empty");
  const fs::path file(path);
  std::error_code error;
  if (!file.has_filename() || fs::is_directory(file, error)) {
    throw FileError(path, "is a folder, not a file; give a file name, e.g. " +
                              (file / "output").lexically_normal().string());
  }
  const fs::path folder = file.has_parent_path() ? file.parent_path() : fs::path(".");
  create_folder(folder, path);
  check_writable(folder, path);
}

void prepare_output_directory(const std::string& path) {
  if (path.empty()) throw InvalidArgument("an output folder name is empty");
  std::error_code error;
  if (fs::exists(path, error) && !fs::is_directory(path, error)) {
    throw FileError(path, "exists and is not a folder; remove it or choose another folder");
  }
  create_folder(path, path);
  check_writable(path, path);
}

}  // namespace binbow::detail
