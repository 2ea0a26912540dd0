#include <algorithm>
#include <cctype>
#include <cmath>
#include <functional>
#include <iterator>
#include <sstream>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "binbow/error.h"
#include "binbow/loop/loop_detector.h"
#include "core/regular_file.h"
#include "vision/flat_yaml.h"
#include "vision/storage_text.h"

namespace binbow::loop {

using binbow::detail::read_regular_file;
using vision::check_storage_text;
using vision::parse_flat_yaml;
using vision::parse_fundamental_estimator;
namespace {

using Json = nlohmann::json;

std::string normalise_name(std::string name) {
  for (char& c : name)
    c = c == '_' ? '-' : static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return name;
}

// One table drives reading, writing and error messages, so the three cannot diverge.
struct Field {
  const char* key;
  std::function<void(LoopDetectorParams&, const Json&)> read;  // throws std::string on type errors
  std::function<Json(const LoopDetectorParams&)> write;
};

template <class T>
Field number_field(const char* key, T LoopDetectorParams::*member) {
  return {key,
          [key, member](LoopDetectorParams& p, const Json& v) {
            if (!v.is_number()) throw std::string("\"") + key + "\" must be a number";
            // YAML's .inf and .nan arrive here as doubles (JSON cannot spell them).
            if (!std::isfinite(v.get<double>()))
              throw std::string("\"") + key + "\" must be a finite number";
            if constexpr (std::is_integral_v<T>) {
              const double x = v.get<double>();
              if (x != std::floor(x) || std::abs(x) > 1e9)
                throw std::string("\"") + key + "\" must be an integer";
              p.*member = static_cast<T>(x);
            } else {
              p.*member = v.get<T>();
            }
          },
          [member](const LoopDetectorParams& p) { return Json(p.*member); }};
}

Field bool_field(const char* key, bool LoopDetectorParams::*member) {
  return {key,
          [key, member](LoopDetectorParams& p, const Json& v) {
            if (v.is_boolean()) {
              p.*member = v.get<bool>();
            } else if (v.is_number_integer() && (v.get<int>() == 0 || v.get<int>() == 1)) {
              p.*member = v.get<int>() == 1;  // YAML through FileStorage has no booleans
            } else if (v.is_string() && (v == "true" || v == "false")) {
              p.*member = v == "true";
            } else {
              throw std::string("\"") + key + "\" must be true or false";
            }
          },
          [member](const LoopDetectorParams& p) { return Json(p.*member); }};
}

const std::vector<Field>& fields() {
  using P = LoopDetectorParams;
  static const std::vector<Field> table = {
      number_field("frequency", &P::frequency),
      bool_field("use_normalised_score", &P::use_normalised_score),
      number_field("alpha", &P::alpha),
      number_field("min_normalisation_score", &P::min_normalisation_score),
      bool_field("skip_featureless_frames", &P::skip_featureless_frames),
      number_field("dislocal", &P::dislocal),
      number_field("max_db_results", &P::max_db_results),
      bool_field("fast_queries", &P::fast_queries),
      number_field("max_intra_island_gap", &P::max_intra_island_gap),
      number_field("min_matches_per_island", &P::min_matches_per_island),
      number_field("k", &P::k),
      number_field("max_distance_between_islands", &P::max_distance_between_islands),
      number_field("max_distance_between_queries", &P::max_distance_between_queries),
      Field{"geometric_check",
            [](P& p, const Json& v) {
              if (!v.is_string()) throw std::string("\"geometric_check\" must be a string");
              try {
                p.geometric_check = parse_geometric_check(v.get<std::string>());
              } catch (const InvalidArgument& e) {
                throw std::string(e.what());
              }
            },
            [](const P& p) { return Json(to_string(p.geometric_check)); }},
      number_field("direct_index_levels", &P::direct_index_levels),
      bool_field("exhaustive_fallback", &P::exhaustive_fallback),
      number_field("max_verified_entries", &P::max_verified_entries),
      number_field("max_neighbor_ratio", &P::max_neighbor_ratio),
      number_field("max_match_distance", &P::max_match_distance),
      bool_field("accept_single_candidate", &P::accept_single_candidate),
      bool_field("mutual_matching", &P::mutual_matching),
      Field{"fundamental_estimator",
            [](P& p, const Json& v) {
              if (!v.is_string()) throw std::string("\"fundamental_estimator\" must be a string");
              try {
                p.fundamental_estimator = parse_fundamental_estimator(v.get<std::string>());
              } catch (const InvalidArgument& e) {
                throw std::string(e.what());
              }
            },
            [](const P& p) { return Json(to_string(p.fundamental_estimator)); }},
      number_field("min_inliers", &P::min_inliers),
      number_field("max_reprojection_error", &P::max_reprojection_error),
      number_field("ransac_confidence", &P::ransac_confidence),
      number_field("max_ransac_iterations", &P::max_ransac_iterations),
      number_field("min_inlier_ratio", &P::min_inlier_ratio),
      number_field("min_inlier_spread", &P::min_inlier_spread),
      bool_field("reject_degenerate_fits", &P::reject_degenerate_fits),
      number_field("min_uncorroborated_inliers", &P::min_uncorroborated_inliers),
      number_field("min_uncorroborated_view_agreement", &P::min_uncorroborated_view_agreement),
      bool_field("strong_fits_skip_temporal_check", &P::strong_fits_skip_temporal_check),
      number_field("corroboration_distance", &P::corroboration_distance),
      number_field("corroboration_horizon", &P::corroboration_horizon),
      number_field("corroboration_pace_tolerance", &P::corroboration_pace_tolerance),
      bool_field("localise_in_island", &P::localise_in_island),
      number_field("max_localisation_checks", &P::max_localisation_checks),
  };
  return table;
}

// The frame-count parameters of `p` scaled from the paper's 1 Hz values to `f` Hz.
void scale_to_frequency(LoopDetectorParams& p, double f) {
  if (!(f > 0) || f > kMaxFrequency) throw InvalidArgument("frequency must be in (0, 10000] Hz");
  const auto scaled = [f](double base, int at_least) {
    return std::max(at_least, static_cast<int>(base * f));
  };
  p.frequency = f;
  p.dislocal = scaled(20, 0);
  p.max_db_results = scaled(50, 1);
  p.min_matches_per_island = scaled(1, 1);
  p.max_intra_island_gap = scaled(3, 1);
  p.max_distance_between_islands = scaled(3, 0);
  p.max_distance_between_queries = scaled(2, 1);
  p.corroboration_distance = scaled(4, 1);
  p.corroboration_horizon = scaled(10, 1);
}

LoopDetectorParams from_object(const Json& object, const std::string& name,
                               const LoopDetectorParams& defaults) {
  if (!object.is_object()) throw FileError(name, "loop detector parameters must be an object");
  LoopDetectorParams params = defaults;
  if (object.contains("frequency")) {
    const Json& f = object["frequency"];
    if (!f.is_number() || !(f.get<double>() > 0) || !(f.get<double>() <= kMaxFrequency))
      throw FileError(name, "\"frequency\" must be a number in (0, 10000]");
    scale_to_frequency(params, f.get<double>());
  }
  for (const auto& [key, value] : object.items()) {
    const auto field = std::find_if(fields().begin(), fields().end(),
                                    [&key = key](const Field& f) { return key == f.key; });
    if (field == fields().end()) {
      std::string known;
      for (const Field& f : fields()) known += std::string(known.empty() ? "" : ", ") + f.key;
      throw FileError(name,
                      "unknown loop detector parameter \"" + key + "\" (known: " + known + ")");
    }
    try {
      field->read(params, value);
    } catch (const std::string& problem) {
      throw FileError(name, problem);
    }
  }
  try {
    params.validate();
  } catch (const InvalidArgument& e) {
    throw FileError(name, e.what());
  }
  return params;
}

}  // namespace

const char* to_string(GeometricCheck check) {
  switch (check) {
    case GeometricCheck::kDirectIndex:
      return "direct-index";
    case GeometricCheck::kExhaustive:
      return "exhaustive";
    case GeometricCheck::kNone:
      return "none";
  }
  return "?";
}

GeometricCheck parse_geometric_check(const std::string& name) {
  const std::string n = normalise_name(name);
  if (n == "direct-index") return GeometricCheck::kDirectIndex;
  if (n == "exhaustive") return GeometricCheck::kExhaustive;
  if (n == "none") return GeometricCheck::kNone;
  throw InvalidArgument("unknown geometric check \"" + name +
                        "\" (expected direct-index, exhaustive or none)");
}

LoopDetectorParams LoopDetectorParams::for_frequency(double f) {
  LoopDetectorParams p;
  scale_to_frequency(p, f);
  return p;
}

void LoopDetectorParams::validate() const {
  // The ranges documented beside each field in loop_detector.h and in
  // docs/limits.md. The upper bounds keep hostile parameter files from asking
  // for unbounded work (RANSAC iterations, verified entries) or memory.
  const auto in_range = [](const char* name, double value, double low, double high,
                           bool low_open = false, bool high_open = false) {
    const bool ok = std::isfinite(value) && (low_open ? value > low : value >= low) &&
                    (high_open ? value < high : value <= high);
    if (!ok) {
      std::ostringstream message;
      message.precision(15);
      message << "loop detector parameter " << name << " must be in " << (low_open ? '(' : '[')
              << low << ", " << high << (high_open ? ')' : ']') << ", got " << value;
      throw InvalidArgument(message.str());
    }
  };
  in_range("frequency", frequency, 0, kMaxFrequency, true);
  in_range("alpha", alpha, 0, kMaxScoreThreshold);
  in_range("min_normalisation_score", min_normalisation_score, 0, kMaxScoreThreshold);
  in_range("dislocal", dislocal, 0, kMaxFrameDistance);
  in_range("max_db_results", max_db_results, 1, kMaxFrameDistance);
  in_range("max_intra_island_gap", max_intra_island_gap, 1, kMaxFrameDistance);
  in_range("min_matches_per_island", min_matches_per_island, 1, kMaxFrameDistance);
  in_range("k", k, 0, kMaxConsistentQueries);
  in_range("max_distance_between_islands", max_distance_between_islands, 0, kMaxFrameDistance);
  in_range("max_distance_between_queries", max_distance_between_queries, 1, kMaxFrameDistance);
  in_range("direct_index_levels", direct_index_levels, 0, kMaxDirectIndexLevels);
  in_range("max_verified_entries", max_verified_entries, 1, kMaxVerifiedEntries);
  in_range("max_localisation_checks", max_localisation_checks, 1, kMaxLocalisationChecks);
  in_range("max_neighbor_ratio", max_neighbor_ratio, 0, 1, true);
  in_range("max_match_distance", max_match_distance, 0, 1);
  // A fundamental matrix needs 8 points.
  in_range("min_inliers", min_inliers, 8, kMaxMinInliers);
  in_range("max_reprojection_error", max_reprojection_error, kMinReprojectionError,
           kMaxReprojectionError);
  in_range("ransac_confidence", ransac_confidence, 0, 1, true, true);
  in_range("max_ransac_iterations", max_ransac_iterations, 1, kMaxRansacIterations);
  in_range("min_inlier_ratio", min_inlier_ratio, 0, 1);
  in_range("min_inlier_spread", min_inlier_spread, 0, 1);
  in_range("min_uncorroborated_inliers", min_uncorroborated_inliers, 0, kMaxMinInliers);
  in_range("min_uncorroborated_view_agreement", min_uncorroborated_view_agreement, 0, 1);
  in_range("corroboration_distance", corroboration_distance, 1, kMaxFrameDistance);
  in_range("corroboration_horizon", corroboration_horizon, 1, kMaxFrameDistance);
  in_range("corroboration_pace_tolerance", corroboration_pace_tolerance, 0, 1);
}

namespace {
Json parse_json_object(const std::string& text, const std::string& name) {
  try {
    return Json::parse(text);
  } catch (const Json::exception& e) {
    throw FileError(name, std::string("invalid JSON: ") + e.what());
  }
}
}  // namespace

LoopDetectorParams LoopDetectorParams::from_json(const std::string& text, const std::string& name,
                                                 const LoopDetectorParams& defaults) {
  return from_object(parse_json_object(text, name), name, defaults);
}

LoopDetectorParams LoopDetectorParams::load(const std::string& path,
                                            const LoopDetectorParams& defaults) {
  const std::string text = read_regular_file(path, kMaxLoopParamsFileBytes);
  // nlohmann's JSON parser recurses per nesting level; parameters are one flat mapping.
  check_storage_text(text, path);
  const std::size_t first = text.find_first_not_of(" \t\r\n");
  const bool json = (first != std::string::npos && text[first] == '{') ||
                    (path.size() >= 5 && path.compare(path.size() - 5, 5, ".json") == 0);
  // YAML: parsed here (OpenCV's parser hangs on some malformed files) into
  // JSON, to share one validator.
  const Json object = json ? parse_json_object(text, path) : parse_flat_yaml(text, path);
  // A file that sets nothing is a wrong file, not a wish for the defaults.
  if (object.is_object() && object.empty())
    throw FileError(path,
                    "sets no parameter: the file is empty or holds only comments (expected "
                    "\"name: value\" lines or a JSON object)");
  return from_object(object, path, defaults);
}

LoopDetectorParams LoopDetectorParams::load(const std::string& path) {
  return load(path, LoopDetectorParams{});
}

LoopDetectorParams LoopDetectorParams::from_json(const std::string& text, const std::string& name) {
  return from_json(text, name, LoopDetectorParams{});
}

std::string LoopDetectorParams::to_json() const {
  nlohmann::ordered_json object = nlohmann::ordered_json::object();
  for (const Field& f : fields()) object[f.key] = f.write(*this);
  return object.dump(2);
}

}  // namespace binbow::loop
