// binbow features: detect and describe keypoints in one image (the first
// frame of a video, directory or list).
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <memory>
#include <string>
#include <vector>

#include <opencv2/features2d.hpp>
#include <opencv2/imgproc.hpp>

#include "binbow/error.h"
#include "binbow/vision/features.h"
#include "binbow/vision/image_source.h"
#include "commands.h"
#include "extractor_options.h"
#include "image_source_options.h"
#include "output_options.h"
#include "vision/media_module.h"

namespace binbow::cli {
namespace {

struct FeaturesArguments {
  std::string image;
  std::string descriptor = kDefaultDescriptor;
  int max_features = 0;
  int fast_threshold = -1;
  std::string pattern;
  std::string draw;
  int repeat = 5;
  vision::ImageSourceOptions source;
};

// Options that do not apply to the chosen descriptor are usage errors.
void check_options_apply(const FeaturesArguments& arguments) {
  if (!arguments.pattern.empty() && arguments.descriptor != "brief")
    throw CLI::ValidationError("--pattern", "applies to --descriptor brief only");
  if (arguments.fast_threshold >= 0 && arguments.descriptor != "brief" &&
      arguments.descriptor != "orb")
    throw CLI::ValidationError("--fast-threshold", "applies to --descriptor brief and orb only");
}

std::unique_ptr<vision::FeatureExtractor> make_configured_extractor(
    const FeaturesArguments& arguments) {
  if (arguments.descriptor == "brief") {
    vision::BriefOptions options;
    if (arguments.max_features > 0) options.max_features = arguments.max_features;
    if (arguments.fast_threshold >= 0) options.fast_threshold = arguments.fast_threshold;
    options.pattern_file = arguments.pattern;
    return vision::make_brief_extractor(options);
  }
  if (arguments.descriptor == "orb") {
    vision::OrbOptions options;
    if (arguments.max_features > 0) options.max_features = arguments.max_features;
    if (arguments.fast_threshold >= 0) options.fast_threshold = arguments.fast_threshold;
    return vision::make_orb_extractor(options);
  }
  return vision::make_extractor(arguments.descriptor, arguments.max_features);
}

void draw_features(const cv::Mat& image, const vision::Features& features,
                   const std::string& path) {
  cv::Mat canvas;
  cv::drawKeypoints(image, vision::to_opencv(features.keypoints), canvas, cv::Scalar(0, 255, 0),
                    cv::DrawMatchesFlags::DRAW_RICH_KEYPOINTS);
  bool written = false;
  try {
    written = vision::media_module().write_image(path, canvas);
  } catch (const cv::Exception& e) {
    throw FileError(path, "cannot write image: " + e.msg);
  }
  if (!written) throw FileError(path, "cannot write image (unknown extension or unwritable)");
}

void run_features(const FeaturesArguments& arguments) {
  check_options_apply(arguments);
  if (!arguments.draw.empty()) {
    refuse_standard_output("--draw", arguments.draw);
    if (!vision::media_module().have_image_writer(arguments.draw)) {
      throw CLI::ValidationError(
          "--draw",
          arguments.draw + ": OpenCV has no image writer for this extension (use .png or .jpg)");
    }
    prepare_output_file("--draw", arguments.draw);
  }
  const auto extractor = make_configured_extractor(arguments);
  vision::ImageSource source({arguments.image},
                             vision::limit_for_extractor(arguments.source, *extractor));
  vision::Frame frame;
  if (!source.next(frame)) throw FileError(arguments.image, "has no frames");
  const cv::Mat& image = frame.image;
  // The first call pays for OpenCV's lazy initialisation; time the calls after it.
  const vision::Features features = vision::extract_features(*extractor, image, frame.name);
  std::vector<double> times;
  for (int run = 0; run < arguments.repeat; ++run) {
    const auto start = std::chrono::steady_clock::now();
    vision::extract_features(*extractor, image, frame.name);
    times.push_back(
        std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start)
            .count());
  }
  std::nth_element(times.begin(), times.begin() + times.size() / 2, times.end());
  const double milliseconds = times[times.size() / 2];
  std::printf("image: %s (%dx%d)\n", frame.name.c_str(), image.cols, image.rows);
  std::printf("descriptor: %s (%zu bytes)\n", extractor->name().c_str(), extractor->code_size());
  std::printf("keypoints: %zu\n", features.keypoints.size());
  std::printf("time: %.3f ms (median of %d runs)\n", milliseconds, arguments.repeat);
  if (!arguments.draw.empty()) {
    draw_features(image, features, arguments.draw);
    std::printf("drawn: %s\n", arguments.draw.c_str());
  }
}

}  // namespace

void add_features_command(CLI::App& app) {
  auto arguments = std::make_shared<FeaturesArguments>();
  CLI::App* command = app.add_subcommand(
      "features",
      "Detect keypoints and compute binary descriptors in one image; print the count "
      "and the extraction time");
  command
      ->add_option("image", arguments->image,
                   "Image file (any format OpenCV reads); of a video, directory or text list "
                   "of images, the first frame")
      ->required();
  add_descriptor_option(command, arguments->descriptor);
  add_features_option(command, arguments->max_features, "-n,--features");
  command
      ->add_option("--fast-threshold", arguments->fast_threshold,
                   "FAST threshold for brief (default 10) and orb (default 20)")
      ->check(CLI::Range(0, 255));
  command->add_option("--pattern", arguments->pattern,
                      "BRIEF test pattern file (OpenCV YAML with x1 y1 x2 y2; default built in)");
  command
      ->add_option("--repeat", arguments->repeat,
                   "Timed runs after a warm-up; the median is printed")
      ->check(CLI::Range(1, 1000))
      ->capture_default_str();
  command->add_option(
      "--draw", arguments->draw,
      std::string("Write the image with its keypoints to this file") + kOutputFolderParentsHelp);
  add_image_source_options(command, arguments->source);
  command->callback([arguments] { run_features(*arguments); });
}

}  // namespace binbow::cli
