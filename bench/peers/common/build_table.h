// The vocabulary-building table both build harnesses print: one row per
// builder and thread count, process CPU time (all threads) per repetition,
// words, quantisation error, and the ratio to binbow on one thread of the
// same repetitions.
#pragma once

#include <cstdio>
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
