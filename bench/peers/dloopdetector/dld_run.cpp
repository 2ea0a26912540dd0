// dld_run: run DLoopDetector's TemplatedLoopDetector over an image folder.
//
// Our own driver (not part of binbow, not copied from DLoopDetector): it
// lists the images of a folder in natural order (digit runs compared as
// numbers, so 2.jpg < 10.jpg), extracts ORB (binbow's settings) or
// DLoopDetector's BRIEF (FAST + DVision::BRIEF256, as demo_brief does), feeds
// OrbLoopDetector / BriefLoopDetector and writes
//   <out>          query_index,match_index   (0-based, one line per loop)
//   <out>.status   query_index,status,candidate,n_features  (every frame)
//
// FRAMES is an image folder or a video file (cv::VideoCapture, frames
// converted to grey). Last line on stderr: the frame loop's wall and process
// CPU time (reading, decoding, features and detection; not the vocabulary's
// load), which bench/peers/dloopdetector/timing.sh reads.
//
// usage: dld_run --descriptor orb|brief --vocab VOC.yml.gz [--pattern P.yml]
//                [--k K] [--di-levels L] [--alpha A] [--frequency F]
//                [--fast-threshold T] [--seed S] -o OUT.csv FRAMES
#include <dirent.h>
#include <time.h>
#include <algorithm>
#include <cctype>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <string>
#include <vector>

#include <opencv2/core.hpp>
#include <opencv2/features2d.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>  // DVision/BRIEF256.h uses cv::cvtColor/GaussianBlur without including it
#include <opencv2/videoio.hpp>

#include <DBoW2/DBoW2.h>
#include <DUtils/DUtils.h>
#include <DVision/DVision.h>
#include "DLoopDetector.h"

