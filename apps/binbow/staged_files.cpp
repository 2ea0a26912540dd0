#include "staged_files.h"

#include <sys/stat.h>
#include <unistd.h>
#include <cerrno>
#include <cstdio>
#include <cstring>

#include "binbow/error.h"

namespace binbow::cli {
namespace {

std::string errno_text() {
  return std::strerror(errno);
}

// Reserves a fresh name beside `path` (mkstemp) and returns it; the file exists, empty.
std::string fresh_name_beside(const std::string& path, const char* suffix) {
  std::string name = path + suffix;
  const int fd = ::mkstemp(name.data());
  if (fd < 0) throw FileError(path, "cannot create a temporary file beside it: " + errno_text());
  // mkstemp creates 0600; give the file the permissions the user's umask asks for.
  const mode_t mask = ::umask(0);
  ::umask(mask);
  ::fchmod(fd, 0666 & ~mask);
  ::close(fd);
  return name;
}

// The previous version of a target while the set is renamed, to put back if
// a later rename fails.
struct Backup {
  std::string path;  // empty: the target did not exist
  bool linked = false;
};

Backup keep_previous(const std::string& target) {
  Backup backup;
  struct stat info {};
  if (::lstat(target.c_str(), &info) != 0) return backup;
  if (S_ISDIR(info.st_mode)) throw FileError(target, "cannot replace it: it is a directory");
  backup.path = fresh_name_beside(target, ".old-XXXXXX");
  ::unlink(backup.path.c_str());
  // A second link keeps the target in place until the rename replaces it;
  // where links are not supported the target moves aside for that moment.
  if (::link(target.c_str(), backup.path.c_str()) == 0) {
    backup.linked = true;
  } else if (std::rename(target.c_str(), backup.path.c_str()) != 0) {
    throw FileError(target, "cannot keep the previous version while replacing it: " + errno_text());
  }
  return backup;
}

void restore(const std::string& target, const Backup& backup) {
  if (backup.path.empty())
    ::unlink(target.c_str());
  else
    std::rename(backup.path.c_str(), target.c_str());
}

}  // namespace

StagedFiles::~StagedFiles() {
  for (const Staged& s : staged_) ::unlink(s.temporary.c_str());
}

std::string StagedFiles::stage(const std::string& target) {
  staged_.push_back({target, fresh_name_beside(target, ".tmp-XXXXXX")});
  return staged_.back().temporary;
}

void StagedFiles::commit() {
  std::vector<Backup> backups;
  const auto undo = [&] {
    for (std::size_t i = backups.size(); i-- > 0;) restore(staged_[i].target, backups[i]);
  };
  for (std::size_t i = 0; i < staged_.size(); ++i) {
    const Staged& s = staged_[i];
    try {
      backups.push_back(keep_previous(s.target));
    } catch (...) {
      undo();
      throw;
    }
    if (std::rename(s.temporary.c_str(), s.target.c_str()) != 0) {
      const std::string why = errno_text();
      // This target was not replaced: its second link goes, or, moved aside, it comes back.
      const Backup& unused = backups.back();
      if (unused.linked)
        ::unlink(unused.path.c_str());
      else if (!unused.path.empty())
        std::rename(unused.path.c_str(), s.target.c_str());
      backups.pop_back();
      undo();
      throw FileError(s.target, "cannot replace the file: " + why);
    }
  }
  for (const Backup& backup : backups)
    if (!backup.path.empty()) ::unlink(backup.path.c_str());
  staged_.clear();
}

}  // namespace binbow::cli
