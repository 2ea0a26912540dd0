// What every vocabulary reader checks of the word weights. Words are scored
// with weight × (term frequency or 1) under every weighting, and a weight of
// 0 marks a stop word, which every weighting skips: a negative weight has no
// meaning in any of them (an IDF, log(N / N_i), is never negative), and a
// vocabulary whose words all weigh 0 turns every image into an empty BoW
// vector, which scores 0 against everything (Vocabulary::build refuses to
// make one).
#pragma once

#include <cmath>
#include <cstddef>
#include <string>

namespace binbow::detail {

// Empty when the `count` weights `weight(i)` are usable; otherwise the
// problem, naming the first bad one as "<unit> i" ("word 7", "node 12").
template <class WeightOf>
std::string word_weights_problem(std::size_t count, const WeightOf& weight, const char* unit) {
  bool any_positive = false;
  for (std::size_t i = 0; i < count; ++i) {
    const float w = weight(i);
    const std::string which = std::string("the weight of ") + unit + " " + std::to_string(i);
    if (!std::isfinite(w)) return which + " is not a finite number";
    if (w < 0)
      return which + " is negative (" + std::to_string(w) +
             "); weights are 0 (a stop word) or positive";
    any_positive = any_positive || w > 0;
  }
  if (count > 0 && !any_positive)
    return "every word weighs 0 (all stop words): every image would become an empty BoW vector "
           "and no two images could be told apart";
  return {};
}

}  // namespace binbow::detail
