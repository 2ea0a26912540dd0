// binbow's on-demand modules (the image/video module, the CLI's image
// commands) are opened the same way: loaded once and never closed, since
// what their entry points return lives in them.
#pragma once

#include <string>

namespace binbow::detail {

// The address of `symbol` in the shared object at `path`, loading it; null
// on failure, with why in `reason` (the loader's words without the path, or
// "no <symbol> entry point").
void* module_entry(const std::string& path, const char* symbol, std::string& reason);

}  // namespace binbow::detail
