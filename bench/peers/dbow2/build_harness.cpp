// binbow against DBoW2 building a vocabulary: k=10 L=5, TF-IDF, L1 from the
// same 150,000 real ORB descriptors (peers::training_set), one builder after
// the other in each repetition, the first alternating; process CPU time and
// the quantisation error (mean bits from a training descriptor to its word,
// each library descending its own tree).
//
//   build_harness [--reps N]
#include <cstdio>
#include <cstdlib>
#include <string>
#include <vector>

#include <DBoW2/DBoW2.h>

#include "build_table.h"

int main(int argc, char** argv) {
  std::setvbuf(stdout, nullptr, _IOLBF, 0);  // tables appear as they are made, even through tee
  const int reps = peers::build_repetitions(argc, argv);
  if (reps < 0) return 2;
  const std::vector<cv::Mat> images = peers::training_set();
  std::vector<std::vector<cv::Mat>> rows;  // DBoW2 takes one cv::Mat per descriptor
  for (const cv::Mat& m : images) rows.push_back(peers::rows_of(m));

  peers::BuildRow one{"binbow", 1, {}}, two{"binbow", 2, {}}, dbow2{"DBoW2", 1, {}};
  for (int rep = 0; rep < reps; ++rep) {
    auto run_binbow = [&] {
      for (peers::BuildRow* row : {&one, &two}) peers::measure_binbow_build(images, *row);
    };
    auto run_dbow2 = [&] {
      std::srand(static_cast<unsigned>(rep));  // DBoW2's k-means++ seeds draw from rand()
      OrbVocabulary v(10, 5, DBoW2::TF_IDF, DBoW2::L1_NORM);
      const double t0 = peers::process_cpu_us();
      v.create(rows);
      dbow2.cpu_s.push_back((peers::process_cpu_us() - t0) * 1e-6);
      double bits = 0;
      std::size_t count = 0;
      for (const auto& image : rows)
        for (const cv::Mat& d : image) {
          bits += DBoW2::FORB::distance(d, v.getWord(v.transform(d)));
          ++count;
        }
      char error[32];
      std::snprintf(error, sizeof error, "%.2f", bits / count);
      dbow2.words = std::to_string(v.size());
      dbow2.error = error;
    };
    if (rep % 2 == 0) {
      run_binbow();
      run_dbow2();
    } else {
      run_dbow2();
      run_binbow();
    }
  }
  peers::print_build_table({one, two, dbow2});
  return 0;
}
