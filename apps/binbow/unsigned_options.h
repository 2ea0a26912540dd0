// One check for every option of an unsigned integer type, whichever command
// adds it. CLI11 reads those with strtoull, which takes "-1" as the type's
// largest value, turns numbers past 2^64 - 1 into 2^64 - 1 instead of
// refusing them, and reads "010" as octal and "0x10" as hexadecimal. Here a
// value must be decimal digits (leading zeros are dropped: "010" is ten)
// within the option's type, and the error names the option and that range.
#pragma once

#include <string>
#include <vector>

#include <CLI/CLI.hpp>

namespace binbow::cli {

class UnsignedOptions {
 public:
  // Adds the check, after the option's own checks (which keep their
  // messages; leading zeros are dropped before them), to every option of `app` and of its commands
  // that CLI11 reads as an unsigned integer (type name UINT); call it once every command is added.
  // `app` must outlive this object's use.
  explicit UnsignedOptions(CLI::App& app);
  UnsignedOptions(const UnsignedOptions&) = delete;
  UnsignedOptions& operator=(const UnsignedOptions&) = delete;

  // After app.parse() threw `error`: when an unsigned option's value caused
  // it, "--seed: must be a whole number from 0 to 18446744073709551615, not
  // -1"; otherwise empty. Leaves the options' values undefined: for the
  // error path only.
  std::string message(const CLI::ParseError& error);

 private:
  void add_checks(CLI::App& app);

  std::vector<CLI::Option*> options_;
  CLI::Option* refused_ = nullptr;  // the option whose value the check refused
  std::string refused_value_;
};

}  // namespace binbow::cli
