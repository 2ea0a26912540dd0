// load_vocabulary / save_vocabulary with the details `binbow convert` and
// `binbow info` report: the format found, the descriptor spelling of DBoW2
// YAML, whether the file's word ids are binbow's.
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
};

LoadedVocabulary load_vocabulary_with_details(const std::string& path, VocabularyFormat format);
void save_vocabulary_as(const Vocabulary& vocabulary, const std::string& path,
                        VocabularyFormat format, DescriptorText descriptor_text);

}  // namespace binbow::detail
