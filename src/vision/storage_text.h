// Text handed to OpenCV's FileStorage. Its YAML, JSON and XML parsers recurse
// once per nesting level and allocate per node without limits, so a small
// file nested tens of thousands of levels deep overflows the stack. Every
// FileStorage input is read through here first: bounded in size (gzip
// included) and in nesting depth, then parsed from memory.
#pragma once

#include <cstddef>
#include <cstdint>
#include <string>
#include <string_view>

namespace binbow::vision {

// Deepest nesting of mappings and sequences accepted; binbow's files use 2.
inline constexpr std::size_t kMaxStorageNesting = 64;

// An upper bound of the nesting depth of YAML, JSON or XML text, without
// parsing it: XML counts open elements; YAML and JSON count open flow
// brackets plus block indentation levels plus "- " and "? " entries opened on
// a line. Linear in the text, never less than the depth a parser sees.
std::size_t nesting_depth_bound(std::string_view text);

// Throws FileError(path, ...) when `text` holds a NUL byte or
// nesting_depth_bound(text) exceeds kMaxStorageNesting.
void check_storage_text(std::string_view text, const std::string& path);

// The FileStorage format flag (FORMAT_XML, FORMAT_JSON or FORMAT_YAML) for
// `text` read from `path`: OpenCV's rule (the name's extension, a trailing
// .gz ignored), else the first character ('<' XML, '{' JSON, else YAML).
int storage_format(std::string_view text, const std::string& path);

// The text of `path` (a regular file, gzip-compressed or not), refusing more
// than `max_bytes` bytes before or after decompression, NUL bytes, and
// nesting deeper than kMaxStorageNesting (FileError naming the file). Give it to
// cv::FileStorage with READ | MEMORY | storage_format(text, path).
std::string read_storage_text(const std::string& path, std::uint64_t max_bytes);

}  // namespace binbow::vision
