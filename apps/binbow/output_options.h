// Output paths made ready before a command starts its work (missing folders
// created, writability checked: core/output_path.h). A path that cannot be
// written is a usage error that names the option, e.g.
// "-o r1/loops.csv: cannot create the folder r1: ...".
#pragma once

#include <string>

#include <CLI/CLI.hpp>

#include "binbow/error.h"
#include "core/output_path.h"

namespace binbow::cli {

inline void prepare_output_file(const std::string& option, const std::string& path) {
  try {
    detail::prepare_output_file(path);
  } catch (const Error& e) {
    throw CLI::ValidationError(option + " " + e.what());
  }
}

inline void prepare_output_directory(const std::string& option, const std::string& path) {
  try {
    detail::prepare_output_directory(path);
  } catch (const Error& e) {
    throw CLI::ValidationError(option + " " + e.what());
  }
}

}  // namespace binbow::cli
