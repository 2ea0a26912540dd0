#include "vision/media_module.h"

#include <link.h>
#include <unistd.h>

#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <filesystem>
#include <mutex>
#include <string>
#include <system_error>
#include <vector>

#include "binbow/error.h"
#include "core/module_entry.h"

namespace binbow::vision {
namespace fs = std::filesystem;

namespace {

constexpr const char* kModuleFile = "binbow_media.so";

struct Search {
  std::uintptr_t address = 0;
  bool found = false;
  std::string path;  // empty for the main program
};

// The file of the loaded object (executable or shared library) holding
// `address`. dladdr would name the main program only as argv[0], which may be
// relative or a bare name found through PATH.
std::string object_holding(const void* address) {
  Search search{reinterpret_cast<std::uintptr_t>(address), false, {}};
  dl_iterate_phdr(
      [](dl_phdr_info* info, std::size_t, void* data) -> int {
        auto* s = static_cast<Search*>(data);
        for (int i = 0; i < info->dlpi_phnum; ++i) {
          const ElfW(Phdr)& segment = info->dlpi_phdr[i];
          const std::uintptr_t start = info->dlpi_addr + segment.p_vaddr;
          if (segment.p_type == PT_LOAD && s->address >= start &&
              s->address < start + segment.p_memsz) {
            s->found = true;
            s->path = info->dlpi_name != nullptr ? info->dlpi_name : "";
            return 1;
          }
        }
        return 0;
      },
      &search);
  std::error_code error;
  if (!search.found) return {};
  if (search.path.empty()) {
    const fs::path exe = fs::read_symlink("/proc/self/exe", error);
    return error ? std::string() : exe.string();
  }
  const fs::path canonical = fs::canonical(search.path, error);
  return error ? search.path : canonical.string();
}

std::string load_error(const std::string& path, const std::string& reason) {
  return "cannot load the image/video module " + path + ": " + reason;
}

static_assert(offsetof(media::Api, version) == offsetof(detail::ModuleTableHeader, version) &&
                  offsetof(media::Api, binbow_version) ==
                      offsetof(detail::ModuleTableHeader, binbow_version),
              "media::Api begins as every module table does");

const media::Api& load(const std::string& given) {
  const std::string path = detail::module_file(given);
  std::string reason;
  using Entry = const media::Api* (*)();
  const auto entry =
      reinterpret_cast<Entry>(detail::module_entry(path, kBinbowMediaApiSymbol, reason));
  if (entry == nullptr) throw Error(load_error(path, reason));
  const media::Api* api = entry();
  reason = detail::check_module_table(reinterpret_cast<const void*>(entry), api, sizeof(media::Api),
                                      media::kApiVersion, BINBOW_VERSION);
  if (!reason.empty()) throw Error(load_error(path, reason));
  return *api;
}

const media::Api& find_and_load() {
  if (const char* chosen = std::getenv("BINBOW_MEDIA_MODULE"); chosen != nullptr && *chosen)
    return load(chosen);
  const std::vector<std::string> candidates = media_module_candidates();
  for (const std::string& candidate : candidates)
    if (::access(candidate.c_str(), F_OK) == 0) return load(candidate);
  std::string elsewhere;
  for (std::size_t i = 1; i < candidates.size(); ++i)
    elsewhere += (i > 1 ? ", " : "") + candidates[i];
  throw Error(load_error(candidates.front(), "no such file (nor at " + elsewhere +
                                                 "; BINBOW_MEDIA_MODULE may name it)"));
}

}  // namespace

std::vector<std::string> media_module_candidates() {
  std::vector<std::string> candidates;
  const std::string holder = object_holding(reinterpret_cast<const void*>(&media_module));
  if (!holder.empty()) {
    const fs::path dir = fs::path(holder).parent_path();
    for (const char* relative : {BINBOW_MEDIA_FROM_LIBDIR, BINBOW_MEDIA_FROM_BINDIR,
                                 BINBOW_MEDIA_FROM_PACKAGE, BINBOW_MEDIA_FROM_MODULE}) {
      candidates.push_back((dir / relative / kModuleFile).lexically_normal().string());
    }
  }
  candidates.push_back((fs::path(BINBOW_MEDIA_INSTALL_DIR) / kModuleFile).string());
  std::vector<std::string> unique;
  for (const std::string& candidate : candidates)
    if (std::find(unique.begin(), unique.end(), candidate) == unique.end())
      unique.push_back(candidate);
  return unique;
}

const media::Api& media_module() {
  // A failed load is retried on the next call (and reported again).
  static std::mutex mutex;
  static const media::Api* api = nullptr;
  const std::lock_guard<std::mutex> lock(mutex);
  if (api == nullptr) api = &find_and_load();
  return *api;
}

}  // namespace binbow::vision
