#include <cstdio>
#include <cstring>
#include <exception>
#include <filesystem>
#include <new>
#include <string>
#include <vector>

#include "binbow/error.h"
#include "commands.h"
#include "interruption.h"
#include "invocation.h"
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

// argv without the app's own flags before the command's name (`binbow
// --quiet detect-loops ...`), for the decisions taken before parsing that
// look at the command's name.
std::vector<const char*> without_leading_flags(int argc, const char* const* argv) {
  std::vector<const char*> words(argv, argv + argc);
  while (words.size() > 1 &&
         (std::strcmp(words[1], "-q") == 0 || std::strcmp(words[1], "--quiet") == 0))
    words.erase(words.begin() + 1);
  return words;
}

// Every command, in the order --help lists them; those of the vision module
// only when the command line needs them (vision_commands.h), so that the
// others start without OpenCV.
void add_commands(CLI::App& app, const std::vector<const char*>& words) {
  using namespace binbow::cli;
  const VisionCommands* vision = needs_vision_commands(static_cast<int>(words.size()), words.data())
                                     ? &vision_commands()
                                     : nullptr;
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

// -q/--quiet on the app and on every command, where a user writes it
// (before or after the command's name), all setting Invocation::quiet.
void add_quiet_flag(CLI::App& command) {
  command.add_flag("-q,--quiet", binbow::cli::own_invocation().quiet,
                   "No progress and no informational lines; results asked for, warnings and "
                   "errors still print");
  for (CLI::App* subcommand : command.get_subcommands([](CLI::App*) { return true; }))
    add_quiet_flag(*subcommand);
}

int fail(const std::string& message) {
  std::fprintf(stderr, "binbow: error: %s\n", message.c_str());
  return 1;
}

// The commands that can run for minutes, whose loops have check points
// (interruption.h): a signal stops them there, their temporaries removed.
bool stops_at_check_points(const std::vector<const char*>& words) {
  const std::string command = words.size() >= 2 ? words[1] : "";
  const std::string subcommand = words.size() >= 3 ? words[2] : "";
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
  const std::vector<const char*> words = without_leading_flags(argc, argv);
  if (stops_at_check_points(words)) binbow::cli::stop_at_check_points();
  binbow::cli::Invocation& invocation = binbow::cli::own_invocation();
  invocation.command_line = binbow::cli::shell_quoted({argv, argv + argc});
  invocation.started_utc = binbow::cli::utc_now();
  CLI::App app{"binbow: fast place recognition and loop closure with bags of binary words"};
  app.require_subcommand(1);
  app.set_version_flag("--version", "binbow " BINBOW_VERSION);
  try {
    add_commands(app, words);
    add_quiet_flag(app);
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
