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
  kOrbSlamBinary,  // the binary ORBvoc.bin of ORB-SLAM2 pull request 21 and its forks, .bin
  kDbow3,          // DBoW3 binary .dbow3
  kFbow,           // fbow .fbow
  kVinsBinary,     // VINS-Mono/VINS-Fusion brief_k10L6.bin (256-bit descriptors only), .vins.bin
};

// "bbw", "dbow2", "orbslam-text", "orbslam-binary", "dbow3", "fbow", "vins"
// ("auto" for kAuto).
const char* to_string(VocabularyFormat format);
// Accepts the names above; throws InvalidArgument listing them.
VocabularyFormat parse_vocabulary_format(const std::string& name);
// The format of an existing file, from its first bytes, then its extension.
// ORB-SLAM and VINS binary files have no magic: each is recognised by its
// header predicting the file's exact size (inside a plain .gz the size is
// unknown until decompressed, so there the extension decides: .bin is
// ORB-SLAM, .vins.bin VINS; load_vocabulary decompresses and looks again).
// Every format may be gzip-compressed or the first file of a .tar.gz; the
// format is then the one of the file inside. Throws FileError if the file
// cannot be read or nothing matches; when nothing matches, its problem()
// begins with kUnknownVocabularyFormat, so that the CLI and Python can say how
// to name the format in their own terms (--from, format=).
VocabularyFormat detect_vocabulary_format(const std::string& path);
inline constexpr char kUnknownVocabularyFormat[] = "unknown vocabulary format";
// The format an output file name asks for: .bbw, .txt, .bin (ORB-SLAM binary),
// .vins.bin (VINS binary), .yml/.yaml/.yml.gz/.voc.gz (DBoW2 YAML), .dbow3,
// .fbow; any of them may be followed by .gz (written gzip-compressed). Throws
// InvalidArgument for other extensions.
VocabularyFormat format_for_output(const std::string& path);

// Reads a vocabulary in any supported format. Throws FileError naming the file
// and the problem for anything unreadable, truncated or inconsistent.
//
// The extractor the vocabulary was trained on (Vocabulary::descriptor) is
// recorded by .bbw files only. A .bbw that records it keeps its own;
// otherwise `descriptor` ("orb", "brief", ...; "" when unknown) is taken.
// Without it, a VINS file is brief (VINS computes BRIEF descriptors), and any
// other file is assumed to be orb when its descriptors are 256-bit (left
// without a name otherwise), with a warning through the warning handler
// (set_warning_handler) naming the file, the assumption and how to give the
// right one. InvalidArgument for a `descriptor` that is not a valid name
// (VocabularyTree::descriptor).
Vocabulary load_vocabulary(const std::string& path,
                           VocabularyFormat format = VocabularyFormat::kAuto,
                           const std::string& descriptor = "");
// Writes atomically (temporary file, then rename; missing folders are made);
// kAuto: by extension. DBoW2
// YAML is written with decimal-byte descriptors (DBoW2's FORB) unless
// `brief_bit_strings` asks for FBrief's 0/1 strings (DLoopDetector, VINS).
// fbow files keep neither L nor the weighting and scoring types (read back as
// the tree's depth, tf-idf, L1); VINS files take 256-bit descriptors only
// (InvalidArgument otherwise); docs/formats.md lists what each format keeps.
void save_vocabulary(const Vocabulary& vocabulary, const std::string& path,
                     VocabularyFormat format = VocabularyFormat::kAuto,
                     bool brief_bit_strings = false);

}  // namespace binbow
