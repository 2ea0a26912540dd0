// The fuzz targets of binbow::vision's readers of untrusted files: loop
// detector parameters (JSON and YAML), BRIEF patterns, ground truth (.mat,
// image, text pairs) and loops.csv. Same contract as fuzz_targets.h: each
// function returns for a valid file, throws binbow::FileError for an invalid
// one, and throws std::logic_error when an accepted file breaks an invariant.
// Readers that only take a path get the input through a temporary file.
#pragma once

#include <unistd.h>
#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <stdexcept>
#include <string>
#include <system_error>
#include <vector>

#include "binbow/error.h"
#include "binbow/loop/evaluation.h"
#include "binbow/loop/loop_detector.h"
#include "binbow/loop/run_record.h"
#include "fuzz_targets.h"
#include "vision/brief_pattern.h"

namespace binbow::fuzz {

// A directory of this process for the inputs, removed at exit.
class InputDirectory {
 public:
  InputDirectory()
      : path_(std::filesystem::temp_directory_path() /
              ("binbow-fuzz-" + std::to_string(::getpid()))) {
    std::filesystem::create_directories(path_);
  }
  ~InputDirectory() {
    std::error_code ignored;
    std::filesystem::remove_all(path_, ignored);
  }
  InputDirectory(const InputDirectory&) = delete;
  InputDirectory& operator=(const InputDirectory&) = delete;
  const std::filesystem::path& path() const { return path_; }

