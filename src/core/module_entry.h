// binbow's on-demand modules (the image/video module, the CLI's image
// commands) are opened the same way: loaded once and never closed, since
// what their entry points return lives in them.
//
// A module file may be anything a user points the environment at (another
// build's module, another library, a file that is no library), so nothing it
// returns is trusted before it is checked: the entry point must be code of
// the module, and its table must lie in the module's memory and say that it
// is this build's before any other field of it is read.
#pragma once

#include <cstddef>
#include <string>

namespace binbow::detail {

// The file dlopen is given for `path`: a name without a slash is made
// relative to the working directory ("./name"), since dlopen would search
// the library path for it and could load an unrelated library.
std::string module_file(const std::string& path);

// The address of the function `symbol` in the shared object at
// module_file(path), loading it; null on failure, with why in `reason` (the
// loader's words without the path, "no <symbol> entry point", or
// "<symbol> is not a function").
void* module_entry(const std::string& path, const char* symbol, std::string& reason);

// How every module's table begins, whatever its version: what
// check_module_table reads before anything else.
struct ModuleTableHeader {
  int version;  // the interface version, raised whenever the table changes
  const char* binbow_version;
};

// Checks the table (of `table_size` bytes, beginning with a
// ModuleTableHeader) that `entry`, from module_entry, returned: empty if it
// lies in the module's memory, is of interface `version` and was built for
// binbow `binbow_version`; else why not, saying what differs.
std::string check_module_table(const void* entry, const void* table, std::size_t table_size,
                               int version, const char* binbow_version);

}  // namespace binbow::detail
