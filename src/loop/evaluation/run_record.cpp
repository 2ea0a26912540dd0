#include "binbow/loop/run_record.h"

#include <sys/stat.h>
#include <unistd.h>
#include <algorithm>
#include <cerrno>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <limits>
#include <numeric>
#include <sstream>

#include <nlohmann/json.hpp>

#include "binbow/error.h"
#include "core/crc32c.h"
#include "core/file_io.h"
#include "core/output_path.h"
#include "core/regular_file.h"

namespace binbow::loop {

using Json = nlohmann::json;

double StageTiming::mean() const {
  return ms.empty() ? 0 : std::accumulate(ms.begin(), ms.end(), 0.0) / double(ms.size());
}

double StageTiming::median() const {
  if (ms.empty()) return 0;
  std::vector<double> sorted = ms;
  const std::size_t mid = sorted.size() / 2;
  std::nth_element(sorted.begin(), sorted.begin() + static_cast<long>(mid), sorted.end());
  const double upper = sorted[mid];
  if (sorted.size() % 2 == 1) return upper;
  return (upper + *std::max_element(sorted.begin(), sorted.begin() + static_cast<long>(mid))) / 2;
}

double StageTiming::max() const {
  return ms.empty() ? 0 : *std::max_element(ms.begin(), ms.end());
}

namespace {
// JSON text of `value`; file names that are not UTF-8 (any bytes are allowed
// on Linux) get U+FFFD instead of failing the run at its end.
std::string json_text(const Json& value) {
  return value.dump(-1, ' ', false, Json::error_handler_t::replace);
}

// The integer at `key` of `object`, if it fits T. nlohmann's get<T>() also
// converts a fraction or a number out of T's range (found by fuzzing: a
// "match" of -5.6e35 converted to long long, which is undefined behaviour).
template <typename T>
T integer_at(const Json& object, const char* key, const std::string& path) {
  const Json& value = object.at(key);
  if (value.is_number_unsigned()) {
    const auto v = value.get<std::uint64_t>();
    if (v <= static_cast<std::uint64_t>(std::numeric_limits<T>::max())) return static_cast<T>(v);
  } else if (value.is_number_integer()) {
    const auto v = value.get<std::int64_t>();
    if (std::numeric_limits<T>::is_signed &&
        v >= static_cast<std::int64_t>(std::numeric_limits<T>::min()) &&
        v <= static_cast<std::int64_t>(std::numeric_limits<T>::max()))
      return static_cast<T>(v);
  }
  throw FileError(path, std::string("malformed run record: \"") + key + "\" is " + value.dump() +
                            ", not an integer in [" +
                            std::to_string(std::numeric_limits<T>::min()) + ", " +
                            std::to_string(std::numeric_limits<T>::max()) + "]");
}
// The largest max_features a record may hold: detect-loops --features' bound.
constexpr int kMaxRecordedFeatures = 1'000'000;

// How the inputs were read, within the bounds ImageSource takes: a sweep
// re-reads them so.
void check_source(const vision::ImageSourceOptions& source, const std::string& path) {
  const auto fail = [&](const char* key, const std::string& value, const std::string& range) {
    throw FileError(path, std::string("malformed run record: \"source\" \"") + key + "\" is " +
                              value + " (" + range + " expected)");
  };
  if (source.stride < 1 || source.stride > vision::kMaxStride)
    fail("stride", std::to_string(source.stride), "1 to " + std::to_string(vision::kMaxStride));
  if (source.max_width < 0 || source.max_width > vision::kMaxFrameWidth)
    fail("max_width", std::to_string(source.max_width),
         "0 to " + std::to_string(vision::kMaxFrameWidth));
  if (!(source.video_fps >= 0 && source.video_fps <= vision::kMaxVideoFps))
    fail("video_fps", Json(source.video_fps).dump(), "0 to " + Json(vision::kMaxVideoFps).dump());
}

bool is_frame_status(const std::string& status) {
  if (status == kUnreadableFrameStatus) return true;
  for (const LoopStatus s :
       {LoopStatus::kLoopDetected, LoopStatus::kNoDatabaseResults,
        LoopStatus::kLowNormalisationScore, LoopStatus::kLowScores, LoopStatus::kNoIslands,
        LoopStatus::kNoTemporalConsistency, LoopStatus::kNoGeometricConsistency})
    if (status == to_string(s)) return true;
  return false;
}

Json provenance_json(const Provenance& provenance) {
  return {{"binbow_version", provenance.binbow_version},
          {"date", provenance.date},
          {"command", provenance.command}};
}

}  // namespace

struct LoopRunFiles::Impl {
  Impl(const std::string& loops_csv, const LoopRun& run)
      : csv_path(loops_csv),
        record_path(LoopRun::path_for(loops_csv)),
        csv(staged.stage(csv_path)),
        // Nothing can be kept beside /dev/null, a FIFO or a terminal.
        record(detail::is_written_in_place(loops_csv) ? nullptr : staged.stage(record_path)) {
    for (const char* stage : kStageNames) timing.push_back({stage, {}});
    // The keys of a version 1 record, written one value at a time; "frames"
    // stays open until commit().
    write("{\"format\":\"binbow-loop-run\",\"version\":1" +
          (run.provenance.empty()
               ? std::string()
               : ",\"provenance\":" + json_text(provenance_json(run.provenance))) +
          ",\"inputs\":" + json_text(Json(run.inputs)) +
          ",\"vocabulary\":" + json_text(Json(run.vocabulary)) +
          (run.online_vocabulary
               ? ",\"online_vocabulary\":true,\"online_options\":" +
                     Json{{"new_word_distance", run.online_options.new_word_distance},
                          {"purge_after_images", run.online_options.purge_after_images},
                          {"trees", run.online_options.trees},
                          {"branching", run.online_options.branching},
                          {"leaf_size", run.online_options.leaf_size},
                          {"max_checks", run.online_options.max_checks},
                          {"exact", run.online_options.exact},
                          {"scoring", to_string(run.online_options.scoring)},
                          {"seed", run.online_options.seed}}
                         .dump()
               : "") +
          (run.resumed_from.empty()
               ? ""
               : ",\"resumed_from\":" + json_text(Json(run.resumed_from)) +
                     ",\"resumed_frames\":" + std::to_string(run.resumed_frames)) +
          ",\"descriptor\":" + json_text(Json(run.descriptor)) +
          ",\"max_features\":" + std::to_string(run.max_features) +
          ",\"params\":" + json_text(Json::parse(run.params_json)) + ",\"source\":" +
          Json{{"stride", run.source.stride},
               {"max_width", run.source.max_width},
               {"video_fps", run.source.video_fps}}
              .dump() +
          ",\n\"frames\":[");
  }

