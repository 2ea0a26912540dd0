// One flag per loop detector parameter (--min-inliers for "min_inliers"),
// generated from the keys of LoopDetectorParams::to_json(): a parameter added
// to the library's table is a flag of every command that takes these options,
// with nothing to add here. The flags override a --params file's keys.
#pragma once

#include <map>
#include <string>

#include <CLI/CLI.hpp>
#include <nlohmann/json.hpp>

#include "binbow/loop/loop_detector.h"

namespace binbow::cli {

// The flag of a parameter key: "--" and the key with '_' written '-'.
inline std::string loop_param_flag(std::string key) {
  for (char& c : key)
    if (c == '_') c = '-';
  return "--" + key;
}

// The values given on the command line, by parameter key (as typed).
struct LoopParamFlags {
  std::map<std::string, std::string> values;
  std::map<std::string, CLI::Option*> options;
};

// Adds every parameter's flag to `command`. Numbers take a number, booleans
// true or false, the rest the names LoopDetectorParams reads (geometric_check,
// fundamental_estimator: the library checks them).
inline void add_loop_param_flags(CLI::App* command, LoopParamFlags& flags) {
  // A number as a parameter file spells it (no inf, nan or hexadecimal).
  const CLI::Validator json_number(
      [](std::string& text) -> std::string {
        const auto number = nlohmann::json::parse(text, nullptr, false);
        return number.is_number() ? std::string() : "'" + text + "' is not a number";
      },
      "NUMBER");
  const auto defaults = nlohmann::ordered_json::parse(loop::LoopDetectorParams{}.to_json());
  for (const auto& [key, value] : defaults.items()) {
    CLI::Option* option =
        command->add_option(loop_param_flag(key), flags.values[key],
                            "Loop detector parameter \"" + key +
                                "\" (overrides --params; default " + value.dump() + ")");
    option->group("Loop detector parameters");
    if (value.is_boolean())
      option->check(CLI::IsMember({"true", "false"}));
    else if (value.is_number())
      option->check(json_number);
    flags.options[key] = option;
  }
}

// The flags given, as a JSON object of parameter keys ("" when none was).
inline std::string loop_param_overrides(const LoopParamFlags& flags) {
  const auto defaults = nlohmann::ordered_json::parse(loop::LoopDetectorParams{}.to_json());
  nlohmann::ordered_json overrides = nlohmann::ordered_json::object();
  for (const auto& [key, value] : defaults.items()) {
    if (flags.options.at(key)->count() == 0) continue;
    const std::string& text = flags.values.at(key);
    if (value.is_boolean())
      overrides[key] = text == "true";
    else if (value.is_number())
      overrides[key] = nlohmann::ordered_json::parse(text);
    else
      overrides[key] = text;
  }
  return overrides.empty() ? std::string() : overrides.dump();
}

}  // namespace binbow::cli
