// The commands that read images or videos (build-vocab, features,
// detect-loops, db build/query/add, bench, demo, make-route) and the parts of
// info, convert and evaluate that need an extractor, the loop detector or the
// run's images live in binbow_cli_vision, a module the binbow executable
// loads with dlopen only when the command line asks for one of them. The
// executable itself links no OpenCV: OpenCV's core alone brings TBB, BLAS,
// LAPACK and X11 libraries, several times the start-up of the whole of
// `binbow --version`, `info`, `convert`, `evaluate` or `db remove`.
//
// Both sides are built by the same build with the same CLI11 and standard
// library, so the interface passes C++ types (CLI::App, std::string); the
// version check refuses a module of another build, and a file that is not
// binbow's module is an error naming it, never a crash (core/module_entry.h).
// Exceptions thrown by the module's commands reach the executable's main()
// as they are.
#pragma once

#include <atomic>
#include <cstddef>
#include <string>
#include <vector>

#include <CLI/CLI.hpp>

#include "evaluate.h"
#include "info_fields.h"
#include "invocation.h"

namespace binbow::cli {

// Raised whenever VisionCommands changes.
inline constexpr int kVisionCommandsVersion = 3;

struct VisionCommands {
  int version;
  const char* binbow_version;
  // Each registers its command on `app` (commands.h).
  void (*add_build_vocab_command)(CLI::App& app);
  void (*add_features_command)(CLI::App& app);
  void (*add_detect_loops_command)(CLI::App& app);
  // `db build`, `db query` and `db add`, on the `db` command.
  void (*add_db_image_commands)(CLI::App& db);
  void (*add_bench_command)(CLI::App& app);
  void (*add_demo_command)(CLI::App& app);
  void (*add_make_route_command)(CLI::App& app);
  // `binbow info` of a loop detector state (.bbld): checks and describes it.
  void (*describe_loop_state)(const std::string& path, const std::string& vocab_argument,
                              InfoFields& fields);
  // The descriptor size in bytes of extractor `name` (vision::make_extractor).
  std::size_t (*descriptor_code_size)(const std::string& name);
  // `binbow evaluate --sweep` and `--report` (evaluate.h).
  std::vector<double> (*evaluate_sweep_values)(const EvaluateArguments& arguments);
  SweepOutcome (*sweep_and_report)(const EvaluateArguments& arguments,
                                   const Evaluation& evaluation);
  // Makes the module's check points read the executable's signal flag
  // (interruption.h); called once the module is loaded.
  void (*watch_interruption_flag)(const std::atomic<int>* flag) noexcept;
  // Makes the module's invocation() the executable's (invocation.h): the
  // command line, the start time and --quiet that main() set.
  void (*watch_invocation)(const Invocation* invocation) noexcept;
};

// Whether the command line names a command (or asks for the help or the
// usage error listing every command) that needs the module: all but
// `--version`, `info`, `convert`, `evaluate` and `db remove`.
bool needs_vision_commands(int argc, const char* const* argv);

// The module's functions, loading it on the first call. It is looked for at
// $BINBOW_CLI_VISION_MODULE (a file path, when set: a name without a slash
// is in the working directory, never searched for on the library path), then
// beside binbow_media relative to the executable: <bindir>/../<libdir>/binbow
// (installed, and the build tree's layout), <package>/lib/binbow (the Python
// package's bin/binbow); then in the install prefix's <libdir>/binbow.
// Throws binbow::Error naming the file, why it did not load and what to do
// when none loads. Inside the module (its `demo` runs `evaluate`), the
// module's own functions.
const VisionCommands& vision_commands();

}  // namespace binbow::cli

// The module's one exported symbol.
extern "C" const binbow::cli::VisionCommands* binbow_cli_vision_commands();
inline constexpr const char* kBinbowCliVisionSymbol = "binbow_cli_vision_commands";
