#include "default_vocabulary.h"

#include <cstdlib>
#include <filesystem>
#include <system_error>

#include "binbow/error.h"

namespace binbow::cli {
namespace fs = std::filesystem;

std::string default_vocabulary_name(const std::string& descriptor) {
  if (descriptor == "orb" || descriptor == "brief") return descriptor + "_default.bbw";
  throw InvalidArgument("no default vocabulary for descriptor \"" + descriptor + "\"");
}

std::vector<std::string> default_vocabulary_candidates(const std::string& descriptor) {
  const std::string name = default_vocabulary_name(descriptor);
  std::vector<std::string> candidates;
  if (const char* data_dir = std::getenv("BINBOW_DATA_DIR"); data_dir != nullptr && *data_dir)
    candidates.push_back((fs::path(data_dir) / "vocab" / name).string());
  std::error_code error;
  const fs::path exe = fs::read_symlink("/proc/self/exe", error);
  if (!error) {
    const fs::path dir = exe.parent_path();
    candidates.push_back(
        (dir / ".." / "share" / "binbow" / "vocab" / name).lexically_normal().string());
    candidates.push_back((dir / ".." / ".." / "data" / "vocab" / name).lexically_normal().string());
  }
  return candidates;
}

std::string default_vocabulary_path(const std::string& descriptor) {
  const std::vector<std::string> candidates = default_vocabulary_candidates(descriptor);
  std::string searched;
  for (const std::string& path : candidates) {
    std::error_code error;
    if (fs::is_regular_file(path, error)) return path;
    searched += "\n  " + path;
  }
  throw InvalidArgument("the default " + descriptor + " vocabulary (" +
                        default_vocabulary_name(descriptor) +
                        ") is not installed; pass one with --vocab FILE. Searched:" + searched);
}

}  // namespace binbow::cli
