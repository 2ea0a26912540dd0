#include "vision_commands.h"

#include <unistd.h>

#include <algorithm>
#include <cstddef>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <string>
#include <system_error>
#include <vector>

#include "binbow/error.h"
#include "core/module_entry.h"
#include "interruption.h"
#include "invocation.h"

namespace binbow::cli {
namespace fs = std::filesystem;

namespace {

constexpr const char* kModuleFile = "binbow_cli_vision.so";

std::string load_error(const std::string& path, const std::string& reason) {
  return "cannot load binbow's image and video commands, " + path + ": " + reason +
         "; reinstall binbow or set BINBOW_CLI_VISION_MODULE to the path of " + kModuleFile;
}

static_assert(offsetof(VisionCommands, version) == offsetof(detail::ModuleTableHeader, version) &&
                  offsetof(VisionCommands, binbow_version) ==
                      offsetof(detail::ModuleTableHeader, binbow_version),
              "VisionCommands begins as every module table does");

const VisionCommands& load(const std::string& given) {
  const std::string path = detail::module_file(given);
  std::string reason;
  using Entry = const VisionCommands* (*)();
  const auto entry =
      reinterpret_cast<Entry>(detail::module_entry(path, kBinbowCliVisionSymbol, reason));
  if (entry == nullptr) throw Error(load_error(path, reason));
  const VisionCommands* commands = entry();
  reason =
      detail::check_module_table(reinterpret_cast<const void*>(entry), commands,
                                 sizeof(VisionCommands), kVisionCommandsVersion, BINBOW_VERSION);
  if (!reason.empty()) throw Error(load_error(path, reason));
  commands->watch_interruption_flag(&interruption_flag());
  commands->watch_invocation(&own_invocation());
  return *commands;
}

// From the executable's directory: an installed prefix's <libdir>/binbow (the
// build tree has the same layout), then the Python package's lib/binbow;
// then the install prefix's own.
std::vector<std::string> candidates() {
  std::vector<std::string> paths;
  std::error_code error;
  const fs::path exe = fs::read_symlink("/proc/self/exe", error);
  if (!error)
    for (const char* relative : {BINBOW_CLI_VISION_FROM_BINDIR, "../lib/binbow"})
      paths.push_back((exe.parent_path() / relative / kModuleFile).lexically_normal().string());
  paths.push_back((fs::path(BINBOW_CLI_VISION_INSTALL_DIR) / kModuleFile).string());
  std::vector<std::string> unique;
  for (const std::string& path : paths)
    if (std::find(unique.begin(), unique.end(), path) == unique.end()) unique.push_back(path);
  return unique;
}

const VisionCommands& find_and_load() {
  if (const char* chosen = std::getenv("BINBOW_CLI_VISION_MODULE"); chosen != nullptr && *chosen)
    return load(chosen);
  const std::vector<std::string> paths = candidates();
  for (const std::string& path : paths)
    if (::access(path.c_str(), F_OK) == 0) return load(path);
#if defined(BINBOW_CLI_WITHOUT_VISION)
  throw Error(
      "this binbow was built without its image and video commands (BINBOW_BUILD_VISION=OFF): "
      "build it with OpenCV (Debian: libopencv-dev) and -DBINBOW_BUILD_VISION=ON, or set "
      "BINBOW_CLI_VISION_MODULE to the path of a binbow_cli_vision.so of this version");
#endif
  std::string elsewhere;
  for (std::size_t i = 1; i < paths.size(); ++i) elsewhere += (i > 1 ? ", " : "") + paths[i];
  throw Error(load_error(
      paths.front(), "no such file" + (elsewhere.empty() ? "" : " (nor at " + elsewhere + ")")));
}

bool is_lean_command(const std::string& first, const std::string& second) {
  return first == "info" || first == "convert" || first == "evaluate" ||
         (first == "db" && second == "remove");
}

}  // namespace

bool needs_vision_commands(int argc, const char* const* argv) {
  if (argc == 2 && std::strcmp(argv[1], "--version") == 0) return false;
#if defined(BINBOW_CLI_WITHOUT_VISION)
  // Help and unknown commands list the commands this build has.
  if (const char* chosen = std::getenv("BINBOW_CLI_VISION_MODULE"); chosen == nullptr || !*chosen)
    return false;
#endif
  return !(argc >= 2 && is_lean_command(argv[1], argc >= 3 ? argv[2] : ""));
}

const VisionCommands& vision_commands() {
  static const VisionCommands* commands = &find_and_load();
  return *commands;
}

}  // namespace binbow::cli
