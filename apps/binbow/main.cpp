#include <cstdio>
#include <exception>

#include "binbow/error.h"
#include "commands.h"

int main(int argc, char** argv) {
  CLI::App app{"binbow: fast place recognition and loop closure with bags of binary words"};
  app.require_subcommand(1);
  app.set_version_flag("--version", "binbow 0.1.0");
  binbow::cli::add_info_command(app);
  binbow::cli::add_build_vocab_command(app);
  binbow::cli::add_features_command(app);
  binbow::cli::add_convert_command(app);
  binbow::cli::add_detect_loops_command(app);
  binbow::cli::add_evaluate_command(app);
  binbow::cli::add_db_command(app);
  binbow::cli::add_bench_command(app);
  binbow::cli::add_demo_command(app);
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    return app.exit(e);
  } catch (const binbow::Error& e) {
    std::fprintf(stderr, "binbow: error: %s\n", e.what());
    return 1;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "binbow: unexpected error: %s\n", e.what());
    return 1;
  }
  return 0;
}
