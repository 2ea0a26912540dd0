// Real ORB-1000 images for the benchmarks: the training photographs that
// Debian ships (scripts/training_images.sh), their descriptors, and noisy
// copies of them (distinct images of the same scenes).
#pragma once

#include <cstdint>
#include <cstdio>
#include <opencv2/imgproc.hpp>
#include <random>
#include <string>
#include <vector>

#include "binbow/descriptors.h"
#include "binbow/vision/features.h"
#include "binbow/vision/image_source.h"

namespace binbow::bench {

// The photographs' paths, sorted: the default list, or with `all` every ViSP
// frame too (~1100 images).
inline std::vector<std::string> training_photographs(bool all) {
  const std::string command =
      std::string(BINBOW_SOURCE_DIR) + "/scripts/training_images.sh" + (all ? " --all" : "");
  std::vector<std::string> paths;
  FILE* pipe = popen(command.c_str(), "r");
  if (pipe == nullptr) return paths;
  char line[4096];
  while (std::fgets(line, sizeof line, pipe) != nullptr) {
    std::string path(line);
    while (!path.empty() && (path.back() == '\n' || path.back() == '\r')) path.pop_back();
    if (!path.empty()) paths.push_back(path);
  }
  pclose(pipe);
  return paths;
}

// `features` ORB descriptors of a photograph; small photographs are enlarged
// until they give as many (empty if they never do).
inline DescriptorMatrix orb_descriptors(const vision::FeatureExtractor& extractor,
                                        const std::string& path, std::size_t features) {
  cv::Mat image = vision::read_grey_image(path);
  for (int attempt = 0; attempt < 3; ++attempt) {
    DescriptorMatrix descriptors = extractor.extract(image).descriptors;
    if (descriptors.rows() >= features) {
      descriptors.resize(features);
      return descriptors;
    }
    cv::resize(image, image, cv::Size(), 2.0, 2.0);
  }
  return DescriptorMatrix(32);
}

// Flips `bits` random bits of every descriptor (seeded): another image of
// the same scene.
inline void flip_bits(DescriptorMatrix& image, int bits, std::uint64_t seed) {
  std::mt19937_64 rng(seed);
  for (std::size_t r = 0; r < image.rows(); ++r) {
    std::uint8_t* row = image.row(r);
    for (int flip = 0; flip < bits; ++flip) {
      const auto bit = rng() % (8 * image.code_size());
      row[bit / 8] ^= static_cast<std::uint8_t>(1u << (bit % 8));
    }
  }
}

}  // namespace binbow::bench
