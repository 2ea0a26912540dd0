// Uses the installed binbow::core: builds a small vocabulary and transforms.
#include <binbow/vocabulary.h>

#include <cstdio>
#include <random>
#include <vector>

static_assert(__cplusplus >= 201703L, "binbow::core must bring C++17 to its consumers");

int main() {
  std::mt19937 rng(1);
  binbow::DescriptorMatrix training(2000, 32);
  for (std::size_t i = 0; i < training.rows() * 32; ++i) training.data()[i] = rng() & 0xff;
  binbow::BuildOptions options;
  options.branching = 4;
  options.levels = 3;
  // Twenty "images" of 100 descriptors: IDF weights need more than one image.
  std::vector<binbow::DescriptorView> images;
  for (std::size_t i = 0; i < 20; ++i) images.push_back(training.view().slice(i * 100, 100));
  const auto vocabulary = binbow::Vocabulary::build(images, options);
  binbow::BowVector bow;
  vocabulary.transform(training.view().slice(0, 100), bow);
  std::printf("words: %zu, bow entries: %zu\n", vocabulary.word_count(), bow.size());
  return bow.empty() ? 1 : 0;
}
