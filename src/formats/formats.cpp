// Format names, detection, and the load/save entry points that dispatch to
// the codecs.
#include "binbow/formats.h"

#include <algorithm>
#include <cctype>
#include <cstring>
#include <utility>

#include "binbow/error.h"
#include "core/file_io.h"
#include "core/little_endian.h"
#include "core/warnings.h"
#include "formats/codecs.h"
#include "formats/container.h"
#include "formats/gzip.h"
#include "formats/loader.h"
#include "formats/text_numbers.h"
#include "formats/tree_checks.h"
#include "vocabulary/vocabulary_block.h"

namespace binbow {

namespace {

constexpr std::uint64_t kDbow3Signature = 88877711233ull;
constexpr std::uint64_t kFbowSignature = 55824124ull;

struct FormatName {
  VocabularyFormat format;
  const char* name;
};
constexpr FormatName kFormatNames[] = {
    {VocabularyFormat::kAuto, "auto"},
    {VocabularyFormat::kBinbow, "bbw"},
    {VocabularyFormat::kDbow2Yaml, "dbow2"},
    {VocabularyFormat::kOrbSlamText, "orbslam-text"},
    {VocabularyFormat::kOrbSlamBinary, "orbslam-binary"},
    {VocabularyFormat::kDbow3, "dbow3"},
    {VocabularyFormat::kFbow, "fbow"},
    {VocabularyFormat::kVinsBinary, "vins"},
};

bool ends_with(const std::string& text, const char* suffix) {
  const std::size_t n = std::strlen(suffix);
  if (text.size() < n) return false;
  for (std::size_t i = 0; i < n; ++i)
    if (std::tolower(static_cast<unsigned char>(text[text.size() - n + i])) != suffix[i])
      return false;
  return true;
}

std::string without_suffix(const std::string& path, const char* suffix) {
  return ends_with(path, suffix) ? path.substr(0, path.size() - std::strlen(suffix)) : path;
}

VocabularyFormat format_from_plain_extension(const std::string& path) {
  if (ends_with(path, ".bbw")) return VocabularyFormat::kBinbow;
  if (ends_with(path, ".txt")) return VocabularyFormat::kOrbSlamText;
  if (ends_with(path, ".vins.bin")) return VocabularyFormat::kVinsBinary;
  if (ends_with(path, ".bin")) return VocabularyFormat::kOrbSlamBinary;
  if (ends_with(path, ".yml") || ends_with(path, ".yaml") || ends_with(path, ".yml.gz") ||
      ends_with(path, ".yaml.gz") || ends_with(path, ".voc.gz"))
    return VocabularyFormat::kDbow2Yaml;
  if (ends_with(path, ".dbow3")) return VocabularyFormat::kDbow3;
  if (ends_with(path, ".fbow")) return VocabularyFormat::kFbow;
  return VocabularyFormat::kAuto;
}

// The format an extension suggests, kAuto for none. `.gz`, `.tar.gz` and
// `.tgz` are looked through (ORBvoc.txt.tar.gz is ORB-SLAM text).
VocabularyFormat format_from_extension(const std::string& path) {
  const VocabularyFormat format = format_from_plain_extension(path);
  if (format != VocabularyFormat::kAuto) return format;
  if (ends_with(path, ".tgz")) return format_from_plain_extension(without_suffix(path, ".tgz"));
  if (ends_with(path, ".gz"))
    return format_from_plain_extension(without_suffix(without_suffix(path, ".gz"), ".tar"));
  return VocabularyFormat::kAuto;
}

// A first line of exactly four unsigned integers: the ORB-SLAM text header.
bool looks_like_orbslam_text(const std::uint8_t* data, std::size_t size) {
  const char* p = reinterpret_cast<const char*>(data);
  const char* end = p + std::min<std::size_t>(size, 256);
  const char* line_end = static_cast<const char*>(std::memchr(p, '\n', end - p));
  if (line_end == nullptr) line_end = end;
  std::uint64_t value = 0;
  for (int i = 0; i < 4; ++i)
    if (!detail::parse_token(p, line_end, value)) return false;
  return detail::skip_blanks(p, line_end) == line_end;
}

bool looks_like_yaml(const std::uint8_t* data, std::size_t size) {
  const std::string_view head(reinterpret_cast<const char*>(data), std::min<std::size_t>(size, 64));
  return head.rfind("%YAML", 0) == 0 || head.rfind("---", 0) == 0 ||
         head.rfind("vocabulary:", 0) == 0;
}

// ORB-SLAM binary has no magic: its 24-byte header must predict the file size.
bool looks_like_orbslam_binary(const std::uint8_t* data, std::size_t size, std::size_t file_size) {
  if (size < 24) return false;
  const std::uint64_t nodes = detail::load_le<std::uint32_t>(data);
  const std::uint64_t node_size = detail::load_le<std::uint32_t>(data + 4);
  const std::uint32_t branching = detail::load_le<std::uint32_t>(data + 8);
  const std::uint32_t levels = detail::load_le<std::uint32_t>(data + 12);
  return nodes >= 1 && node_size >= 10 && node_size <= 9 + detail::kMaxCodeSize && branching >= 1 &&
         branching <= detail::kMaxBranching && levels >= 1 && levels <= detail::kMaxLevels &&
         24 + (nodes - 1) * node_size == file_size;
}

// VINS binary has no magic either: its counts must give the file size
// exactly, and its first record must start with a node id in 1..node_count.
// An ORB-SLAM binary file's first record starts with node 1's parent, the
// root 0, so no file passes both checks.
bool looks_like_vins_binary(const std::uint8_t* data, std::size_t size, std::size_t file_size) {
  if (size < 28) return false;
  const std::int32_t branching = detail::load_le<std::int32_t>(data);
  const std::int32_t levels = detail::load_le<std::int32_t>(data + 4);
  const std::int32_t scoring = detail::load_le<std::int32_t>(data + 8);
  const std::int32_t weighting = detail::load_le<std::int32_t>(data + 12);
  const std::int32_t nodes = detail::load_le<std::int32_t>(data + 16);
  const std::int32_t words = detail::load_le<std::int32_t>(data + 20);
  const std::int32_t first_id = detail::load_le<std::int32_t>(data + 24);
  return branching >= 1 && static_cast<std::uint32_t>(branching) <= detail::kMaxBranching &&
         levels >= 1 && static_cast<std::uint32_t>(levels) <= detail::kMaxLevels && scoring >= 0 &&
         scoring <= static_cast<int>(Scoring::kDotProduct) && weighting >= 0 &&
         weighting <= static_cast<int>(Weighting::kBinary) && nodes >= 1 && words >= 1 &&
         words <= nodes && first_id >= 1 && first_id <= nodes &&
         detail::vins_binary_size(nodes, words) == file_size;
}

// `data` holds the first `size` bytes of a file of `file_size` bytes (0: unknown).
VocabularyFormat format_from_content(const std::uint8_t* data, std::size_t size,
                                     std::size_t file_size) {
  if (size >= 8 && std::memcmp(data, detail::bbw::kMagic, 8) == 0) return VocabularyFormat::kBinbow;
  if (detail::is_gzip(data, size)) return VocabularyFormat::kDbow2Yaml;
  if (size >= 8 && detail::load_le<std::uint64_t>(data) == kDbow3Signature)
    return VocabularyFormat::kDbow3;
  if (size >= 8 && detail::load_le<std::uint64_t>(data) == kFbowSignature)
    return VocabularyFormat::kFbow;
  if (looks_like_yaml(data, size)) return VocabularyFormat::kDbow2Yaml;
  if (looks_like_orbslam_text(data, size)) return VocabularyFormat::kOrbSlamText;
  if (looks_like_vins_binary(data, size, file_size)) return VocabularyFormat::kVinsBinary;
  if (looks_like_orbslam_binary(data, size, file_size)) return VocabularyFormat::kOrbSlamBinary;
  return VocabularyFormat::kAuto;
}

std::string format_list() {
  std::string names;
  for (const FormatName& entry : kFormatNames) {
    if (!names.empty()) names += ", ";
    names += entry.name;
  }
  return names;
}

}  // namespace

const char* to_string(VocabularyFormat format) {
  for (const FormatName& entry : kFormatNames)
    if (entry.format == format) return entry.name;
  return "unknown";
}

VocabularyFormat parse_vocabulary_format(const std::string& name) {
  std::string lower(name);
  for (char& c : lower) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  std::replace(lower.begin(), lower.end(), '_', '-');
  for (const FormatName& entry : kFormatNames)
    if (lower == entry.name) return entry.format;
  throw InvalidArgument("unknown vocabulary format '" + name + "'; expected one of " +
                        format_list());
}

VocabularyFormat detect_vocabulary_format(const std::string& path) {
  const detail::MappedFile file(path);
  std::size_t contained_size = 0;
  const std::vector<std::uint8_t> head =
      detail::contained_head(file.data(), file.size(), contained_size);
  const VocabularyFormat by_content = format_from_content(head.data(), head.size(), contained_size);
  if (by_content != VocabularyFormat::kAuto) return by_content;
  const VocabularyFormat by_name = format_from_extension(path);
  if (by_name != VocabularyFormat::kAuto) return by_name;
  throw FileError(path,
                  "unknown vocabulary format: neither its first bytes nor its extension "
                  "match " +
                      format_list() + "; name its format");
}

VocabularyFormat format_for_output(const std::string& path) {
  if (ends_with(path, ".tgz") || ends_with(path, ".tar.gz"))
    throw InvalidArgument("'" + path +
                          "': binbow reads vocabularies inside tar archives but "
                          "does not write them; name the output .gz to compress it");
  const VocabularyFormat format = format_from_extension(path);
  if (format == VocabularyFormat::kAuto)
    throw InvalidArgument("cannot tell the vocabulary format from the name '" + path +
                          "': use .bbw, .txt (ORB-SLAM text), .bin (ORB-SLAM binary), "
                          ".vins.bin (VINS binary), .yml, .yml.gz or .voc.gz (DBoW2 YAML), "
                          ".dbow3 or .fbow (any of them may end in .gz), or --to");
  return format;
}

namespace detail {

ChildLists child_lists(const VocabularyTree& tree) {
  const std::size_t nodes = tree.node_count();
  ChildLists lists;
  lists.first.assign(nodes + 1, 0);
  for (std::size_t node = 1; node < nodes; ++node) ++lists.first[tree.parent[node] + 1];
  for (std::size_t node = 0; node < nodes; ++node) lists.first[node + 1] += lists.first[node];
  lists.child.resize(nodes > 0 ? nodes - 1 : 0);
  std::vector<std::uint32_t> next(lists.first.begin(), lists.first.end() - 1);
  for (std::size_t node = 1; node < nodes; ++node)
    lists.child[next[tree.parent[node]]++] = static_cast<NodeId>(node);
  return lists;
}

Vocabulary vocabulary_from_parsed(const ParsedVocabulary& parsed, const std::string& name) {
  check_word_weights(parsed.tree, name);
  try {
    return Vocabulary::from_tree(parsed.tree);
  } catch (const InvalidArgument& e) {
    throw FileError(name, e.what());
  }
}

ParsedVocabulary parse_vocabulary_bytes(VocabularyFormat format, const std::uint8_t* data,
                                        std::size_t size, const std::string& name) {
  switch (format) {
    case VocabularyFormat::kDbow2Yaml:
      return parse_dbow2_yaml(data, size, name);
    case VocabularyFormat::kOrbSlamText:
      return parse_orbslam_text(data, size, name);
    case VocabularyFormat::kOrbSlamBinary:
      return parse_orbslam_binary(data, size, name);
    case VocabularyFormat::kDbow3:
      return parse_dbow3_binary(data, size, name);
    case VocabularyFormat::kFbow:
      return parse_fbow(data, size, name);
    case VocabularyFormat::kVinsBinary:
      return parse_vins_binary(data, size, name);
    default:
      throw InvalidArgument(std::string("no tree parser for format ") + to_string(format));
  }
}

namespace {

// The extractor of a vocabulary whose file does not record one (see
// UnrecordedDescriptor); sets `warning` when it is an assumption or unknown.
std::string unrecorded_descriptor(const std::string& path, VocabularyFormat format,
                                  std::size_t code_size, const std::string& given,
                                  UnrecordedDescriptor unrecorded, std::string& warning) {
  if (!given.empty()) return given;
  // VINS computes BRIEF descriptors: its files hold BRIEF words by definition.
  if (format == VocabularyFormat::kVinsBinary) return "brief";
  if (unrecorded == UnrecordedDescriptor::kLeaveBlank) return "";
  const std::string what =
      path + ": " +
      (format == VocabularyFormat::kBinbow ? std::string("the file")
                                           : std::string(to_string(format)) + " files") +
      " do" + (format == VocabularyFormat::kBinbow ? "es" : "") + " not store the descriptor kind";
  // ORB is binbow's default extractor and the one of ORB-SLAM and most DBoW2
  // files; any other length is not ORB's, and nothing can be assumed.
  if (code_size == 32) {
    warning = what +
              "; assuming orb (give --descriptor brief, or descriptor=\"brief\" in Python, if "
              "it is BRIEF)";
    return "orb";
  }
  warning = what + ", and its " + std::to_string(code_size * 8) +
            "-bit descriptors are not orb's: give it with --descriptor NAME (descriptor=\"NAME\" "
            "in Python)";
  return "";
}

}  // namespace

LoadedVocabulary load_vocabulary_with_details(const std::string& path, VocabularyFormat format,
                                              const std::string& descriptor,
                                              UnrecordedDescriptor unrecorded) {
  // Checked first: a bad name is the caller's mistake, not the file's.
  if (!valid_descriptor_name(descriptor))
    throw InvalidArgument("descriptor name \"" + descriptor + "\" is not " + kDescriptorNameRule);
  LoadedVocabulary loaded;
  // A .bbw records the extractor, or says nothing: only then does the rest apply.
  const auto name_unrecorded = [&] {
    if (!loaded.vocabulary.descriptor().empty()) return;
    const std::string name =
        unrecorded_descriptor(path, VocabularyFormat::kBinbow, loaded.vocabulary.code_size(),
                              descriptor, unrecorded, loaded.descriptor_warning);
    if (!name.empty()) loaded.vocabulary = loaded.vocabulary.with_descriptor(name);
  };
  const MappedFile file(path);
  if (!is_gzip(file.data(), file.size())) {
    if (format == VocabularyFormat::kAuto) format = detect_vocabulary_format(path);
    loaded.format = format;
    if (format == VocabularyFormat::kBinbow) {
      loaded.vocabulary = Vocabulary::load(path);  // memory-mapped
      name_unrecorded();
      return loaded;
    }
  }
  const ContainedFile contained = open_contained(file.data(), file.size(), path);
  loaded.compressed = contained.gzip;
  if (format == VocabularyFormat::kAuto) {
    format = format_from_content(contained.data, contained.size, contained.size);
    if (format == VocabularyFormat::kAuto) format = format_from_extension(path);
    if (format == VocabularyFormat::kAuto)
      throw FileError(path,
                      "unknown vocabulary format inside the compressed file; name its format");
  }
  loaded.format = format;
  if (format == VocabularyFormat::kBinbow) {
    loaded.vocabulary = Vocabulary::deserialize(contained.data, contained.size, path);
    name_unrecorded();
    return loaded;
  }
  ParsedVocabulary parsed = parse_vocabulary_bytes(format, contained.data, contained.size, path);
  loaded.descriptor_text = parsed.descriptor_text;
  loaded.word_ids_match = parsed.word_ids_match;
  // No other format records the extractor: named here, before the tree
  // becomes a vocabulary, so that nothing is copied to name it.
  parsed.tree.descriptor = unrecorded_descriptor(path, format, parsed.tree.code_size, descriptor,
                                                 unrecorded, loaded.descriptor_warning);
  loaded.vocabulary = vocabulary_from_parsed(parsed, path);
  return loaded;
}

void save_vocabulary_as(const Vocabulary& vocabulary, const std::string& path,
                        VocabularyFormat format, DescriptorText descriptor_text) {
  if (vocabulary.empty()) throw InvalidArgument("cannot save an empty vocabulary to " + path);
  if (format == VocabularyFormat::kAuto) format = format_for_output(path);
  if (format == VocabularyFormat::kVinsBinary && vocabulary.code_size() != kVinsCodeSize)
    throw InvalidArgument("cannot write " + path +
                          " as a VINS vocabulary: the format holds 256-bit descriptors only, "
                          "this vocabulary has " +
                          std::to_string(vocabulary.code_size() * 8) + "-bit ones");
  const bool compress = ends_with(path, ".gz");
  if (format == VocabularyFormat::kBinbow && !compress) {
    vocabulary.save(path);
    return;
  }
  const VocabularyTree tree = vocabulary.to_tree();
  std::vector<std::uint8_t> bytes;
  switch (format) {
    case VocabularyFormat::kBinbow:
      bytes = vocabulary.serialize();
      break;
    case VocabularyFormat::kDbow2Yaml:
      bytes = format_dbow2_yaml(tree, descriptor_text);
      break;
    case VocabularyFormat::kOrbSlamText:
      bytes = format_orbslam_text(tree);
      break;
    case VocabularyFormat::kOrbSlamBinary:
      bytes = format_orbslam_binary(tree);
      break;
    case VocabularyFormat::kDbow3:
      bytes = format_dbow3_binary(tree);
      break;
    case VocabularyFormat::kFbow:
      bytes = format_fbow(tree);
      break;
    case VocabularyFormat::kVinsBinary:
      bytes = format_vins_binary(tree);
      break;
    default:
      throw InvalidArgument(std::string("cannot write format ") + to_string(format));
  }
  if (compress) bytes = gzip(bytes);
  write_file_atomically(path, bytes.data(), bytes.size());
}

}  // namespace detail

Vocabulary load_vocabulary(const std::string& path, VocabularyFormat format,
                           const std::string& descriptor) {
  detail::LoadedVocabulary loaded = detail::load_vocabulary_with_details(path, format, descriptor);
  if (!loaded.descriptor_warning.empty()) detail::warn(loaded.descriptor_warning);
  return std::move(loaded.vocabulary);
}

void save_vocabulary(const Vocabulary& vocabulary, const std::string& path, VocabularyFormat format,
                     bool brief_bit_strings) {
  detail::save_vocabulary_as(
      vocabulary, path, format,
      brief_bit_strings ? detail::DescriptorText::kBits : detail::DescriptorText::kBytes);
}

}  // namespace binbow
