#include "core/output_path.h"

#include <sys/stat.h>
#include <unistd.h>
#include <algorithm>
#include <cctype>
#include <cerrno>
#include <cstring>
#include <filesystem>
#include <system_error>

#include "binbow/error.h"
#include "core/file_io.h"

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

constexpr int kMaxSymlinkHops = 40;  // as the kernel's ELOOP limit

bool is_number(const std::string& text) {
  return !text.empty() && std::all_of(text.begin(), text.end(), [](char c) {
    return std::isdigit(static_cast<unsigned char>(c)) != 0;
  });
}

}  // namespace

int own_descriptor(const std::string& path) {
  std::error_code error;
  const fs::path descriptors = fs::canonical("/proc/self/fd", error);
  if (error) return -1;
  fs::path current(path);
  for (int hop = 0; hop < kMaxSymlinkHops; ++hop) {
    const fs::path folder =
        fs::canonical(current.has_parent_path() ? current.parent_path() : ".", error);
    if (!error && folder == descriptors && is_number(current.filename().string()))
      return std::stoi(current.filename().string());
    if (!fs::is_symlink(current, error)) return -1;
    const fs::path target = fs::read_symlink(current, error);
    if (error) return -1;
    current = target.is_absolute() ? target : current.parent_path() / target;
  }
  return -1;
}

bool is_written_in_place(const std::string& path) {
  if (own_descriptor(path) >= 0) return true;
  struct stat st {};
  if (::stat(path.c_str(), &st) != 0 || S_ISREG(st.st_mode) || S_ISDIR(st.st_mode)) return false;
  if (S_ISCHR(st.st_mode) || S_ISFIFO(st.st_mode)) return true;
  throw FileError(path, std::string("is ") + file_kind(st.st_mode) +
                            ", not a place for output; write to a regular file, a FIFO or a "
                            "character device such as /dev/null");
}

void prepare_output_file(const std::string& path) {
  if (path.empty()) throw InvalidArgument("an output file name is empty");
  if (is_written_in_place(path)) {
    if (::access(path.c_str(), W_OK) == 0) return;
    throw FileError(path, std::string("cannot write into it: ") + std::strerror(errno));
  }
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
