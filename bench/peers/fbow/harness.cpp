// binbow vs fbow: Vocabulary::transform -> BoW vector, side by side in one
// process, on the same vocabulary (.bbw for binbow, the same tree written as
// .fbow by `binbow convert` for fbow) and the same real ORB descriptors.
//
//   harness --bbw V.bbw --fbow V.fbow [--images rtabmap|doc|both] [--reps N]
//           [--first binbow|fbow] [--check-only] [--no-check]
//           [--profile binbow|fbow --passes N]
//
// 1. Extracts ORB descriptors (cv::ORB, 1000 features) from real images,
//    pools them in image order and cuts them into "images" of 1000 rows
//    (as binbow's bench_transform does).
// 2. Checks that binbow and fbow give the same word for every descriptor
//    (fbow: transform of a one-row matrix, the single key of its BoW) and
//    the same BoW vector per image (same words, values within 1e-5 relative).
// 3. Times transform -> BoW vector, binbow and fbow calls interleaved per
//    image (order alternating per image and repetition), thread CPU time per
//    call; prints medians and the ratio fbow / binbow.
//
// --profile runs only one library's transform `passes` times over all images
// (for callgrind with --toggle-collect), after the check.
#include <time.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <string>
#include <vector>

#include <opencv2/core.hpp>
#include <opencv2/features2d.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "binbow/descriptors.h"
#include "binbow/vocabulary.h"
#include "fbow.h"

namespace fs = std::filesystem;

namespace {

double thread_cpu_us() {
  timespec ts;
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &ts);
  return ts.tv_sec * 1e6 + ts.tv_nsec * 1e-3;
}

double median(std::vector<double> v) {
  if (v.empty()) return 0;
  std::sort(v.begin(), v.end());
  const std::size_t n = v.size();
  return n % 2 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]);
}

double quantile(std::vector<double> v, double q) {
  if (v.empty()) return 0;
  std::sort(v.begin(), v.end());
  const double pos = q * (v.size() - 1);
  const std::size_t lo = static_cast<std::size_t>(pos);
  const std::size_t hi = std::min(lo + 1, v.size() - 1);
  return v[lo] + (pos - lo) * (v[hi] - v[lo]);
}

// The shared data folder: $BINBOW_SHARED_DATA, set by run.sh.
std::string shared_data() {
  const char* dir = std::getenv("BINBOW_SHARED_DATA");
  if (dir == nullptr) {
    std::fprintf(stderr, "harness: set BINBOW_SHARED_DATA to the folder holding rtabmap-samples\n");
    std::exit(1);
  }
  return dir;
}

std::vector<std::string> image_list(const std::string& which) {
  std::vector<std::string> out;
  if (which == "rtabmap" || which == "both") {
    const std::string dir = shared_data() + "/rtabmap-samples/samples";
    for (int frame = 1; fs::exists(dir + "/" + std::to_string(frame) + ".jpg"); ++frame)
      out.push_back(dir + "/" + std::to_string(frame) + ".jpg");
  }
  if (which == "doc" || which == "both") {
    std::vector<std::string> doc;
    for (const auto& e : fs::directory_iterator(shared_data() + "/opencv-doc-samples")) {
      const std::string ext = e.path().extension().string();
      if (ext == ".jpg" || ext == ".png") doc.push_back(e.path().string());
    }
    std::sort(doc.begin(), doc.end());
    out.insert(out.end(), doc.begin(), doc.end());
  }
  return out;
}

struct Images {
  std::vector<cv::Mat> mats;  // CV_8UC1, 1000 x 32 each
};

Images extract(const std::vector<std::string>& files, bool rtabmap_twice) {
  auto orb = cv::ORB::create(1000);
  cv::Mat pool;
  for (const auto& f : files) {
    cv::Mat img = cv::imread(f, cv::IMREAD_GRAYSCALE);
    if (img.empty()) continue;
    // rtabmap frames are 512x384: at twice their size, as bench_transform.
    if (rtabmap_twice && f.find("rtabmap-samples") != std::string::npos)
      cv::resize(img, img, cv::Size(), 2.0, 2.0);
    std::vector<cv::KeyPoint> kp;
    cv::Mat d;
    orb->detectAndCompute(img, cv::noArray(), kp, d);
    if (!d.empty()) pool.push_back(d);
  }
  Images out;
  for (int row = 0; row + 1000 <= pool.rows; row += 1000)
    out.mats.push_back(pool.rowRange(row, row + 1000).clone());
  std::fprintf(stderr, "%zu files, %d descriptors, %zu images of 1000\n", files.size(), pool.rows,
               out.mats.size());
  return out;
}