namespace {

struct Options {
  std::string descriptor = "orb";
  std::string vocab;
  std::string pattern;
  std::string out;
  std::string frames;
  int k = 1;          // demo_brief sets params.k = 1
  int di_levels = 2;  // demo_brief sets params.di_levels = 2
  float alpha = 0.3f;
  float frequency = 1.0f;
  int fast_threshold = 20;  // demo_brief's FAST threshold
  // Variant (not DLoopDetector's demo): keep only corners whose every BRIEF
  // test lies inside the image, then the N strongest by FAST response (0: all).
  bool drop_border_corners = false;
  int max_features = 0;
  int seed = 0;
};

[[noreturn]] void usage(const char* msg) {
  std::cerr << "dld_run: " << msg << "\n"
            << "usage: dld_run --descriptor orb|brief --vocab VOC.yml.gz [--pattern P.yml]\n"
               "       [--k K] [--di-levels L] [--alpha A] [--frequency F]\n"
               "       [--fast-threshold T] [--max-features N] [--drop-border-corners]\n"
               "       [--seed S] -o OUT.csv FRAMES_DIR\n";
  std::exit(2);
}

Options parse(int argc, char** argv) {
  Options o;
  for (int i = 1; i < argc; ++i) {
    std::string a = argv[i];
    auto next = [&]() -> std::string {
      if (i + 1 >= argc) usage(("missing value for " + a).c_str());
      return argv[++i];
    };
    if (a == "--descriptor")
      o.descriptor = next();
    else if (a == "--vocab")
      o.vocab = next();
    else if (a == "--pattern")
      o.pattern = next();
    else if (a == "-o" || a == "--output")
      o.out = next();
    else if (a == "--k")
      o.k = std::stoi(next());
    else if (a == "--di-levels")
      o.di_levels = std::stoi(next());
    else if (a == "--alpha")
      o.alpha = std::stof(next());
    else if (a == "--frequency")
      o.frequency = std::stof(next());
    else if (a == "--fast-threshold")
      o.fast_threshold = std::stoi(next());
    else if (a == "--seed")
      o.seed = std::stoi(next());
    else if (a == "--max-features")
      o.max_features = std::stoi(next());
    else if (a == "--drop-border-corners")
      o.drop_border_corners = true;
    else if (!a.empty() && a[0] == '-')
      usage(("unknown option " + a).c_str());
    else
      o.frames = a;
  }
  if (o.vocab.empty() || o.out.empty() || o.frames.empty()) usage("missing argument");
  if (o.descriptor != "orb" && o.descriptor != "brief") usage("descriptor must be orb or brief");
  if (o.descriptor == "brief" && o.pattern.empty()) usage("--pattern is required for brief");
  return o;
}

// Natural order: runs of digits compare by value, the rest byte by byte.
bool natural_less(const std::string& a, const std::string& b) {
  size_t i = 0, j = 0;
  while (i < a.size() && j < b.size()) {
    if (std::isdigit((unsigned char)a[i]) && std::isdigit((unsigned char)b[j])) {
      size_t i2 = i, j2 = j;
      while (i2 < a.size() && std::isdigit((unsigned char)a[i2])) ++i2;
      while (j2 < b.size() && std::isdigit((unsigned char)b[j2])) ++j2;
      std::string da = a.substr(i, i2 - i), db = b.substr(j, j2 - j);
      da.erase(0, std::min(da.find_first_not_of('0'), da.size()));
      db.erase(0, std::min(db.find_first_not_of('0'), db.size()));
      if (da.size() != db.size()) return da.size() < db.size();
      if (da != db) return da < db;
      i = i2;
      j = j2;
    } else {
      if (a[i] != b[j]) return a[i] < b[j];
      ++i;
      ++j;
    }
  }
  if ((a.size() - i) != (b.size() - j)) return (a.size() - i) < (b.size() - j);
  return a < b;
}

std::vector<std::string> list_images(const std::string& dir) {
  std::vector<std::string> names;
  DIR* d = opendir(dir.c_str());
  if (!d) {
    std::cerr << "dld_run: cannot open " << dir << "\n";
    std::exit(1);
  }
  while (dirent* e = readdir(d)) {
    std::string n = e->d_name;
    std::string low = n;
    for (char& c : low) c = (char)std::tolower((unsigned char)c);
    auto ends = [&](const char* s) {
      std::string x = s;
      return low.size() > x.size() && low.compare(low.size() - x.size(), x.size(), x) == 0;
    };
    if (ends(".jpg") || ends(".jpeg") || ends(".png") || ends(".bmp") || ends(".pgm") ||
        ends(".ppm") || ends(".tif") || ends(".tiff"))
      names.push_back(n);
  }
  closedir(d);
  std::sort(names.begin(), names.end(), natural_less);
  for (auto& n : names) n = dir + "/" + n;
  return names;
}

// The frames of an image folder (natural order) or of a video file, grey.
class Frames {
 public:
  explicit Frames(const std::string& path) : path_(path) {
    if (std::filesystem::is_directory(path)) {
      files_ = list_images(path);
    } else if (!video_.open(path)) {
      std::cerr << "dld_run: cannot open the video " << path << "\n";
      std::exit(1);
    }
  }
  bool empty() const { return video_.isOpened() ? false : files_.empty(); }
  std::string describe() const {
    if (video_.isOpened()) return "video " + path_;
    return std::to_string(files_.size()) + " images, first " + files_.front() + ", last " +
           files_.back();
  }
  // The number of frames when known in advance (a video's may be 0).
  std::size_t expected() const {
    return video_.isOpened() ? static_cast<std::size_t>(video_.get(cv::CAP_PROP_FRAME_COUNT))
                             : files_.size();
  }
  // The next frame, grey; false at the end.
  bool next(cv::Mat& grey) {
    if (video_.isOpened()) {
      cv::Mat frame;
      if (!video_.read(frame)) return false;
      if (frame.channels() == 3)
        cv::cvtColor(frame, grey, cv::COLOR_BGR2GRAY);
      else
        grey = frame;
      return true;
    }
    if (index_ == files_.size()) return false;
    grey = cv::imread(files_[index_], cv::IMREAD_GRAYSCALE);
    if (grey.empty()) {
      std::cerr << "dld_run: cannot read " << files_[index_] << "\n";
      std::exit(1);
    }
    ++index_;
    return true;
  }

 private:
  std::string path_;
  std::vector<std::string> files_;
  std::size_t index_ = 0;
  cv::VideoCapture video_;
};

double process_cpu_seconds() {
  timespec ts;
  clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &ts);
  return ts.tv_sec + ts.tv_nsec * 1e-9;
}