 private:
  std::filesystem::path path_;
};

// A file named input<suffix> in that directory (the name picks the reader:
// .json, .mat, ...).
inline std::string input_path(const char* suffix) {
  static const InputDirectory directory;
  return (directory.path() / (std::string("input") + suffix)).string();
}

// The input written to input_path(suffix), afresh for every input.
inline std::string input_file(const std::uint8_t* data, std::size_t size, const char* suffix) {
  const std::string path = input_path(suffix);
  // A new file each time: ext4 flushes a file truncated and rewritten when it
  // is closed (auto_da_alloc), which made every input cost 4 ms.
  std::remove(path.c_str());
  std::FILE* file = std::fopen(path.c_str(), "wb");
  if (file == nullptr) throw std::runtime_error("cannot write the fuzz input " + path);
  const bool written = std::fwrite(data, 1, size, file) == size;
  if (std::fclose(file) != 0 || !written)
    throw std::runtime_error("cannot write the fuzz input " + path);
  return path;
}

// Accepted parameters are valid and survive to_json / from_json unchanged.
inline void check_accepted(const loop::LoopDetectorParams& params) {
  params.validate();
  const std::string json = params.to_json();
  if (loop::LoopDetectorParams::from_json(json, "rewritten").to_json() != json)
    throw std::logic_error("writing and reading back changed the parameters");
}

inline void load_params_json(const std::uint8_t* data, std::size_t size) {
  check_accepted(loop::LoopDetectorParams::from_json(
      std::string(reinterpret_cast<const char*>(data), size), "fuzz"));
}

inline void load_params_yaml(const std::uint8_t* data, std::size_t size) {
  check_accepted(loop::LoopDetectorParams::load(input_file(data, size, ".yml")));
}

inline void load_brief_pattern(const std::uint8_t* data, std::size_t size) {
  const vision::BriefPattern pattern = vision::load_brief_pattern(input_file(data, size, ".yml"));
  const std::size_t tests = pattern.tests();
  if (tests == 0 || tests % 8 != 0 || pattern.y1.size() != tests || pattern.x2.size() != tests ||
      pattern.y2.size() != tests)
    throw std::logic_error("accepted a pattern of unequal or partial-byte tests");
  if (pattern.radius() > vision::kMaxBriefPatternRadius)
    throw std::logic_error("accepted a pattern wider than kMaxBriefPatternRadius");
}

// Every query's ranges are earlier, increasing, disjoint and not adjacent
// (else they would be one), they add up to pair_count(), and is_loop agrees
// at both ends of each range and just past it.
inline void check_accepted(const loop::GroundTruth& truth) {
  std::size_t pairs = 0;
  const std::vector<std::size_t> queries = truth.loop_queries();
  if (queries.size() != truth.queries_with_loops())
    throw std::logic_error("queries_with_loops disagrees with loop_queries");
  for (const std::size_t q : queries) {
    const Span<loop::FrameRange> ranges = truth.earlier_match_ranges(q);
    if (ranges.empty()) throw std::logic_error("a loop query without ranges");
    for (std::size_t i = 0; i < ranges.size(); ++i) {
      const loop::FrameRange r = ranges[i];
      if (r.first >= r.end || r.end > q || (i > 0 && ranges[i - 1].end >= r.first))
        throw std::logic_error("ranges not earlier, increasing, disjoint and apart");
      if (!truth.is_loop(q, r.first) || !truth.is_loop(r.end - 1, q) || truth.is_loop(q, r.end))
        throw std::logic_error("is_loop disagrees with earlier_match_ranges");
      pairs += r.size();
    }
  }
  if (pairs != truth.pair_count()) throw std::logic_error("pair_count disagrees with the ranges");
}

inline void load_ground_truth(const std::uint8_t* data, std::size_t size, const char* suffix) {
  check_accepted(loop::GroundTruth::load(input_file(data, size, suffix)));
}

inline std::string file_text(const std::string& path) {
  std::FILE* file = std::fopen(path.c_str(), "rb");
  if (file == nullptr) throw std::runtime_error("cannot read " + path);
  std::string text;
  char buffer[4096];
  for (std::size_t n; (n = std::fread(buffer, 1, sizeof buffer, file)) > 0;) text.append(buffer, n);
  std::fclose(file);
  return text;
}

// An accepted loops.csv is written back and read again with the same rows;
// scores are written to 9 significant digits, so they only have to give the
// same file when written once more.
inline void load_loops_csv(const std::uint8_t* data, std::size_t size) {
  const std::vector<loop::Detection> detections =
      loop::read_detections_csv(input_file(data, size, ".csv"));
  std::string rewritten[2] = {input_path("-rewritten.csv"), input_path("-rewritten-twice.csv")};
  for (const std::string& path : rewritten)
    std::remove(path.c_str());  // renaming over it would flush it, as above
  loop::write_detections_csv(rewritten[0], detections);
  const std::vector<loop::Detection> again = loop::read_detections_csv(rewritten[0]);
  const auto same_row = [](const loop::Detection& a, const loop::Detection& b) {
    return a.query == b.query && a.match == b.match && a.query_file == b.query_file &&
           a.match_file == b.match_file && a.inliers == b.inliers;
  };
  if (again.size() != detections.size() ||
      !std::equal(again.begin(), again.end(), detections.begin(), same_row))
    throw std::logic_error("writing and reading back changed the detections");
  loop::write_detections_csv(rewritten[1], again);
  if (file_text(rewritten[0]) != file_text(rewritten[1]))
    throw std::logic_error("writing loops.csv twice gave two files");
}

// evaluate --sweep re-runs detection with the recorded parameters.
inline void load_loop_run(const std::uint8_t* data, std::size_t size) {
  const loop::LoopRun run = loop::LoopRun::load(input_file(data, size, ".run.json"));
  (void)loop::LoopDetectorParams::from_json(run.params_json, "the run record's params");
}

// The fixed vocabulary of the .bbld seeds: 4-byte descriptors, 2 levels of 3
// (built the same way every run, so its checksum is the seeds').
inline const Vocabulary& bbld_vocabulary() {
  static const Vocabulary vocabulary = [] {
    std::vector<DescriptorMatrix> images(4, DescriptorMatrix(4));
    std::uint32_t state = 12345;
    for (DescriptorMatrix& image : images)
      for (int row = 0; row < 12; ++row) {
        std::uint8_t code[4];
        for (std::uint8_t& byte : code) {
          state = state * 1103515245u + 12345u;
          byte = static_cast<std::uint8_t>(state >> 24);
        }
        image.append(code);
      }
    std::vector<DescriptorView> views(images.begin(), images.end());
    BuildOptions options;
    options.branching = 3;
    options.levels = 2;
    options.seed = 7;
    options.threads = 1;
    return Vocabulary::build(views, options);
  }();
  return vocabulary;
}

// A probe image for an accepted detector: `rows` descriptors of its size
// (the last remembered image's, so that candidates and matching are reached),
// with keypoints spread over a 100 x 100 image.
inline vision::Features bbld_probe(const loop::LoopDetector& detector, std::size_t code_size) {
  vision::Features probe;
  probe.descriptors = DescriptorMatrix(code_size);
  DescriptorView last;
  for (auto frame = static_cast<EntryId>(detector.size()); frame-- > 0;)
    if (!detector.is_forgotten(frame)) {
      last = detector.descriptors(frame);
      break;
    }
  for (std::size_t row = 0; row < 12; ++row) {
    std::vector<std::uint8_t> code(code_size, static_cast<std::uint8_t>(row * 37));
    if (row < last.rows) std::memcpy(code.data(), last.row(row), code_size);
    probe.descriptors.append(code.data());
    probe.keypoints.push_back({float(row * 7 % 100), float(row * 13 % 100), 7, -1, 1, 0});
  }
  return probe;
}

// An accepted state saves back to the same bytes, and processes images
// without proposing a forgotten one.
inline void check_accepted_detector(loop::LoopDetector detector, std::size_t code_size) {
  const std::vector<std::uint8_t> saved = detector.serialize();
  const bool online = detector.online_vocabulary() != nullptr;
  const loop::LoopDetector again =
      online ? loop::LoopDetector::deserialize(saved.data(), saved.size(), "resaved")
             : loop::LoopDetector::deserialize(saved.data(), saved.size(), "resaved",
                                               bbld_vocabulary());
  if (again.serialize() != saved) throw std::logic_error("save/load round trip changed the state");
  const std::size_t frames = detector.size();
  for (int i = 0; i < 2; ++i) {
    const loop::LoopResult result = detector.process(bbld_probe(detector, code_size));
    if (result.query != frames + i) throw std::logic_error("a resumed detector renumbered frames");
    if (result.has_candidate && detector.is_forgotten(result.match))
      throw std::logic_error("a resumed detector proposed a forgotten frame");
  }
}

// .bbld: as is, then with the CRCs of the embedded .bbdb and .bbov and its
// own recomputed, so that mutations reach the checks behind them. The flags
// (byte 16) say online (no vocabulary) or fixed (bbld_vocabulary()).
inline void load_bbld(const std::uint8_t* data, std::size_t size) {
  const auto load = [](const std::uint8_t* bytes, std::size_t n) {
    const bool online = n > 16 && (bytes[16] & 1) != 0;
    const std::size_t code_size = n >= 24 ? detail::load_le<std::uint32_t>(bytes + 20) : 0;
    check_accepted_detector(
        online ? loop::LoopDetector::deserialize(bytes, n, "fuzz")
               : loop::LoopDetector::deserialize(bytes, n, "fuzz", bbld_vocabulary()),
        code_size);
  };
  std::vector<std::uint8_t> fixed(data, data + size);
  fix_nested_checksums(fixed, {3, 4});
  try {
    load(fixed.data(), fixed.size());
  } catch (const FileError&) {
  }
  load(data, size);
}

inline const Target kVisionTargets[] = {
    {"params_json", load_params_json},
    {"params_yaml", load_params_yaml},
    {"brief_pattern", load_brief_pattern},
    {"gt_mat", [](const std::uint8_t* d, std::size_t n) { load_ground_truth(d, n, ".mat"); }},
    {"gt_image", [](const std::uint8_t* d, std::size_t n) { load_ground_truth(d, n, ".png"); }},
    {"gt_pairs", [](const std::uint8_t* d, std::size_t n) { load_ground_truth(d, n, ".txt"); }},
    {"loops_csv", load_loops_csv},
    {"loop_run", load_loop_run},
    {"bbld", load_bbld},
};

}  // namespace binbow::fuzz
