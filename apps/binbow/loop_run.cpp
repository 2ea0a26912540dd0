#include "loop_run.h"

#include <sys/stat.h>
#include <unistd.h>
#include <algorithm>
#include <cerrno>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <numeric>
#include <sstream>

#include <nlohmann/json.hpp>

#include "binbow/error.h"
#include "binbow/formats.h"
#include "binbow/vocabulary.h"
#include "core/file_io.h"
#include "default_vocabulary.h"

namespace binbow::cli {

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

void write_file_atomically(const std::string& path, const std::string& text) {
  detail::write_file_atomically(path, text.data(), text.size());
}

void LoopRun::save(const std::string& path) const {
  Json j;
  j["format"] = "binbow-loop-run";
  j["version"] = 1;
  j["inputs"] = inputs;
  j["vocabulary"] = vocabulary;
  j["descriptor"] = descriptor;
  j["max_features"] = max_features;
  j["params"] = Json::parse(params_json);
  j["source"] = {
      {"stride", source.stride}, {"max_width", source.max_width}, {"video_fps", source.video_fps}};
  Json frames_json = Json::array();
  for (const FrameRecord& f : frames)
    frames_json.push_back({{"file", f.file},
                           {"status", f.status},
                           {"match", f.match},
                           {"score", f.score},
                           {"normalised_score", f.normalised_score},
                           {"inliers", f.inliers}});
  j["frames"] = std::move(frames_json);
  Json loops_json = Json::array();
  for (const LoopRecord& l : loops)
    loops_json.push_back({{"query", l.query}, {"match", l.match}, {"inliers", l.inliers}});
  j["loops"] = std::move(loops_json);
  Json timing_json = Json::object();
  for (const StageTiming& t : timing) timing_json[t.stage] = t.ms;
  j["timing_ms"] = std::move(timing_json);
  write_file_atomically(path, j.dump());
}

LoopRun LoopRun::load(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in)
    throw FileError(path, "cannot open the run record (written by detect-loops beside loops.csv)");
  LoopRun run;
  try {
    const Json j = Json::parse(in);
    if (j.at("format") != "binbow-loop-run" || j.at("version") != 1)
      throw FileError(path, "not a binbow detect-loops run record (version 1)");
    run.inputs = j.at("inputs").get<std::vector<std::string>>();
    run.vocabulary = j.at("vocabulary").get<std::string>();
    run.descriptor = j.at("descriptor").get<std::string>();
    run.max_features = j.at("max_features").get<int>();
    run.params_json = j.at("params").dump(2);
    if (j.contains("source")) {  // absent from records of earlier versions
      const Json& source = j.at("source");
      run.source.stride = source.at("stride").get<std::size_t>();
      run.source.max_width = source.at("max_width").get<int>();
      run.source.video_fps = source.at("video_fps").get<double>();
    }
    for (const Json& f : j.at("frames"))
      run.frames.push_back({f.at("file").get<std::string>(), f.at("status").get<std::string>(),
                            f.at("match").get<long long>(), f.at("score").get<double>(),
                            f.at("normalised_score").get<double>(),
                            f.at("inliers").get<std::size_t>()});
    for (const Json& l : j.at("loops"))
      run.loops.push_back({l.at("query").get<std::size_t>(), l.at("match").get<std::size_t>(),
                           l.at("inliers").get<std::vector<std::array<float, 4>>>()});
    for (const auto& [stage, values] : j.at("timing_ms").items())
      run.timing.push_back({stage, values.get<std::vector<double>>()});
  } catch (const Json::exception& e) {
    throw FileError(path, std::string("malformed run record: ") + e.what());
  }
  // Stages in pipeline order (JSON objects come back sorted by name).
  static const char* const order[] = {"features", "transform",    "query",
                                      "islands",  "verification", "insertion"};
  const auto rank = [](const std::string& s) {
    return std::find_if(std::begin(order), std::end(order), [&](const char* o) { return s == o; }) -
           std::begin(order);
  };
  std::stable_sort(
      run.timing.begin(), run.timing.end(),
      [&](const StageTiming& a, const StageTiming& b) { return rank(a.stage) < rank(b.stage); });
  return run;
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

std::string load_loop_vocabulary(const std::string& vocab_argument, const std::string& descriptor,
                                 std::size_t code_size, Vocabulary& vocabulary) {
  const std::string path =
      vocab_argument.empty() ? default_vocabulary_path(descriptor) : vocab_argument;
  vocabulary = load_vocabulary(path);
  check_vocabulary_fits(vocabulary, path, descriptor, code_size);
  std::error_code error;
  const std::filesystem::path absolute = std::filesystem::absolute(path, error);
  return error ? path : absolute.string();
}

}  // namespace binbow::cli
