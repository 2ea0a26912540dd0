// Uses the installed binbow::core: builds a small vocabulary and transforms.
#include <binbow/vocabulary.h>

#include <cstdio>
#include <random>

int main() {
  std::mt19937 rng(1);
  binbow::DescriptorMatrix training(2000, 32);
  for (std::size_t i = 0; i < training.rows() * 32; ++i) training.data()[i] = rng() & 0xff;
  binbow::BuildOptions options;
  options.branching = 4;
  options.levels = 3;
  const auto vocabulary = binbow::Vocabulary::build({training.view()}, options);
  binbow::BowVector bow;
  vocabulary.transform(training.view().slice(0, 100), bow);
  std::printf("words: %zu, bow entries: %zu\n", vocabulary.word_count(), bow.size());
  return bow.empty() ? 1 : 0;
}
