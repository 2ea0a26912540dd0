// Tree checks shared by several readers.
#pragma once

#include <cstddef>
#include <cstdint>
#include <string>
#include <utility>
#include <vector>

#include "binbow/vocabulary.h"

namespace binbow::detail {

// The branching factor, depth, scoring and weighting codes a header states,
// against what binbow supports; throws FileError(name, "<where>: ...") naming
// the first value out of range.
void check_header_values(const std::string& name, const std::string& where, std::int64_t branching,
                         std::int64_t levels, std::int64_t scoring, std::int64_t weighting);

// Every parent must be an earlier node, a node flagged as a leaf must have no
// children and an inner one must have some. Zeroes inner nodes' weights.
// Errors name the node as "<unit> <node + unit_offset>" ("line 12").
void check_listed_tree(VocabularyTree& tree, const std::vector<std::uint8_t>& leaf_flags,
                       const std::string& name, const char* unit, std::size_t unit_offset);

// For formats that list nodes with explicit ids and a separate word list of
// (word id, leaf node id) pairs (DBoW2/DBoW3 YAML, DBoW3 binary): checks the
// list names every leaf exactly once and returns whether its word ids equal
// binbow's (leaves numbered in node order). Zeroes inner nodes' weights.
// Parents must already be in range.
bool check_word_list(VocabularyTree& tree,
                     const std::vector<std::pair<std::uint32_t, std::uint32_t>>& words,
                     const std::string& name);

// The weights of the tree's words (its leaves), as vocabulary/word_weights.h
// wants them; inner nodes' weights must already be zeroed. Throws
// FileError(name, ...).
void check_word_weights(const VocabularyTree& tree, const std::string& name);

}  // namespace binbow::detail
