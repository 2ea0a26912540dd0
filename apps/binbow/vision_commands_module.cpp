// The entry point of binbow_cli_vision (vision_commands.h).
#include <cstddef>
#include <string>

#include "binbow/vision/features.h"
#include "commands.h"
#include "evaluate.h"
#include "interruption.h"
#include "invocation.h"
#include "vision_commands.h"

namespace binbow::cli {
namespace {

std::size_t descriptor_code_size(const std::string& name) {
  return vision::make_extractor(name)->code_size();
}

// clang-format off
constexpr VisionCommands kCommands{
    kVisionCommandsVersion,
    BINBOW_VERSION,
    add_build_vocab_command,
    add_features_command,
    add_detect_loops_command,
    add_db_image_commands,
    add_bench_command,
    add_demo_command,
    add_make_route_command,
    describe_loop_state,
    descriptor_code_size,
    evaluate_sweep_values,
    sweep_and_report,
    watch_interruption_flag,
    watch_invocation};
// clang-format on

}  // namespace

const VisionCommands& vision_commands() {
  return kCommands;
}

}  // namespace binbow::cli

extern "C" __attribute__((visibility("default"))) const binbow::cli::VisionCommands*
binbow_cli_vision_commands() {
  return &binbow::cli::kCommands;
}
