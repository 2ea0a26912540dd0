// CLI11 validators built on the library's own parsers: the accepted names
// live in one place, and a bad value is a usage error before any work.
#pragma once

#include <string>

#include <CLI/CLI.hpp>

#include "binbow/error.h"

namespace binbow::cli {

// Accepts the values `parse` accepts; the error is the library's message,
// which lists the valid names.
template <typename Parser>
CLI::Validator parsed_by(Parser parse) {
  return CLI::Validator(
      [parse](std::string& value) -> std::string {
        try {
          parse(value);
          return {};
        } catch (const Error& e) {
          return e.what();
        }
      },
      "");
}

}  // namespace binbow::cli
