#include "saved_state_descriptor.h"

#include <algorithm>
#include <vector>

#include "binbow/error.h"
#include "binbow/vision/features.h"

namespace binbow::cli {

void check_saved_descriptor(const std::string& path, const loop::LoopDetectorFileInfo& saved) {
  if (saved.descriptor.empty()) return;  // the vocabulary's extractor is used
  const std::vector<std::string> known = vision::extractor_names();
  if (std::find(known.begin(), known.end(), saved.descriptor) == known.end()) {
    constexpr std::size_t kShown = 40;
    std::string list;
    for (const std::string& name : known) list += (list.empty() ? "" : ", ") + name;
    throw FileError(path, "the state names the descriptor \"" + saved.descriptor.substr(0, kShown) +
                              (saved.descriptor.size() > kShown ? "..." : "") +
                              "\", which binbow cannot extract (expected one of " + list + ")");
  }
  const std::size_t code_size = vision::make_extractor(saved.descriptor, 0)->code_size();
  if (code_size != saved.code_size)
    throw FileError(path, "the state's descriptors have " + std::to_string(saved.code_size) +
                              " bytes, but " + saved.descriptor + " descriptors have " +
                              std::to_string(code_size));
}

}  // namespace binbow::cli
