// `binbow info STATE.bbld`: a loop detector state, checked by loading it.
#include <cstdio>
#include <filesystem>
#include <string>
#include <system_error>
#include <utility>
#include <vector>

#include "binbow/formats.h"
#include "binbow/loop/loop_detector.h"
#include "binbow/vocabulary.h"
#include "commands.h"
#include "default_vocabulary.h"
#include "info_fields.h"
#include "invocation.h"
#include "saved_state_descriptor.h"

namespace binbow::cli {

namespace {

// Checks the whole state as `detect-loops --resume-state` does, by loading
// it. A fixed vocabulary's state needs that vocabulary: --vocab, else the
// bundled default of its descriptor when its checksum is the state's; without
// one, says on stderr what was left unchecked.
void verify_loop_state(const std::string& path, const loop::LoopDetectorFileInfo& info,
                       const std::string& vocab_argument) {
  if (info.online) {
    loop::LoopDetector::load(path);
    return;
  }
  Vocabulary vocabulary;
  if (vocab_argument.empty()) {
    if (has_default_vocabulary(info.descriptor)) {
      const std::vector<std::string> candidates = default_vocabulary_candidates(info.descriptor);
      for (const std::string& candidate : candidates) {
        std::error_code error;
        if (!std::filesystem::is_regular_file(candidate, error)) continue;
        Vocabulary bundled = load_vocabulary(candidate);
        if (bundled.checksum() == info.vocabulary_checksum) vocabulary = std::move(bundled);
        break;
      }
    }
    if (vocabulary.empty()) {
      note(
          "note: %s: the header, the parameters and the previous BoW vector are checked; "
          "the database, features and the rest need the state's vocabulary (checksum "
          "%08x): give --vocab to check them\n",
          path.c_str(), info.vocabulary_checksum);
      return;
    }
  } else {
    std::string descriptor = info.descriptor;
    load_loop_vocabulary(vocab_argument, descriptor, vocabulary);
  }
  loop::LoopDetector::load(path, std::move(vocabulary));
}

}  // namespace

void describe_loop_state(const std::string& path, const std::string& vocab_argument,
                         InfoFields& fields) {
  const loop::LoopDetectorFileInfo info = loop::LoopDetector::inspect(path);
  check_saved_descriptor(path, info);
  verify_loop_state(path, info, vocab_argument);
  fields.add("kind", "loop detector state");
  fields.add("version", info.version);
  fields.add("vocabulary", info.online ? "online" : "fixed");
  fields.add("descriptor", info.descriptor.empty() ? "unknown" : info.descriptor);
  fields.add("descriptor_bits", info.code_size * 8);
  fields.add("frames", info.frames);
  fields.add("forgotten_frames", info.forgotten_frames);
  if (!info.online) {
    fields.add("vocabulary_checksum", hex_checksum(info.vocabulary_checksum));
    fields.add("vocabulary_words", info.vocabulary_words);
    fields.add("vocabulary_levels", info.vocabulary_levels);
  }
}

}  // namespace binbow::cli
