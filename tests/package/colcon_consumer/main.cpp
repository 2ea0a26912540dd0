// A colcon workspace package using binbow: loads the vocabulary binbow
// installs (its path is the argument) and prints its size.
#include <binbow/vocabulary.h>

#include <cstdio>
#include <exception>

int main(int argc, char** argv) {
  if (argc != 2) {
    std::fprintf(stderr, "usage: binbow_colcon_consumer VOCABULARY.bbw\n");
    return 2;
  }
  try {
    const auto vocabulary = binbow::Vocabulary::load(argv[1]);
    std::printf("words: %zu, levels: %u\n", vocabulary.word_count(), vocabulary.levels());
    return vocabulary.word_count() > 0 ? 0 : 1;
  } catch (const std::exception& error) {
    std::fprintf(stderr, "binbow_colcon_consumer: error: %s\n", error.what());
    return 1;
  }
}
