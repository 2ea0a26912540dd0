// The YAML binbow reads: a flat mapping whose values are scalars or
// sequences of scalars (loop detector parameters, BRIEF patterns), as OpenCV
// writes them. OpenCV's own YAML parser hangs or crashes on some small
// malformed files (found by fuzzing), so these files are parsed here, in one
// linear pass, and anything beyond that subset is an error naming the line.
#pragma once

#include <string>
#include <string_view>

#include <nlohmann/json.hpp>

namespace binbow::vision {

// `text` as a JSON object: integers, finite reals,
// true/false and strings ("quoted", 'quoted' or plain) as JSON values; flow ("[1, 2]") and
// block ("- 1" lines) sequences as arrays of those. A "%YAML" directive,
// "---", blank lines and # comments are skipped. Throws FileError(path, ...)
// naming the line for anything else: nested mappings or sequences, a
// repeated key, an unclosed bracket or quote, non-finite numbers (.inf, .nan).
nlohmann::json parse_flat_yaml(std::string_view text, const std::string& path);

}  // namespace binbow::vision
