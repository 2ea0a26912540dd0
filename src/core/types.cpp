#include "binbow/types.h"

#include <algorithm>
#include <cctype>

#include "binbow/error.h"

namespace binbow {
namespace {

const char* const kWeightingNames[] = {"tf-idf", "tf", "idf", "binary"};
const char* const kScoringNames[] = {"l1",         "l2", "chi-square", "kl", "bhattacharyya",
                                     "dot-product"};

std::string normalise(std::string name) {
  for (char& c : name)
    c = c == '_' ? '-' : static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return name;
}

template <std::size_t N>
int find_name(const char* const (&names)[N], const std::string& name) {
  const std::string wanted = normalise(name);
  for (std::size_t i = 0; i < N; ++i)
    if (wanted == names[i]) return static_cast<int>(i);
  return -1;
}

template <std::size_t N>
std::string list(const char* const (&names)[N]) {
  std::string out;
  for (std::size_t i = 0; i < N; ++i) out += (i ? ", " : "") + std::string(names[i]);
  return out;
}

}  // namespace

const char* to_string(Weighting weighting) {
  const auto i = static_cast<std::size_t>(weighting);
  return i < std::size(kWeightingNames) ? kWeightingNames[i] : "invalid";
}

const char* to_string(Scoring scoring) {
  const auto i = static_cast<std::size_t>(scoring);
  return i < std::size(kScoringNames) ? kScoringNames[i] : "invalid";
}

Weighting parse_weighting(const std::string& name) {
  if (name == "tfidf" || name == "TFIDF") return Weighting::kTfIdf;
  const int i = find_name(kWeightingNames, name);
  if (i < 0)
    throw InvalidArgument("unknown weighting '" + name + "' (expected one of " +
                          list(kWeightingNames) + ")");
  return static_cast<Weighting>(i);
}

Scoring parse_scoring(const std::string& name) {
  const int i = find_name(kScoringNames, name);
  if (i < 0)
    throw InvalidArgument("unknown scoring '" + name + "' (expected one of " + list(kScoringNames) +
                          ")");
  return static_cast<Scoring>(i);
}

Weighting weighting_from_code(int code) {
  if (code < 0 || code >= static_cast<int>(std::size(kWeightingNames)))
    throw InvalidArgument("weighting code " + std::to_string(code) + " is out of range 0..3");
  return static_cast<Weighting>(code);
}

Scoring scoring_from_code(int code) {
  if (code < 0 || code >= static_cast<int>(std::size(kScoringNames)))
    throw InvalidArgument("scoring code " + std::to_string(code) + " is out of range 0..5");
  return static_cast<Scoring>(code);
}

}  // namespace binbow
