// What every vocabulary reader checks of the word weights. Words are scored
// with weight × (term frequency or 1) under every weighting, and a weight of
// 0 marks a stop word, which every weighting skips: a negative weight has no
// meaning in any of them (an IDF, log(N / N_i), is never negative). A
// vocabulary whose words all weigh 0 is legal but useless (every image becomes
// an empty BoW vector): readers accept it, so that databases and states saved
// with one still load, and the commands warn (Vocabulary::build refuses to
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
  // The message is made only for a bad weight: made for every word, it was
  // most of the time a .bbw took to load.
  auto which = [&](std::size_t i) {
    return std::string("the weight of ") + unit + " " + std::to_string(i);
  };
  for (std::size_t i = 0; i < count; ++i) {
    const float w = weight(i);
    if (!std::isfinite(w)) return which(i) + " is not a finite number";
    if (w < 0)
      return which(i) + " is negative (" + std::to_string(w) +
             "); weights are 0 (a stop word) or positive";
  }
  return {};
}

}  // namespace binbow::detail
