// binbow_media, the module with OpenCV's imgcodecs and videoio and matio
// (media/media_api.h), loaded on first use so that programs start without
// them.
#pragma once

#include <string>
#include <vector>

#include "media/media_api.h"

namespace binbow::vision {

// The module's functions, loading it on the first call (thread-safe). It is
// looked for, in order, at $BINBOW_MEDIA_MODULE (a file path, when set), then
// relative to the program or shared library holding this code: beside a
// shared binbow library (<libdir>/binbow/binbow_media.so), from an
// executable in <prefix>/<bindir>, inside the Python package
// (<package>/lib/binbow/), beside a module in <libdir>/binbow (the CLI's
// binbow_cli_vision), and at the install prefix's <libdir>/binbow.
// Throws binbow::Error "cannot load the image/video module <path>: <reason>"
// when none loads, or the one found belongs to another binbow build.
const media::Api& media_module();

// Where media_module() looks, in order (without $BINBOW_MEDIA_MODULE).
std::vector<std::string> media_module_candidates();

}  // namespace binbow::vision
