// The vocabulary-building table both build harnesses print: one row per
// builder and thread count, process CPU time (all threads) per repetition,
// words, quantisation error, and the ratio to binbow on one thread of the
// same repetitions.
#pragma once

#include <cstdio>
#include <cstdlib>
#include <string>
#include <vector>

#include "binbow/vocabulary.h"
#include "peer_bench.h"

namespace peers {

struct BuildRow {
  std::string builder;
  unsigned threads = 1;
  std::vector<double> cpu_s;  // per repetition
  std::string words = "—";
  std::string error = "not measured";
};

// binbow's build, k=10 L=5, TF-IDF, L1, seed 0, as bench_build.
inline binbow::Vocabulary binbow_build(const std::vector<cv::Mat>& images, unsigned threads,
                                       double& cpu_s) {
  std::vector<binbow::DescriptorView> views;
  for (const cv::Mat& m : images) views.push_back(view(m));
  binbow::BuildOptions options;
  options.branching = 10;
  options.levels = 5;
  options.threads = threads;
  const double t0 = process_cpu_us();
  binbow::Vocabulary v = binbow::Vocabulary::build(views, options);
  cpu_s = (process_cpu_us() - t0) * 1e-6;
  return v;
}

// Mean Hamming distance from each training descriptor to its word, in bits.
inline double binbow_error(const binbow::Vocabulary& v, const std::vector<cv::Mat>& images) {
  cv::Mat all;
  for (const cv::Mat& m : images) all.push_back(m);
  return v.mean_quantisation_error(view(all));
}

// One repetition of binbow's row: the build on row.threads threads, its CPU
// time, words and quantisation error.
inline void measure_binbow_build(const std::vector<cv::Mat>& images, BuildRow& row) {
  double cpu_s;
  const binbow::Vocabulary v = binbow_build(images, row.threads, cpu_s);
  row.cpu_s.push_back(cpu_s);
  row.words = std::to_string(v.word_count());
  char error[32];
  std::snprintf(error, sizeof error, "%.2f", binbow_error(v, images));
  row.error = error;
}

// The build harnesses' one argument, --reps N (default 1); -1 after printing
// the usage for anything else.
inline int build_repetitions(int argc, char** argv) {
  int reps = 1;
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    if (a == "--reps" && i + 1 < argc) {
      reps = std::atoi(argv[++i]);
    } else {
      std::fprintf(stderr, "usage: build_harness [--reps N]\n");
      return -1;
    }
  }
  return reps;
}

inline void print_build_table(const std::vector<BuildRow>& rows) {
  std::printf(
      "\n**Vocabulary building**, k=10 L=5 from the same ORB descriptors (process CPU time, "
      "all threads):\n\n| builder | threads | CPU time, s | words | quantisation error, bits "
      "| CPU / binbow's on 1 thread |\n| --- | ---: | ---: | ---: | ---: | ---: |\n");
  const BuildRow& reference = rows.front();
  for (const BuildRow& r : rows) {
    std::vector<double> ratio;
    for (std::size_t i = 0; i < r.cpu_s.size(); ++i)
      ratio.push_back(r.cpu_s[i] / reference.cpu_s[i]);
    std::printf("| %s | %u | %s | %s | %s | %s |\n", r.builder.c_str(), r.threads,
                spread(r.cpu_s, "%.2f").c_str(), r.words.c_str(), r.error.c_str(),
                &r == &reference ? "1x" : ("**" + spread(ratio, "%.1fx") + "**").c_str());
  }
}

}  // namespace peers
