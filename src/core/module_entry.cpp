#include "core/module_entry.h"

#include <dlfcn.h>
#include <link.h>

#include <cstdint>
#include <cstring>

namespace binbow::detail {

namespace {

// The loaded segment holding an address, in the object (executable or
// shared library) holding another one.
struct Segment {
  bool found = false;
  ElfW(Word) flags = 0;      // PF_R, PF_W, PF_X
  std::size_t readable = 0;  // bytes from the address to the segment's end
};

struct Search {
  std::uintptr_t anchor = 0;
  std::uintptr_t address = 0;
  Segment segment;
};

bool holds(const dl_phdr_info& info, const ElfW(Phdr) & header, std::uintptr_t address) {
  const std::uintptr_t start = info.dlpi_addr + header.p_vaddr;
  return header.p_type == PT_LOAD && address >= start && address - start < header.p_memsz;
}

// The segment holding `address` among those of the object holding `anchor`
// (not found when `address` is outside that object).
Segment segment_of(const void* anchor, const void* address) {
  Search search;
  search.anchor = reinterpret_cast<std::uintptr_t>(anchor);
  search.address = reinterpret_cast<std::uintptr_t>(address);
  dl_iterate_phdr(
      [](dl_phdr_info* info, std::size_t, void* data) -> int {
        auto* s = static_cast<Search*>(data);
        bool holds_anchor = false;
        for (int i = 0; i < info->dlpi_phnum && !holds_anchor; ++i)
          holds_anchor = holds(*info, info->dlpi_phdr[i], s->anchor);
        if (!holds_anchor) return 0;
        for (int i = 0; i < info->dlpi_phnum; ++i) {
          const ElfW(Phdr)& header = info->dlpi_phdr[i];
          if (!holds(*info, header, s->address)) continue;
          s->segment.found = true;
          s->segment.flags = header.p_flags;
          s->segment.readable = static_cast<std::size_t>(info->dlpi_addr + header.p_vaddr +
                                                         header.p_memsz - s->address);
          break;
        }
        return 1;
      },
      &search);
  return search.segment;
}

bool readable_in_module(const void* entry, const void* address, std::size_t size) {
  const Segment segment = segment_of(entry, address);
  return segment.found && (segment.flags & PF_R) != 0 && segment.readable >= size;
}

// The version string a module's table points to, if it is a short
// NUL-terminated printable string in the module's memory; empty otherwise.
std::string version_text(const void* entry, const char* text) {
  constexpr std::size_t kLongest = 64;
  const Segment segment = segment_of(entry, text);
  if (!segment.found || (segment.flags & PF_R) == 0) return {};
  const std::size_t limit = segment.readable < kLongest ? segment.readable : kLongest;
  const std::size_t length = strnlen(text, limit);
  if (length == 0 || length == limit) return {};
  for (std::size_t i = 0; i < length; ++i)
    if (text[i] < 0x20 || text[i] > 0x7e) return {};
  return std::string(text, length);
}

}  // namespace

std::string module_file(const std::string& path) {
  return path.find('/') == std::string::npos ? "./" + path : path;
}

void* module_entry(const std::string& path, const char* symbol, std::string& reason) {
  const std::string file = module_file(path);
  void* handle = dlopen(file.c_str(), RTLD_NOW | RTLD_LOCAL);
  if (handle == nullptr) {
    const char* error = dlerror();
    reason = error != nullptr ? error : "dlopen failed";
    if (reason.rfind(file + ": ", 0) == 0) reason.erase(0, file.size() + 2);
    return nullptr;
  }
  void* entry = dlsym(handle, symbol);
  if (entry == nullptr) {
    reason = std::string("no ") + symbol + " entry point";
    return nullptr;
  }
  // Calling a data symbol of that name would jump into data.
  const Segment segment = segment_of(entry, entry);
  if (!segment.found || (segment.flags & PF_X) == 0) {
    reason = std::string(symbol) + " is not a function";
    return nullptr;
  }
  return entry;
}

std::string check_module_table(const void* entry, const void* table, std::size_t table_size,
                               int version, const char* binbow_version) {
  if (table == nullptr) return "its entry point returned no table";
  if (!readable_in_module(entry, table, sizeof(ModuleTableHeader)))
    return "its entry point returned an address outside the module";
  ModuleTableHeader header;
  std::memcpy(&header, table, sizeof header);
  const std::string built_for = version_text(entry, header.binbow_version);
  if (built_for.empty()) return "its table names no binbow version";
  if (built_for != binbow_version)
    return "built for binbow " + built_for + ", not for this binbow " + binbow_version;
  if (header.version != version)
    return "built by another build of binbow " + built_for + " (module interface " +
           std::to_string(header.version) + ", this binbow's is " + std::to_string(version) + ")";
  if (!readable_in_module(entry, table, table_size)) return "its table ends outside the module";
  return {};
}

}  // namespace binbow::detail