  void write(const std::string& text) {
    if (committed) throw FileError(record_path, "the run record is already finished");
    if (record == nullptr) return;
    detail::write_all(record, text.data(), text.size(), record_path);
  }

  void add_frame(const SequenceFrame& f) {
    const FrameRecord r = frame_record(f);
    // "correspondences" and "features" are new in version 1; readers treat them as optional.
    Json frame = {{"file", r.file},
                  {"status", r.status},
                  {"match", r.match},
                  {"score", r.score},
                  {"normalised_score", r.normalised_score},
                  {"inliers", r.inliers},
                  {"correspondences", r.correspondences},
                  {"features", r.features}};
    // Only loops carry these (newer than version 1's first records; optional to readers).
    if (!r.accepted_by.empty()) frame["accepted_by"] = r.accepted_by;
    if (r.localised_from >= 0) frame["localised_from"] = r.localised_from;
    write((frames == 0 ? "\n" : ",\n") + json_text(frame));
    ++frames;
    const std::array<double, kStageCount> stage_ms = f.stage_ms();
    for (std::size_t s = 0; s < kStageCount; ++s) timing[s].ms.push_back(stage_ms[s]);
  }

  // Keeps kDrawnInliers of the loop's inliers, spread over all of them.
  void add_loop(const SequenceFrame& f) {
    const auto& inliers = f.inlier_points;
    LoopRecord loop{f.result.query, f.result.match, {}};
    const std::size_t drawn = std::min(inliers.size(), kDrawnInliers);
    loop.inliers.reserve(drawn);
    for (std::size_t i = 0; i < drawn; ++i)
      loop.inliers.push_back(inliers[i * inliers.size() / drawn]);
    loops.push_back(std::move(loop));
  }

