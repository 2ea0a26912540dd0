#include <cstdio>
#include <exception>
#include <filesystem>
#include <new>
#include <string>

#include "binbow/error.h"
#include "commands.h"
#include "interruption.h"
#include "unsigned_options.h"
#include "vision_commands.h"

namespace {

// The command the user was typing, e.g. "binbow db query", for the usage hint.
std::string command_path(const CLI::App& app) {
  std::string path = "binbow";
  for (const CLI::App* command = &app; !command->get_subcommands().empty();) {
    command = command->get_subcommands().front();
    path += " " + command->get_name();
  }
  return path;
}

// Every command, in the order --help lists them; those of the vision module
// only when the command line needs them (vision_commands.h), so that the
// others start without OpenCV.
void add_commands(CLI::App& app, int argc, const char* const* argv) {
  using namespace binbow::cli;
  const VisionCommands* vision = needs_vision_commands(argc, argv) ? &vision_commands() : nullptr;
  add_info_command(app);
  if (vision) vision->add_build_vocab_command(app);
  if (vision) vision->add_features_command(app);
  add_convert_command(app);
  if (vision) vision->add_detect_loops_command(app);
  add_evaluate_command(app);
  add_db_command(app, vision ? vision->add_db_image_commands : nullptr);
  if (vision) vision->add_bench_command(app);
  if (vision) vision->add_demo_command(app);
  if (vision) vision->add_make_route_command(app);
}

int fail(const std::string& message) {
  std::fprintf(stderr, "binbow: error: %s\n", message.c_str());
  return 1;
}

// The commands that can run for minutes, whose loops have check points
// (interruption.h): a signal stops them there, their temporaries removed.
bool stops_at_check_points(int argc, const char* const* argv) {
  const std::string command = argc >= 2 ? argv[1] : "";
  const std::string subcommand = argc >= 3 ? argv[2] : "";
  return command == "detect-loops" || command == "evaluate" ||
         (command == "db" && (subcommand == "build" || subcommand == "add"));
}

// 128 + the signal's number, as a shell reports a command a signal stopped.
int interrupted(int signal) {
  std::fprintf(stderr, "binbow: interrupted\n");
  return 128 + signal;
}

}  // namespace

// Every failure ends the same way, so scripts can rely on it: one
// "binbow: error: ..." line on stderr and exit status 1; a usage error adds
// where to read the usage. --help and --version print to stdout and exit 0.
// A long command stopped by SIGINT or SIGTERM prints "binbow: interrupted"
// and exits with 130 or 143.
int main(int argc, char** argv) {
  if (stops_at_check_points(argc, argv)) binbow::cli::stop_at_check_points();
  CLI::App app{"binbow: fast place recognition and loop closure with bags of binary words"};
  app.require_subcommand(1);
  app.set_version_flag("--version", "binbow " BINBOW_VERSION);
  try {
    add_commands(app, argc, argv);
  } catch (const binbow::Error& e) {
    return fail(e.what());
  }
  binbow::cli::UnsignedOptions unsigned_options(app);
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    if (e.get_exit_code() == static_cast<int>(CLI::ExitCodes::Success)) return app.exit(e);
    std::string message = binbow::cli::unknown_command_message(app, argc, argv);
    if (message.empty()) message = unsigned_options.message(e);
    fail(message.empty() ? e.what() : message);
    std::fprintf(stderr, "Run '%s --help' for usage.\n", command_path(app).c_str());
    return 1;
  } catch (const binbow::cli::Interrupted& e) {
    return interrupted(e.signal());
  } catch (const binbow::Error& e) {
    return fail(e.what());
  } catch (const std::filesystem::filesystem_error& e) {
    const std::string path = e.path1().string();
    return fail((path.empty() ? "" : path + ": ") + e.code().message());
  } catch (const std::bad_alloc&) {
    return fail("out of memory; try fewer or smaller inputs");
  } catch (const std::exception& e) {
    return fail(e.what());
  }
  // A signal after the last check point: the outputs are written, but the
  // caller asked to stop and a script must not go on as if it had not.
  if (const int signal = binbow::cli::interruption_signal()) return interrupted(signal);
  return 0;
}
