// binbow make-route: a long synthetic route through photographs, with exact
// loop ground truth (loop/route.h).
#include <cstdio>
#include <memory>
#include <string>
#include <vector>

#include "binbow/loop/route.h"
#include "commands.h"
#include "invocation.h"
#include "output_options.h"
#include "progress.h"

namespace binbow::cli {
namespace {

struct MakeRouteArguments {
  std::vector<std::string> photographs;
  std::string output;
  loop::RouteOptions options;
};

void run_make_route(const MakeRouteArguments& arguments) {
  try {
    loop::check_route_options(arguments.options);
  } catch (const InvalidArgument& e) {
    throw CLI::ValidationError(e.what());
  }
  prepare_output_directory("-o", arguments.output);
  Progress progress("writing frames", arguments.options.frames);
  const loop::Route route =
      loop::make_route(arguments.photographs, arguments.options, arguments.output,
                       [&](std::size_t done, std::size_t) { progress.update(done); });
  progress.finish();
  std::size_t revisits = 0, visits = 0;
  for (std::size_t i = 0; i < route.frames.size(); ++i)
    if (i == 0 || route.frames[i].visit != route.frames[i - 1].visit) {
      ++visits;
      revisits += route.frames[i].revisit ? 1 : 0;
    }
  print_summary(false,
                "photographs: %zu\nplaces: %zu\nframes: %zu\nvisits: %zu\nrevisits: %zu\n"
                "ground-truth pairs: %zu\n",
                route.photographs.size(), route.places.size(), route.frames.size(), visits,
                revisits, route.loop_pairs().size());
  print_summary(false, "frames: %s/frames\nground truth: %s/ground_truth.txt\n",
                arguments.output.c_str(), arguments.output.c_str());
}

}  // namespace

void add_make_route_command(CLI::App& app) {
  auto arguments = std::make_shared<MakeRouteArguments>();
  loop::RouteOptions& o = arguments->options;
  CLI::App* command = app.add_subcommand(
      "make-route",
      "Simulate a camera walking through photographs: numbered frames that visit and revisit "
      "places, with exact loop ground truth (docs/routes.md)");
  command
      ->add_option("photographs", arguments->photographs,
                   "Photographs: image files, directories or text lists of images; each gives "
                   "the places of its textured cells")
      ->required();
  command
      ->add_option("-o,--output", arguments->output,
                   std::string("New or empty directory: frames/, ground_truth.txt, route.csv, "
                               "places.csv") +
                       kOutputFolderHelp)
      ->required();
  command->add_option("--frames", o.frames, "Frames of the route")->capture_default_str();
  command->add_option("--seed", o.seed, "Seed of everything random")->capture_default_str();
  command->add_option("--width", o.width, "Frame width in pixels")->capture_default_str();
  command->add_option("--height", o.height, "Frame height in pixels")->capture_default_str();
  command->add_option("--min-visit-frames", o.min_visit_frames, "Frames per visit, at least")
      ->capture_default_str();
  command->add_option("--max-visit-frames", o.max_visit_frames, "Frames per visit, at most")
      ->capture_default_str();
  command
      ->add_option("--revisit-probability", o.revisit_probability,
                   "Chance that a visit returns to a place seen before")
      ->capture_default_str();
  command
      ->add_option("--min-revisit-gap", o.min_revisit_gap,
                   "Frames between visits of one place, at least")
      ->capture_default_str();
  command
      ->add_option("--cell-margin", o.cell_margin,
                   "Size of a place's cell in frame sizes: the room views move in")
      ->capture_default_str();
  command
      ->add_option("--min-place-corners", o.min_place_corners,
                   "FAST corners a cell needs to be a place")
      ->capture_default_str();
  command->add_option("--jpeg-quality", o.jpeg_quality, "JPEG quality of the frames")
      ->capture_default_str();
  command->callback([arguments] { run_make_route(*arguments); });
}

}  // namespace binbow::cli
