// load_vocabulary / save_vocabulary with the details `binbow convert` and
// `binbow info` report: the format found, the descriptor spelling of DBoW2
// YAML, whether the file's word ids are binbow's, and the warning of a file
// that does not record the extractor its vocabulary was trained on.
#pragma once

#include <string>

#include "binbow/formats.h"
#include "binbow/vocabulary.h"
#include "formats/codecs.h"

namespace binbow::detail {

struct LoadedVocabulary {
  Vocabulary vocabulary;
  VocabularyFormat format = VocabularyFormat::kAuto;
  bool compressed = false;  // gzip
  DescriptorText descriptor_text = DescriptorText::kBytes;
  bool word_ids_match = true;
  // Set when the file does not record the extractor and none was given: what
  // was assumed, naming the file and how to say otherwise; load_vocabulary
  // passes it to the warning handler, the commands print it once.
  std::string descriptor_warning;
};

// Which extractor a vocabulary read from a file that does not record one
// (every format but a named .bbw) is taken to be trained on, and how.
enum class UnrecordedDescriptor {
  kAssume,     // `descriptor` when given; else VINS brief, 256-bit orb, with a warning
  kLeaveBlank  // `descriptor` when given; else VINS brief, nothing, no warning (DBoW2 API)
};

// `descriptor` ("" for none) is the extractor the caller knows the file's
// vocabulary was trained on; a file that records one keeps its own.
LoadedVocabulary load_vocabulary_with_details(
    const std::string& path, VocabularyFormat format, const std::string& descriptor = "",
    UnrecordedDescriptor unrecorded = UnrecordedDescriptor::kAssume);
void save_vocabulary_as(const Vocabulary& vocabulary, const std::string& path,
                        VocabularyFormat format, DescriptorText descriptor_text);

}  // namespace binbow::detail