const char* status_name(DLoopDetector::DetectionStatus s) {
  using namespace DLoopDetector;
  switch (s) {
    case LOOP_DETECTED:
      return "LOOP_DETECTED";
    case CLOSE_MATCHES_ONLY:
      return "CLOSE_MATCHES_ONLY";
    case NO_DB_RESULTS:
      return "NO_DB_RESULTS";
    case LOW_NSS_FACTOR:
      return "LOW_NSS_FACTOR";
    case LOW_SCORES:
      return "LOW_SCORES";
    case NO_GROUPS:
      return "NO_GROUPS";
    case NO_TEMPORAL_CONSISTENCY:
      return "NO_TEMPORAL_CONSISTENCY";
    case NO_GEOMETRICAL_CONSISTENCY:
      return "NO_GEOMETRICAL_CONSISTENCY";
  }
  return "?";
}

template <class TVocabulary, class TDetector, class TDescriptor, class Extract>
int run(const Options& o, Extract extract) {
  cv::Mat first;
  if (!Frames(o.frames).next(first)) {
    std::cerr << "dld_run: no frame in " << o.frames << "\n";
    return 1;
  }
  // DLoopDetector's constructor defaults, then what demo_brief sets.
  typename TDetector::Parameters params(first.rows, first.cols, o.frequency);
  params.use_nss = true;
  params.alpha = o.alpha;
  params.k = o.k;
  params.geom_check = DLoopDetector::GEOM_DI;
  params.di_levels = o.di_levels;

  std::cerr << "loading " << o.vocab << "\n";
  TVocabulary voc(o.vocab);
  std::cerr << "vocabulary: " << voc.size() << " words, k=" << voc.getBranchingFactor()
            << " L=" << voc.getDepthLevels() << "\n";
  std::cerr << "params: rows=" << params.image_rows << " cols=" << params.image_cols
            << " use_nss=" << params.use_nss << " alpha=" << params.alpha << " k=" << params.k
            << " geom=GEOM_DI di_levels=" << params.di_levels << " dislocal=" << params.dislocal
            << " max_db_results=" << params.max_db_results
            << " min_nss_factor=" << params.min_nss_factor
            << " min_matches_per_group=" << params.min_matches_per_group
            << " max_intragroup_gap=" << params.max_intragroup_gap
            << " max_distance_between_groups=" << params.max_distance_between_groups
            << " max_distance_between_queries=" << params.max_distance_between_queries
            << " min_Fpoints=" << params.min_Fpoints
            << " max_ransac_iterations=" << params.max_ransac_iterations
            << " ransac_probability=" << params.ransac_probability
            << " max_reprojection_error=" << params.max_reprojection_error
            << " max_neighbor_ratio=" << params.max_neighbor_ratio << "\n";

  TDetector detector(voc, params);
  Frames frames(o.frames);
  if (frames.expected() > 0) detector.allocate(frames.expected());

  std::ofstream out(o.out);
  std::ofstream st(o.out + ".status");
  out << "query_index,match_index\n";
  st << "query_index,status,candidate,n_features\n";
  std::vector<cv::KeyPoint> keys;
  std::vector<TDescriptor> descriptors;
  int loops = 0;
  double t_feat = 0, t_det = 0;
  const auto loop_start = std::chrono::steady_clock::now();
  const double loop_cpu_start = process_cpu_seconds();
  size_t i = 0;
  for (cv::Mat im; frames.next(im); ++i) {
    auto t0 = std::chrono::steady_clock::now();
    extract(im, keys, descriptors);
    auto t1 = std::chrono::steady_clock::now();
    DLoopDetector::DetectionResult result;
    detector.detectLoop(keys, descriptors, result);
    auto t2 = std::chrono::steady_clock::now();
    t_feat += std::chrono::duration<double>(t1 - t0).count();
    t_det += std::chrono::duration<double>(t2 - t1).count();
    if (result.detection()) {
      out << result.query << "," << result.match << "\n";
      ++loops;
    }
    const bool has_candidate = result.status == DLoopDetector::LOOP_DETECTED ||
                               result.status == DLoopDetector::NO_GROUPS ||
                               result.status == DLoopDetector::NO_TEMPORAL_CONSISTENCY ||
                               result.status == DLoopDetector::NO_GEOMETRICAL_CONSISTENCY;
    st << i << "," << status_name(result.status) << ","
       << (has_candidate ? std::to_string(result.match) : std::string("")) << ","
       << descriptors.size() << "\n";
    if (result.query != i) {
      std::cerr << "dld_run: query id " << result.query << " != frame " << i << "\n";
      return 1;
    }
  }
  const double loop_wall =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - loop_start).count();
  const double loop_cpu = process_cpu_seconds() - loop_cpu_start;
  std::cerr << i << " frames, " << loops << " loops; features " << 1e3 * t_feat / i
            << " ms/frame, detection " << 1e3 * t_det / i << " ms/frame\n";
  std::fprintf(stderr, "frame loop: %.3f s wall, %.3f s CPU, %zu frames, %d loops\n", loop_wall,
               loop_cpu, i, loops);
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  const Options o = parse(argc, argv);
  // DUtils::Random (DVision's RANSAC in FSolver, BRIEF pattern generation)
  // seeds itself from the clock unless seeded first: fix it for repeatable runs.
  DUtils::Random::SeedRandOnce(o.seed);
  const Frames frames(o.frames);
  if (frames.empty()) {
    std::cerr << "dld_run: no images in " << o.frames << "\n";
    return 1;
  }
  std::cerr << frames.describe() << "\n";

  if (o.descriptor == "orb") {
    // binbow's ORB settings.
    cv::Ptr<cv::ORB> orb = cv::ORB::create(1000, 1.2f, 8, 31, 0, 2, cv::ORB::HARRIS_SCORE, 31, 20);
    auto extract = [&](const cv::Mat& im, std::vector<cv::KeyPoint>& keys,
                       std::vector<cv::Mat>& descs) {
      keys.clear();
      cv::Mat d;
      orb->detectAndCompute(im, cv::noArray(), keys, d);
      descs.resize(d.rows);
      for (int r = 0; r < d.rows; ++r) descs[r] = d.row(r).clone();
    };
    return run<OrbVocabulary, OrbLoopDetector, FORB::TDescriptor>(o, extract);
  }

  // DLoopDetector's demo_brief: FAST (threshold 20, non-max suppression),
  // every corner, DVision::BRIEF256 with the pattern file's tests.
  cv::FileStorage fs(o.pattern, cv::FileStorage::READ);
  if (!fs.isOpened()) {
    std::cerr << "dld_run: cannot open " << o.pattern << "\n";
    return 1;
  }
  std::vector<int> x1, y1, x2, y2;
  fs["x1"] >> x1;
  fs["x2"] >> x2;
  fs["y1"] >> y1;
  fs["y2"] >> y2;
  DVision::BRIEF256 brief;
  brief.importPairs(x1, y1, x2, y2);
  const int fast_threshold = o.fast_threshold;
  int min_x = 0, max_x = 0, min_y = 0, max_y = 0;  // extent of the tests
  for (size_t i = 0; i < x1.size(); ++i) {
    min_x = std::min({min_x, x1[i], x2[i]});
    max_x = std::max({max_x, x1[i], x2[i]});
    min_y = std::min({min_y, y1[i], y2[i]});
    max_y = std::max({max_y, y1[i], y2[i]});
  }
  auto extract = [&](const cv::Mat& im, std::vector<cv::KeyPoint>& keys,
                     std::vector<DVision::BRIEF256::bitset>& descs) {
    keys.clear();
    cv::FAST(im, keys, fast_threshold, true);
    if (o.drop_border_corners) {
      std::vector<cv::KeyPoint> inside;
      for (const cv::KeyPoint& kp : keys) {
        const int x = (int)kp.pt.x, y = (int)kp.pt.y;
        if (x + min_x >= 0 && y + min_y >= 0 && x + max_x < im.cols && y + max_y < im.rows)
          inside.push_back(kp);
      }
      keys.swap(inside);
    }
    if (o.max_features > 0 && (int)keys.size() > o.max_features) {
      std::stable_sort(keys.begin(), keys.end(), [](const cv::KeyPoint& a, const cv::KeyPoint& b) {
        return a.response > b.response;
      });
      keys.resize(o.max_features);
    }
    brief.compute(im, keys, descs);
  };
  return run<BriefVocabulary, BriefLoopDetector, FBrief::TDescriptor>(o, extract);
}
