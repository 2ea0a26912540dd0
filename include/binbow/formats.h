// Reading and writing vocabularies in every format users have.
#pragma once

#include <string>

#include "binbow/vocabulary.h"

namespace binbow {

enum class VocabularyFormat {
  kAuto,           // detect: by content (magic bytes, gzip header, first line), then extension
  kBinbow,         // .bbw, binbow's own binary format
  kDbow2Yaml,      // DBoW2 YAML through OpenCV FileStorage conventions, .yml / .yml.gz / .voc.gz
  kOrbSlamText,    // ORB-SLAM2/3 ORBvoc.txt
  kDbow3,          // DBoW3 binary .dbow3
  kFbow,           // fbow .fbow
};

// "bbw", "dbow2", "orbslam-text", "dbow3", "fbow" ("auto" for kAuto).
const char* to_string(VocabularyFormat format);
// Accepts the names above; throws InvalidArgument listing them.
VocabularyFormat parse_vocabulary_format(const std::string& name);
// The format of an existing file, from its first bytes, then its extension.
// Throws FileError if the file cannot be read or nothing matches.
VocabularyFormat detect_vocabulary_format(const std::string& path);
// The format an output file name asks for: .bbw, .txt, .yml/.yml.gz/.voc.gz,
// .dbow3, .fbow. Throws InvalidArgument for other extensions.
VocabularyFormat format_for_output(const std::string& path);

// Reads a vocabulary in any supported format. Throws FileError naming the file
// and the problem for anything unreadable, truncated or inconsistent.
Vocabulary load_vocabulary(const std::string& path, VocabularyFormat format = VocabularyFormat::kAuto);
// Writes atomically (temporary file, then rename); kAuto: by extension.
void save_vocabulary(const Vocabulary& vocabulary, const std::string& path,
                     VocabularyFormat format = VocabularyFormat::kAuto);

}  // namespace binbow
