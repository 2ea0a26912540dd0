// What every peer harness shares: CPU clocks, medians and ranges, the heap
// size from malloc's statistics, and the real ORB descriptors of the shared
// data (the same rows for binbow and the peer). Our own code; header-only so
// that each harness stays one CMake project of its own.
#pragma once

#include <malloc.h>
#include <time.h>

#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <string>
#include <vector>

#include <opencv2/core.hpp>
#include <opencv2/features2d.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "binbow/descriptors.h"

namespace peers {

inline double cpu_us(clockid_t clock) {
  timespec ts;
  clock_gettime(clock, &ts);
  return ts.tv_sec * 1e6 + ts.tv_nsec * 1e-3;
}
// The calling thread's CPU time: what the other processes of a loaded
// machine inflate least.
inline double thread_cpu_us() {
  return cpu_us(CLOCK_THREAD_CPUTIME_ID);
}
// Every thread's: for calls that start threads of their own.
inline double process_cpu_us() {
  return cpu_us(CLOCK_PROCESS_CPUTIME_ID);
}

inline double median(std::vector<double> v) {
  if (v.empty()) return 0;
  std::sort(v.begin(), v.end());
  const std::size_t n = v.size();
  return n % 2 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]);
}

// Bytes malloc has handed out and not had back (small and mmapped blocks).
inline double heap_bytes() {
  const struct mallinfo2 m = mallinfo2();
  return static_cast<double>(m.uordblks + m.hblkhd);
}

// One figure over repetitions: "median (min–max)", or the value alone when
// every repetition gave the same.
inline std::string spread(const std::vector<double>& v, const char* format) {
  char med[64], lo[64], hi[64];
  std::snprintf(med, sizeof med, format, median(v));
  std::snprintf(lo, sizeof lo, format, *std::min_element(v.begin(), v.end()));
  std::snprintf(hi, sizeof hi, format, *std::max_element(v.begin(), v.end()));
  if (std::string(lo) == hi) return med;
  return std::string(lo) + "–" + hi + " (" + med + ")";
}

// The shared data folder ($BINBOW_SHARED_DATA, which the scripts set).
inline std::string shared_data() {
  const char* dir = std::getenv("BINBOW_SHARED_DATA");
  if (dir == nullptr || !std::filesystem::is_directory(dir)) {
    std::fprintf(stderr, "set BINBOW_SHARED_DATA to the folder holding rtabmap-samples\n");
    std::exit(1);
  }
  return dir;
}

// The images of shared-data folders, each folder's sorted by name.
inline std::vector<std::string> images_in(const std::vector<std::string>& folders) {
  namespace fs = std::filesystem;
  std::vector<std::string> out;
  for (const std::string& folder : folders) {
    const std::string dir = shared_data() + "/" + folder;
    if (!fs::is_directory(dir)) {
      std::fprintf(stderr, "no folder %s (BINBOW_SHARED_DATA)\n", dir.c_str());
      std::exit(1);
    }
    std::vector<std::string> files;
    for (const auto& e : fs::directory_iterator(dir)) {
      const std::string ext = e.path().extension().string();
      if (ext == ".jpg" || ext == ".png") files.push_back(e.path().string());
    }
    // rtabmap-samples' frames in their order: 2.jpg before 10.jpg.
    std::sort(files.begin(), files.end(), [](const std::string& a, const std::string& b) {
      return a.size() != b.size() ? a.size() < b.size() : a < b;
    });
    out.insert(out.end(), files.begin(), files.end());
  }
  return out;
}

// ORB with binbow's settings (cv::ORB's defaults: 1.2, 8 levels, Harris,
// FAST 20) on a grey image scaled by `scale`, mirrored left–right if asked
// (ORB is not mirror-invariant: new real descriptors).
inline cv::Mat orb_descriptors(const std::string& file, int features, double scale = 1.0,
                               bool mirrored = false) {
  cv::Mat image = cv::imread(file, cv::IMREAD_GRAYSCALE);
  if (image.empty()) {
    std::fprintf(stderr, "cannot read %s\n", file.c_str());
    std::exit(1);
  }
  if (scale != 1.0) cv::resize(image, image, cv::Size(), scale, scale);
  if (mirrored) cv::flip(image, image, 1);
  static thread_local cv::Ptr<cv::ORB> orb;
  if (orb.empty() || orb->getMaxFeatures() != features) orb = cv::ORB::create(features);
  std::vector<cv::KeyPoint> keypoints;
  cv::Mat descriptors;
  orb->detectAndCompute(image, cv::noArray(), keypoints, descriptors);
  return descriptors;
}

// The transform benchmarks' images: ORB-1000 of rtabmap-samples' frames at
// twice their size, pooled in frame order and cut into images of 1000 rows
// (as bench_transform and the fbow harness do).
inline std::vector<cv::Mat> rtabmap_images_of_1000() {
  cv::Mat pool;
  for (const std::string& f : images_in({"rtabmap-samples/samples"})) {
    const cv::Mat d = orb_descriptors(f, 1000, 2.0);
    if (!d.empty()) pool.push_back(d);
  }
  std::vector<cv::Mat> out;
  for (int row = 0; row + 1000 <= pool.rows; row += 1000)
    out.push_back(pool.rowRange(row, row + 1000).clone());
  return out;
}

// The vocabulary-building benchmarks' training set, as bench_build makes it:
// ORB-2000 of every image of rtabmap-samples, opencv-doc-samples and
// dbow2-demo-images, then of the same images mirrored, until 150,000
// descriptors; one matrix per image.
inline std::vector<cv::Mat> training_set() {
  const std::size_t kMax = 150000;
  const std::vector<std::string> files =
      images_in({"rtabmap-samples/samples", "opencv-doc-samples", "dbow2-demo-images"});
  std::vector<cv::Mat> out;
  std::size_t total = 0;
  for (const bool mirrored : {false, true})
    for (const std::string& f : files) {
      if (total == kMax) break;
      cv::Mat d = orb_descriptors(f, 2000, 1.0, mirrored);
      if (d.empty()) continue;
      d = d.rowRange(0, static_cast<int>(std::min<std::size_t>(d.rows, kMax - total)));
      total += d.rows;
      out.push_back(d);
    }
  std::printf("training set: %zu ORB descriptors from %zu real images\n", total, out.size());
  return out;
}

inline binbow::DescriptorView view(const cv::Mat& m) {
  return {m.ptr<std::uint8_t>(0), static_cast<std::size_t>(m.rows),
          static_cast<std::size_t>(m.cols)};
}

// One row per descriptor, as DBoW2 and DBoW3 take them.
inline std::vector<cv::Mat> rows_of(const cv::Mat& m) {
  std::vector<cv::Mat> out(m.rows);
  for (int r = 0; r < m.rows; ++r) out[r] = m.row(r);
  return out;
}

}  // namespace peers
