// Each subcommand lives in its own file and registers itself on the app.
// The binbow executable holds info, convert, evaluate and db (with db
// remove); the others, and db build/query/add, are in the binbow_cli_vision
// module (vision_commands.h), which holds evaluate too for its demo.
#pragma once

#include <string>

#include <CLI/CLI.hpp>

#include "info_fields.h"

namespace binbow::cli {

void add_info_command(CLI::App& app);
void add_build_vocab_command(CLI::App& app);
void add_features_command(CLI::App& app);
void add_convert_command(CLI::App& app);
void add_detect_loops_command(CLI::App& app);
void add_evaluate_command(CLI::App& app);
// `db`, with `db remove`; `db build`, `db query` and `db add` come from
// `add_image_commands` (the module's add_db_image_commands) when not null.
void add_db_command(CLI::App& app, void (*add_image_commands)(CLI::App& db));
void add_db_image_commands(CLI::App& db);
void add_bench_command(CLI::App& app);
void add_demo_command(CLI::App& app);
void add_make_route_command(CLI::App& app);
// The `binbow info` fields of a .bbdb file, after checking the whole file
// with `verify`; false if `path` is not one.
bool describe_database(const std::string& path, bool verify, const std::string& vocabulary,
                       const std::string& descriptor, InfoFields& fields);
// Checks a loop detector state (.bbld) as `detect-loops --resume-state`
// would and gives its `binbow info` fields.
void describe_loop_state(const std::string& path, const std::string& vocab_argument,
                         InfoFields& fields);
// "unknown command 'detect-loop'; did you mean 'detect-loops'?" when the
// argument after the commands given names none of the next level's commands;
// empty otherwise.
std::string unknown_command_message(const CLI::App& app, int argc, const char* const* argv);

}  // namespace binbow::cli
