#include "core/module_entry.h"

#include <dlfcn.h>

namespace binbow::detail {

void* module_entry(const std::string& path, const char* symbol, std::string& reason) {
  void* handle = dlopen(path.c_str(), RTLD_NOW | RTLD_LOCAL);
  if (handle == nullptr) {
    const char* error = dlerror();
    reason = error != nullptr ? error : "dlopen failed";
    if (reason.rfind(path + ": ", 0) == 0) reason.erase(0, path.size() + 2);
    return nullptr;
  }
  void* entry = dlsym(handle, symbol);
  if (entry == nullptr) reason = std::string("no ") + symbol + " entry point";
  return entry;
}

}  // namespace binbow::detail
