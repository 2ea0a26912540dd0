// The extractor flags shared by the commands that extract features and look
// them up in a vocabulary (--descriptor, --features), so they read the same
// everywhere.
#pragma once

#include <string>

#include <CLI/CLI.hpp>

namespace binbow::cli {

// `descriptor_note` is added to the help of --descriptor, e.g. why it must
// match something.
inline void add_extractor_options(CLI::App* command, std::string& descriptor, int& features,
                                  const std::string& descriptor_note = "") {
  command
      ->add_option("--descriptor", descriptor,
                   "Binary descriptor: orb or brief" +
                       (descriptor_note.empty() ? "" : " (" + descriptor_note + ")"))
      ->check(CLI::IsMember({"orb", "brief"}))
      ->capture_default_str();
  command->add_option("--features", features,
                      "Features per image (0: the extractor's default, ORB 1000, BRIEF 300)");
}

}  // namespace binbow::cli
