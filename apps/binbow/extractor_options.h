// The extractor flags of every command that extracts features (--descriptor,
// --features), so they offer the same choices and default everywhere.
#pragma once

#include <string>

#include <CLI/CLI.hpp>

#include "binbow/vision/features.h"

namespace binbow::cli {

using vision::kDefaultDescriptor;  // of every command when --descriptor is not given
// Far above any useful count; it only keeps absurd values away from OpenCV.
inline constexpr int kMaxFeatures = 1000000;

// --descriptor with every extractor binbow has; `note` is added to the help,
// e.g. why it must match something.
inline void add_descriptor_option(CLI::App* command, std::string& descriptor,
                                  const std::string& note = "") {
  std::string names;
  for (const std::string& name : vision::extractor_names())
    names += (names.empty() ? "" : ", ") + name;
  command
      ->add_option("--descriptor", descriptor,
                   "Binary descriptor: " + names + (note.empty() ? "" : " (" + note + ")"))
      ->check(CLI::IsMember(vision::extractor_names()))
      ->capture_default_str();
}

// The number of features per image under the option names `names`.
inline void add_features_option(CLI::App* command, int& features,
                                const std::string& names = "--features") {
  command
      ->add_option(names, features,
                   "Features per image (0: the extractor's default, ORB 1000, BRIEF 300, AKAZE "
                   "and BRISK every keypoint found)")
      ->check(CLI::Range(0, kMaxFeatures));
}

inline void add_extractor_options(CLI::App* command, std::string& descriptor, int& features,
                                  const std::string& descriptor_note = "") {
  add_descriptor_option(command, descriptor, descriptor_note);
  add_features_option(command, features);
}

// The extractor options of a command that has a vocabulary: --descriptor is
// left empty when not given, for descriptor_for() to take the one the
// vocabulary records (default_vocabulary.h).
inline void add_vocabulary_extractor_options(CLI::App* command, std::string& descriptor,
                                             int& features) {
  std::string names;
  for (const std::string& name : vision::extractor_names())
    names += (names.empty() ? "" : ", ") + name;
  command
      ->add_option("--descriptor", descriptor,
                   "Binary descriptor: " + names +
                       ". Default: the extractor the vocabulary records, else " +
                       kDefaultDescriptor + "; it must not contradict the vocabulary's")
      ->check(CLI::IsMember(vision::extractor_names()));
  add_features_option(command, features);
}

}  // namespace binbow::cli