  void finish_record(const std::string& csv_text) {
    write("],\n\"loops\":[");
    for (std::size_t i = 0; i < loops.size(); ++i) {
      const LoopRecord& l = loops[i];
      write((i == 0 ? "\n" : ",\n") +
            Json{{"query", l.query}, {"match", l.match}, {"inliers", l.inliers}}.dump());
    }
    write("],\n\"timing_ms\":{");
    for (std::size_t s = 0; s < kStageCount; ++s)
      write((s == 0 ? "\n" : ",\n") + json_text(Json(timing[s].stage)) + ":" +
            json_text(Json(timing[s].ms)));
    write("},\n\"loops_csv\":" +
          Json{{"bytes", csv_text.size()},
               {"crc32c", binbow::detail::crc32c(csv_text.data(), csv_text.size())}}
              .dump() +
          "}\n");
  }

  std::string csv_path;
  std::string record_path;
  detail::StagedFiles staged;
  std::FILE* csv;
  std::FILE* record;
  bool committed = false;
  std::size_t frames = 0;
  std::vector<Detection> detections;
  std::vector<LoopRecord> loops;
  std::vector<StageTiming> timing;
};

LoopRunFiles::LoopRunFiles(const std::string& loops_csv, const LoopRun& description)
    : impl_(std::make_unique<Impl>(loops_csv, description)) {}

LoopRunFiles::~LoopRunFiles() = default;

void LoopRunFiles::add(const SequenceFrame& frame) {
  Impl& d = *impl_;
  d.add_frame(frame);
  const LoopResult& r = frame.result;
  if (!r.detection()) return;
  d.detections.push_back(
      {r.query, r.match, frame.file, frame.match_file, r.normalised_score, r.inliers.size()});
  if (d.loops.size() < kDrawnLoops) d.add_loop(frame);
}

void LoopRunFiles::commit() {
  Impl& d = *impl_;
  const std::string csv_text = format_detections_csv(d.detections);
  detail::write_all(d.csv, csv_text.data(), csv_text.size(), d.csv_path);
  d.finish_record(csv_text);
  d.committed = true;
  d.staged.commit();
}

std::size_t LoopRunFiles::frames() const noexcept {
  return impl_->frames;
}
const std::vector<Detection>& LoopRunFiles::detections() const noexcept {
  return impl_->detections;
}
const std::vector<LoopRecord>& LoopRunFiles::loops() const noexcept {
  return impl_->loops;
}
const std::vector<StageTiming>& LoopRunFiles::timing() const noexcept {
  return impl_->timing;
}

FrameRecord frame_record(const SequenceFrame& frame) {
  const LoopResult& r = frame.result;
  return {frame.file,
          frame.unreadable.empty() ? to_string(r.status) : kUnreadableFrameStatus,
          r.has_candidate ? static_cast<long long>(r.match) : -1,
          r.score,
          r.normalised_score,
          r.inliers.size(),
          static_cast<long long>(r.correspondences),
          static_cast<long long>(r.features),
          r.detection() ? to_string(r.accepted_by) : "",
          r.detection() && r.localised ? static_cast<long long>(r.localised_from) : -1};
}

std::vector<StageTiming> stage_timings(const std::vector<SequenceFrame>& frames) {
  std::vector<StageTiming> timing;
  for (const char* stage : kStageNames) timing.push_back({stage, {}});
  for (const SequenceFrame& frame : frames) {
    const std::array<double, kStageCount> stage_ms = frame.stage_ms();
    for (std::size_t s = 0; s < kStageCount; ++s) timing[s].ms.push_back(stage_ms[s]);
  }
  return timing;
}

LoopRun LoopRun::load(const std::string& path) {
  // Only a regular file, read whole: a FIFO would block, a device never end.
  const std::string text = binbow::detail::read_regular_file(path, kMaxRunRecordBytes);
  LoopRun run;
  run.path = path;
  try {
    const Json j = Json::parse(text);
    if (j.at("format") != "binbow-loop-run" || j.at("version") != 1)
      throw FileError(path, "not a binbow detect-loops run record (version 1)");
    if (j.contains("provenance")) {  // absent from records written before it was added
      const Json& p = j.at("provenance");
      run.provenance = {p.value("binbow_version", ""), p.value("date", ""), p.value("command", "")};
    }
    run.inputs = j.at("inputs").get<std::vector<std::string>>();
    run.vocabulary = j.at("vocabulary").get<std::string>();
    // Written only for runs without a vocabulary file.
    if (j.contains("online_vocabulary"))
      run.online_vocabulary = j.at("online_vocabulary").get<bool>();
    if (j.contains("online_options")) {  // absent before the CLI had flags for them: defaults
      const Json& o = j.at("online_options");
      OnlineVocabularyOptions& options = run.online_options;
      options.new_word_distance = o.at("new_word_distance").get<double>();
      options.purge_after_images = integer_at<std::uint32_t>(o, "purge_after_images", path);
      options.trees = integer_at<std::uint32_t>(o, "trees", path);
      options.branching = integer_at<std::uint32_t>(o, "branching", path);
      options.leaf_size = integer_at<std::uint32_t>(o, "leaf_size", path);
      options.max_checks = integer_at<std::uint32_t>(o, "max_checks", path);
      options.exact = o.at("exact").get<bool>();
      try {
        options.scoring = parse_scoring(o.at("scoring").get<std::string>());
      } catch (const InvalidArgument& e) {
        throw FileError(path, std::string("online_options: ") + e.what());
      }
      options.seed = integer_at<std::uint64_t>(o, "seed", path);
    }
    if (j.contains("resumed_from")) {
      run.resumed_from = j.at("resumed_from").get<std::string>();
      run.resumed_frames = integer_at<std::size_t>(j, "resumed_frames", path);
    }
    run.descriptor = j.at("descriptor").get<std::string>();
    run.max_features = integer_at<int>(j, "max_features", path);
    // As detect-loops --features takes it: a sweep would re-run with it.
    if (run.max_features < 0 || run.max_features > kMaxRecordedFeatures)
      throw FileError(path, "malformed run record: \"max_features\" is " +
                                std::to_string(run.max_features) + " (0 to " +
                                std::to_string(kMaxRecordedFeatures) + " expected)");
    run.params_json = j.at("params").dump(2);
    if (j.contains("source")) {  // absent from records of earlier versions
      const Json& source = j.at("source");
      run.source.stride = integer_at<std::size_t>(source, "stride", path);
      run.source.max_width = integer_at<int>(source, "max_width", path);
      run.source.video_fps = source.at("video_fps").get<double>();
      check_source(run.source, path);
    }
    for (const Json& f : j.at("frames")) {
      // Absent from records written before it was added: not known.
      const long long correspondences =
          f.contains("correspondences") ? integer_at<long long>(f, "correspondences", path) : -1;
      if (correspondences < -1)
        throw FileError(path, "malformed run record: frame " + std::to_string(run.frames.size()) +
                                  " has a negative number of correspondences");
      const long long features =
          f.contains("features") ? integer_at<long long>(f, "features", path) : -1;
      if (features < -1)
        throw FileError(path, "malformed run record: frame " + std::to_string(run.frames.size()) +
                                  " has a negative number of features");
      const std::string status = f.at("status").get<std::string>();
      if (!is_frame_status(status))
        throw FileError(path, "malformed run record: frame " + std::to_string(run.frames.size()) +
                                  " has the unknown status \"" + status + "\"");
      FrameRecord frame;
      frame.file = f.at("file").get<std::string>();
      frame.status = status;
      frame.match = integer_at<long long>(f, "match", path);
      frame.score = f.at("score").get<double>();
      frame.normalised_score = f.at("normalised_score").get<double>();
      frame.inliers = integer_at<std::size_t>(f, "inliers", path);
      frame.correspondences = correspondences;
      frame.features = features;
      if (f.contains("accepted_by")) {
        frame.accepted_by = f.at("accepted_by").get<std::string>();
        LoopEvidence evidence;
        if (!parse_loop_evidence(frame.accepted_by, &evidence))
          throw FileError(path, "malformed run record: frame " + std::to_string(run.frames.size()) +
                                    " has the unknown accepted_by \"" + frame.accepted_by + "\"");
      }
      if (f.contains("localised_from")) {
        frame.localised_from = integer_at<long long>(f, "localised_from", path);
        if (frame.localised_from < 0)
          throw FileError(path, "malformed run record: frame " + std::to_string(run.frames.size()) +
                                    " has a negative localised_from");
      }
      run.frames.push_back(std::move(frame));
    }
    for (const Json& l : j.at("loops"))
      run.loops.push_back({integer_at<std::size_t>(l, "query", path),
                           integer_at<std::size_t>(l, "match", path),
                           l.at("inliers").get<std::vector<std::array<float, 4>>>()});
    for (const auto& [stage, values] : j.at("timing_ms").items())
      run.timing.push_back({stage, values.get<std::vector<double>>()});
    if (j.contains("loops_csv")) {
      const Json& csv = j.at("loops_csv");
      run.knows_loops_csv = true;
      run.loops_csv_bytes = integer_at<std::uint64_t>(csv, "bytes", path);
      run.loops_csv_crc32c = integer_at<std::uint32_t>(csv, "crc32c", path);
    }
  } catch (const Json::exception& e) {
    throw FileError(path, std::string("malformed run record: ") + e.what());
  }
  // Stages in pipeline order (JSON objects come back sorted by name).
  const auto rank = [](const std::string& s) {
    return std::find_if(std::begin(kStageNames), std::end(kStageNames),
                        [&](const char* o) { return s == o; }) -
           std::begin(kStageNames);
  };
  std::stable_sort(
      run.timing.begin(), run.timing.end(),
      [&](const StageTiming& a, const StageTiming& b) { return rank(a.stage) < rank(b.stage); });
  return run;
}

bool check_loops_csv_of_run(const LoopRun& run, const std::string& run_path,
                            const std::string& loops_csv) {
  if (!run.knows_loops_csv) return false;
  binbow::detail::require_regular_file(loops_csv);
  std::ifstream in(loops_csv, std::ios::binary);
  if (!in) throw FileError(loops_csv, std::string("cannot open: ") + std::strerror(errno));
  std::vector<char> buffer(std::size_t{1} << 20);
  std::uint64_t bytes = 0;
  std::uint32_t crc = 0;
  while (in) {
    in.read(buffer.data(), static_cast<std::streamsize>(buffer.size()));
    const auto got = static_cast<std::size_t>(in.gcount());
    crc = binbow::detail::crc32c(buffer.data(), got, crc);
    bytes += got;
  }
  if (in.bad()) throw FileError(loops_csv, "cannot read: " + std::string(std::strerror(errno)));
  if (bytes != run.loops_csv_bytes || crc != run.loops_csv_crc32c) {
    char sums[64];
    std::snprintf(sums, sizeof sums, "CRC-32C %08x, the record's %08x", crc,
                  static_cast<unsigned>(run.loops_csv_crc32c));
    throw FileError(loops_csv, "not the loops file written with the run record " + run_path + " (" +
                                   std::to_string(bytes) + " bytes, the record's " +
                                   std::to_string(run.loops_csv_bytes) + "; " + sums +
                                   "): one of them was replaced or edited after the run. Run "
                                   "detect-loops again, or move the record away to evaluate the "
                                   "loops alone");
  }
  return true;
}

std::string format_timing_table(const std::vector<StageTiming>& timing) {
  std::ostringstream out;
  char line[160];
  std::snprintf(line, sizeof line, "%-14s %10s %10s %10s\n", "stage (ms)", "mean", "median", "max");
  out << line;
  StageTiming total{"total", {}};
  for (const StageTiming& t : timing) {
    std::snprintf(line, sizeof line, "%-14s %10.3f %10.3f %10.3f\n", t.stage.c_str(), t.mean(),
                  t.median(), t.max());
    out << line;
    if (total.ms.size() < t.ms.size()) total.ms.resize(t.ms.size(), 0);
    for (std::size_t i = 0; i < t.ms.size(); ++i) total.ms[i] += t.ms[i];
  }
  std::snprintf(line, sizeof line, "%-14s %10.3f %10.3f %10.3f\n", "total", total.mean(),
                total.median(), total.max());
  out << line;
  return out.str();
}

}  // namespace binbow::loop
