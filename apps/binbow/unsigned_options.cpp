#include "unsigned_options.h"

#include <algorithm>
#include <cstddef>
#include <string>

namespace binbow::cli {

namespace {

constexpr const char* kLargest64 = "18446744073709551615";

bool is_digits(const std::string& value) {
  if (value.empty()) return false;
  for (const char c : value)
    if (c < '0' || c > '9') return false;
  return true;
}

// Decimal digits without a leading zero (the transform below drops them) and
// at most 2^64 - 1.
bool is_plain_number(const std::string& value) {
  if (!is_digits(value) || (value.size() > 1 && value[0] == '0')) return false;
  const std::string largest = kLargest64;
  return value.size() < largest.size() || (value.size() == largest.size() && value <= largest);
}

bool is_unsigned(const CLI::Option& option) {
  const std::string type = option.get_type_name();
  return type.substr(0, type.find(':')) == "UINT";
}

// Whether the option's own conversion (to the type of the variable it sets)
// takes `value`. Runs its callback, so for the error path only; its checks
// are switched off, as the candidates are about the type alone.
bool converts(CLI::Option& option, const std::string& value) {
  for (int i = 0;; ++i) {
    try {
      option.get_validator(i)->active(false);
    } catch (const CLI::OptionNotFound&) {
      break;
    }
  }
  option.clear();
  option.add_result(value);
  try {
    option.run_callback();
  } catch (const CLI::ConversionError&) {
    return false;
  } catch (...) {
    // A callback of add_option_function refused the number after the
    // conversion took it: the type holds it.
  }
  return true;
}

// The largest value of the option's type, found by offering it the largest
// value of each unsigned width; empty if it takes none.
std::string largest_value(CLI::Option& option) {
  for (const char* largest : {kLargest64, "4294967295", "65535", "255"})
    if (converts(option, largest)) return largest;
  return {};
}

}  // namespace

UnsignedOptions::UnsignedOptions(CLI::App& app) {
  add_checks(app);
}

void UnsignedOptions::add_checks(CLI::App& app) {
  for (CLI::Option* option : app.get_options()) {
    if (!is_unsigned(*option)) continue;
    options_.push_back(option);
    // Before the option's own checks, which would read "017" as octal 15.
    option->transform(CLI::Validator(
        [](std::string& value) -> std::string {
          if (is_digits(value))
            value.erase(0, std::min(value.find_first_not_of('0'), value.size() - 1));
          return {};
        },
        "", "decimal"));
    // After the option's own checks, which keep their messages. Without a
    // description, which --help would show after the type.
    option->check(CLI::Validator(
        [this, option](std::string& value) -> std::string {
          if (is_plain_number(value)) return {};
          refused_ = option;
          refused_value_ = value;
          return "must be a whole number, not " + value;
        },
        "", "unsigned number"));
  }
  for (CLI::App* command : app.get_subcommands([](CLI::App*) { return true; }))
    add_checks(*command);
}

std::string UnsignedOptions::message(const CLI::ParseError& error) {
  CLI::Option* option = refused_;
  std::string value = refused_value_;
  // A plain number the type cannot hold (past 2^32 - 1 for a 32-bit option)
  // passes the check; CLI11's conversion then fails, naming the option.
  if (option == nullptr && dynamic_cast<const CLI::ConversionError*>(&error) != nullptr) {
    const std::string what = error.what();
    for (CLI::Option* candidate : options_) {
      if (candidate->count() == 0 ||
          what.rfind("Could not convert: " + candidate->get_name() + " = ", 0) != 0)
        continue;
      const std::vector<std::string> results = candidate->results();
      for (const std::string& result : results)
        if (!converts(*candidate, result)) {
          option = candidate;
          value = result;
          break;
        }
      if (option != nullptr) break;
    }
  }
  if (option == nullptr) return {};
  const std::string largest = largest_value(*option);
  if (largest.empty()) return {};
  return option->get_name() + ": must be a whole number from 0 to " + largest + ", not " + value;
}

}  // namespace binbow::cli
