#include <algorithm>
#include <string>
#include <vector>

#include "commands.h"

namespace binbow::cli {
namespace {

// Levenshtein distance: a typo of one or two letters is what a user makes.
std::size_t edit_distance(const std::string& a, const std::string& b) {
  std::vector<std::size_t> row(b.size() + 1);
  for (std::size_t j = 0; j <= b.size(); ++j) row[j] = j;
  for (std::size_t i = 1; i <= a.size(); ++i) {
    std::size_t diagonal = row[0];
    row[0] = i;
    for (std::size_t j = 1; j <= b.size(); ++j) {
      const std::size_t substitution = diagonal + (a[i - 1] == b[j - 1] ? 0 : 1);
      diagonal = row[j];
      row[j] = std::min({row[j] + 1, row[j - 1] + 1, substitution});
    }
  }
  return row[b.size()];
}

const CLI::App* find_subcommand(const CLI::App& app, const std::string& name) {
  for (const CLI::App* command : app.get_subcommands({})) {
    if (command->get_name() == name) return command;
  }
  return nullptr;
}

}  // namespace

std::string unknown_command_message(const CLI::App& app, int argc, const char* const* argv) {
  const CLI::App* command = &app;
  std::string path = "binbow";
  int i = 1;
  for (; i < argc; ++i) {
    const CLI::App* next = find_subcommand(*command, argv[i]);
    if (!next) break;
    command = next;
    path += " " + command->get_name();
  }
  const std::vector<const CLI::App*> subcommands = command->get_subcommands({});
  if (i >= argc || argv[i][0] == '-' || subcommands.empty()) return {};

  const std::string typed = argv[i];
  std::string best;
  std::size_t best_distance = 0;
  std::string names;
  for (const CLI::App* candidate : subcommands) {
    const std::string& name = candidate->get_name();
    names += (names.empty() ? "" : ", ") + name;
    const std::size_t distance = edit_distance(typed, name);
    const bool prefix = name.compare(0, typed.size(), typed) == 0;
    if ((prefix || distance <= 2) && (best.empty() || distance < best_distance)) {
      best = name;
      best_distance = distance;
    }
  }
  const std::string unknown =
      "unknown command '" + typed + "'" + (command == &app ? "" : " for '" + path + "'");
  if (!best.empty()) return unknown + "; did you mean '" + best + "'?";
  return unknown + "; the commands are: " + names;
}

}  // namespace binbow::cli
