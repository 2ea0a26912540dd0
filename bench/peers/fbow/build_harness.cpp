// binbow against fbow building a vocabulary: k=10 L=5 from the same 150,000
// real ORB descriptors (peers::training_set), binbow on one and two threads,
// fbow's VocabularyCreator (its default 11 iterations per node) on one and
// two, one builder after the other in each repetition, the first
// alternating; process CPU time (all threads). fbow's words and quantisation
// error are not read back (its API gives neither directly).
//
//   build_harness [--reps N]
#include <cstdio>
#include <cstdlib>
#include <string>
#include <vector>

#include "build_table.h"
#include "fbow.h"
#include "vocabulary_creator.h"

int main(int argc, char** argv) {
  std::setvbuf(stdout, nullptr, _IOLBF, 0);  // tables appear as they are made, even through tee
  const int reps = peers::build_repetitions(argc, argv);
  if (reps < 0) return 2;
  const std::vector<cv::Mat> images = peers::training_set();

  peers::BuildRow one{"binbow", 1, {}}, two{"binbow", 2, {}}, fbow1{"fbow", 1, {}},
      fbow2{"fbow", 2, {}};
  for (int rep = 0; rep < reps; ++rep) {
    auto run_binbow = [&] {
      for (peers::BuildRow* row : {&one, &two}) peers::measure_binbow_build(images, *row);
    };
    auto run_fbow = [&] {
      for (peers::BuildRow* row : {&fbow1, &fbow2}) {
        fbow::Vocabulary v;
        fbow::VocabularyCreator creator;
        const double t0 = peers::process_cpu_us();
        creator.create(v, images, "orb", fbow::VocabularyCreator::Params(10, 5, row->threads));
        row->cpu_s.push_back((peers::process_cpu_us() - t0) * 1e-6);
      }
    };
    if (rep % 2 == 0) {
      run_binbow();
      run_fbow();
    } else {
      run_fbow();
      run_binbow();
    }
  }
  peers::print_build_table({one, two, fbow1, fbow2});
  return 0;
}
