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

// The error for a value that parses as T and fails `accepted` (as
// "must be ..., not <value>"); a value that does not parse is left to CLI11,
// which names the option and the value, and for unsigned options to
// UnsignedOptions (unsigned_options.h). Counts are checked as signed: CLI11
// reads "-1" into an unsigned field as its largest value.
template <typename T, typename Accepted>
CLI::Validator checked_number(Accepted accepted, const std::string& requirement) {
  return CLI::Validator(
      [accepted, requirement](std::string& input) -> std::string {
        T value{};
        if (!CLI::detail::lexical_cast(input, value) || accepted(value)) return {};
        return "must be " + requirement + ", not " + input;
      },
      "");
}

}  // namespace binbow::cli
