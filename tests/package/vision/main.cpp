// Uses the installed binbow::vision: the installed ORB vocabulary and sample
// sequence, ORB features, the database and the loop detector.
#include <binbow/database.h>
#include <binbow/formats.h>
#include <binbow/loop/loop_detector.h>
#include <binbow/vision/features.h>
#include <binbow/vision/image_source.h>

#include <cstdio>
#include <string>

int main(int argc, char** argv) {
  if (argc != 3) {
    std::fprintf(stderr, "usage: consumer VOCABULARY.bbw SAMPLE_FOLDER\n");
    return 2;
  }
  const binbow::Vocabulary vocabulary = binbow::load_vocabulary(argv[1]);
  const auto orb = binbow::vision::make_orb_extractor();
  binbow::Database database(vocabulary);
  binbow::loop::LoopDetector detector(vocabulary);
  binbow::vision::ImageSource images({argv[2]});
  binbow::vision::Frame frame;
  std::size_t frames = 0;
  std::size_t loops = 0;
  while (images.next(frame)) {
    const auto features = orb->extract(frame.image);
    database.add(features.descriptors);
    if (detector.process(features).detection()) ++loops;
    ++frames;
  }
  std::printf("frames: %zu, database entries: %zu, loops: %zu\n", frames, database.size(), loops);
  return frames > 0 && database.size() == frames && loops > 0 ? 0 : 1;
}