binbow::DescriptorView view(const cv::Mat& m) {
  return {m.ptr<std::uint8_t>(0), static_cast<std::size_t>(m.rows), 32};
}

// Defeats dead-code elimination of results.
volatile double g_sink = 0;

}  // namespace

int main(int argc, char** argv) {
  std::string bbw, fbw, images_set = "rtabmap", first = "binbow", profile, cache;
  int reps = 30, passes = 20;
  bool check_only = false, no_check = false;
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    auto next = [&]() -> std::string {
      if (i + 1 >= argc) {
        std::fprintf(stderr, "%s needs a value\n", a.c_str());
        std::exit(2);
      }
      return argv[++i];
    };
    if (a == "--bbw")
      bbw = next();
    else if (a == "--fbow")
      fbw = next();
    else if (a == "--images")
      images_set = next();
    else if (a == "--reps")
      reps = std::stoi(next());
    else if (a == "--first")
      first = next();
    else if (a == "--check-only")
      check_only = true;
    else if (a == "--no-check")
      no_check = true;
    else if (a == "--profile")
      profile = next();
    else if (a == "--passes")
      passes = std::stoi(next());
    else if (a == "--cache")
      cache = next();
    else {
      std::fprintf(stderr, "unknown argument %s\n", a.c_str());
      return 2;
    }
  }
  if (bbw.empty() || fbw.empty()) {
    std::fprintf(stderr, "usage: harness --bbw V.bbw --fbow V.fbow [options]\n");
    return 2;
  }

  // binbow: the vocabulary as loaded, with L2 normalisation so that its BoW
  // vectors are fbow's (fbow always normalises L2; the cost is the same).
  const binbow::Vocabulary loaded = binbow::Vocabulary::load(bbw);
  const binbow::Vocabulary bb = loaded.with_scoring(binbow::Scoring::kL2);
  fbow::Vocabulary fb;
  fb.readFromFile(fbw);
  std::printf("kernel: %s\n", binbow::hamming_kernel_name());
  std::printf("binbow vocabulary: %s\n", loaded.description().c_str());
  std::printf("fbow vocabulary: k=%u, %zu blocks, desc %u bytes\n", fb.getK(), fb.size(),
              fb.getDescSize());

  // --cache FILE: the descriptors (all images, 1000 x 32 bytes each) saved
  // on first use and read back afterwards (for valgrind runs).
  Images im;
  if (!cache.empty() && fs::exists(cache)) {
    FILE* f = std::fopen(cache.c_str(), "rb");
    std::vector<std::uint8_t> buf(1000 * 32);
    while (f && std::fread(buf.data(), 1, buf.size(), f) == buf.size())
      im.mats.push_back(cv::Mat(1000, 32, CV_8UC1, buf.data()).clone());
    if (f) std::fclose(f);
    std::fprintf(stderr, "%zu images of 1000 from %s\n", im.mats.size(), cache.c_str());
  } else {
    im = extract(image_list(images_set), true);
    if (!cache.empty()) {
      FILE* f = std::fopen(cache.c_str(), "wb");
      for (const cv::Mat& m : im.mats) std::fwrite(m.data, 1, 1000 * 32, f);
      std::fclose(f);
    }
  }
  if (im.mats.empty()) {
    std::fprintf(stderr, "no images\n");
    return 1;
  }

  // ---- words-identical check, every descriptor ----
  std::size_t total = 0, word_mismatch = 0, bow_mismatch = 0, fbow_zero_entries = 0;
  double max_rel = 0;
  for (const cv::Mat& m : im.mats) {
    if (no_check) break;
    std::vector<binbow::WordId> words(m.rows);
    bb.quantize(view(m), words.data());
    for (int r = 0; r < m.rows; ++r) {
      const fbow::fBow one = fb.transform(m.row(r));
      const std::uint32_t fw = one.empty() ? 0xffffffffu : one.begin()->first;
      if (one.size() != 1 || fw != words[r]) {
        if (word_mismatch < 5)
          std::fprintf(stderr, "word mismatch: descriptor %zu binbow %u fbow %u\n", total + r,
                       words[r], fw);
        ++word_mismatch;
      }
    }
    total += m.rows;
    binbow::BowVector bv;
    bb.transform(view(m), bv);
    const fbow::fBow fv = fb.transform(m);
    // fbow keeps words of weight 0 (stop words) as 0 entries; binbow drops them.
    std::vector<std::pair<std::uint32_t, float>> fnz;
    for (const auto& e : fv) {
      if (e.second.var != 0.0f)
        fnz.emplace_back(e.first, e.second.var);
      else
        ++fbow_zero_entries;
    }
    bool same = fnz.size() == bv.size();
    for (std::size_t i = 0; same && i < fnz.size(); ++i) {
      if (fnz[i].first != bv[i].word) {
        same = false;
        break;
      }
      const double rel = std::fabs(fnz[i].second - bv[i].value) / std::fabs(bv[i].value);
      max_rel = std::max(max_rel, rel);
      if (rel > 1e-5) same = false;
    }
    if (!same) ++bow_mismatch;
  }
  std::printf(
      "check: %zu descriptors, %zu word mismatches; %zu images, %zu BoW mismatches "
      "(max relative value difference %.2g; %zu zero-weight entries in fbow's BoW)\n",
      total, word_mismatch, im.mats.size(), bow_mismatch, max_rel, fbow_zero_entries);
  if (word_mismatch != 0 || bow_mismatch != 0) return 3;
  if (!no_check) {
    // Path statistics (public API walk): inner nodes visited and children
    // compared per descriptor; also checks the walk against quantize().
    std::size_t levels = 0, children = 0, walk_mismatch = 0;
    for (const cv::Mat& m : im.mats)
      for (int r = 0; r < m.rows; ++r) {
        const std::uint8_t* d = m.ptr<std::uint8_t>(r);
        binbow::NodeId node = 0;
        while (!bb.is_leaf(node)) {
          const binbow::NodeId f = bb.first_child(node);
          const std::uint32_t c = bb.child_count(node);
          std::uint32_t best = ~0u, bi = 0;
          for (std::uint32_t i = 0; i < c; ++i) {
            const std::uint32_t h = binbow::hamming_distance(d, bb.node_descriptor(f + i), 32);
            if (h < best) {
              best = h;
              bi = i;
            }
          }
          ++levels;
          children += c;
          node = f + bi;
        }
        if (bb.node_word(node) != bb.quantize(d)) ++walk_mismatch;
      }
    std::printf(
        "descent: %.3f inner nodes and %.2f child distances per descriptor "
        "(%.2f children per node); %zu walk mismatches\n",
        double(levels) / total, double(children) / total, double(children) / levels, walk_mismatch);
  }
  if (check_only) return 0;

  if (!profile.empty()) {
    binbow::BowVector bv;
    double s = 0;
    for (int p = 0; p < passes; ++p)
      for (const cv::Mat& m : im.mats) {
        if (profile == "binbow") {
          bb.transform(view(m), bv);
          s += bv.size();
        } else {
          const fbow::fBow fv = fb.transform(m);
          s += fv.size();
        }
      }
    g_sink = s;
    std::printf("profile %s: %d passes x %zu images\n", profile.c_str(), passes, im.mats.size());
    return 0;
  }

  // ---- timing ----
  binbow::BowVector bv;
  double sink = 0;
  auto run_binbow = [&](const cv::Mat& m) {
    const double t0 = thread_cpu_us();
    bb.transform(view(m), bv);
    const double t1 = thread_cpu_us();
    sink += bv.size();
    return t1 - t0;
  };
  auto run_fbow = [&](const cv::Mat& m) {
    const double t0 = thread_cpu_us();
    const fbow::fBow fv = fb.transform(m);
    const double t1 = thread_cpu_us();
    sink += fv.size();
    return t1 - t0;  // includes nothing of fv's destruction (after t1)
  };
  std::vector<binbow::WordId> qwords(1000);
  auto run_quantize = [&](const cv::Mat& m) {
    const double t0 = thread_cpu_us();
    bb.quantize(view(m), qwords.data());
    const double t1 = thread_cpu_us();
    sink += qwords[0];
    return t1 - t0;
  };
  // Warm-up: two passes of each.
  for (int w = 0; w < 2; ++w)
    for (const cv::Mat& m : im.mats) {
      run_binbow(m);
      run_fbow(m);
    }

  const bool binbow_first = first == "binbow";
  std::vector<double> tb, tf, tq, pair_ratio, pass_ratio;
  for (int rep = 0; rep < reps; ++rep) {
    double pb = 0, pf = 0;
    for (std::size_t i = 0; i < im.mats.size(); ++i) {
      const bool b_first = ((rep + i) % 2 == 0) == binbow_first;
      double b, f;
      if (b_first) {
        b = run_binbow(im.mats[i]);
        f = run_fbow(im.mats[i]);
      } else {
        f = run_fbow(im.mats[i]);
        b = run_binbow(im.mats[i]);
      }
      // binbow's descent alone, on the image half a pass away (not the one
      // just transformed, whose tree nodes are still in cache).
      tq.push_back(run_quantize(im.mats[(i + im.mats.size() / 2) % im.mats.size()]));
      tb.push_back(b);
      tf.push_back(f);
      pair_ratio.push_back(f / b);
      pb += b;
      pf += f;
    }
    pass_ratio.push_back(pf / pb);
  }
  // Warm: each call repeated at once on the same image and only the repeat
  // timed, so the image's tree paths are in cache: what is left is compute
  // (plus L2/L3 hits), the rest of the cold time is waiting on memory.
  std::vector<double> wb, wf;
  for (int rep = 0; rep < std::max(1, reps / 4); ++rep)
    for (std::size_t i = 0; i < im.mats.size(); ++i) {
      const bool b_first = ((rep + i) % 2 == 0) == binbow_first;
      if (b_first) {
        run_binbow(im.mats[i]);
        wb.push_back(run_binbow(im.mats[i]));
      }
      run_fbow(im.mats[i]);
      wf.push_back(run_fbow(im.mats[i]));
      if (!b_first) {
        run_binbow(im.mats[i]);
        wb.push_back(run_binbow(im.mats[i]));
      }
    }
  g_sink = sink;
  const double mb = median(tb), mf = median(tf);
  std::printf(
      "warm (repeat on the same image): binbow median %.1f us, fbow median %.1f us, "
      "ratio %.2f\n",
      median(wb), median(wf), median(wf) / median(wb));
  std::printf("WARM binbow_us=%.1f fbow_us=%.1f ratio=%.2f\n", median(wb), median(wf),
              median(wf) / median(wb));
  std::printf("calls: %zu per library (%d reps x %zu images of 1000 descriptors), first=%s\n",
              tb.size(), reps, im.mats.size(), first.c_str());
  std::printf("binbow median %.1f us (p25 %.1f, p75 %.1f)\n", mb, quantile(tb, 0.25),
              quantile(tb, 0.75));
  std::printf("fbow   median %.1f us (p25 %.1f, p75 %.1f)\n", mf, quantile(tf, 0.25),
              quantile(tf, 0.75));
  std::printf("binbow quantize (descent only) median %.1f us\n", median(tq));
  std::printf(
      "ratio of medians fbow/binbow %.2f; median per-call-pair ratio %.2f "
      "(p25 %.2f, p75 %.2f); per-pass ratio min %.2f median %.2f max %.2f\n",
      mf / mb, median(pair_ratio), quantile(pair_ratio, 0.25), quantile(pair_ratio, 0.75),
      *std::min_element(pass_ratio.begin(), pass_ratio.end()), median(pass_ratio),
      *std::max_element(pass_ratio.begin(), pass_ratio.end()));
  std::printf(
      "RESULT kernel=%s binbow_us=%.1f fbow_us=%.1f ratio=%.2f pair_ratio=%.2f "
      "pass_ratio_min=%.2f pass_ratio_max=%.2f quantize_us=%.1f\n",
      binbow::hamming_kernel_name(), mb, mf, mf / mb, median(pair_ratio),
      *std::min_element(pass_ratio.begin(), pass_ratio.end()),
      *std::max_element(pass_ratio.begin(), pass_ratio.end()), median(tq));
  return 0;
}
