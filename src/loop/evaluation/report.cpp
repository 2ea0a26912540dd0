#include "binbow/loop/report.h"

#include <algorithm>
#include <cstdio>
#include <filesystem>
#include <sstream>

#include <opencv2/imgproc.hpp>

#include "binbow/error.h"
#include "binbow/loop/sweep.h"
#include "binbow/vision/image_source.h"
#include "core/file_io.h"
#include "vision/media_module.h"

namespace binbow::loop {
namespace {

constexpr int kPairHeight = 280;

std::string escape(const std::string& s) {
  std::string out;
  out.reserve(s.size());
  for (char c : s) {
    switch (c) {
      case '&':
        out += "&amp;";
        break;
      case '<':
        out += "&lt;";
        break;
      case '>':
        out += "&gt;";
        break;
      case '"':
        out += "&quot;";
        break;
      case '\'':
        out += "&#39;";
        break;
      default:
        out += c;
    }
  }
  return out;
}

std::string format(const char* pattern, double value) {
  char buffer[64];
  std::snprintf(buffer, sizeof buffer, pattern, value);
  return buffer;
}

std::string base64(const std::vector<unsigned char>& bytes) {
  static const char* const table =
      "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
  std::string out;
  out.reserve((bytes.size() + 2) / 3 * 4);
  std::size_t i = 0;
  for (; i + 2 < bytes.size(); i += 3) {
    const unsigned v = (bytes[i] << 16) | (bytes[i + 1] << 8) | bytes[i + 2];
    out += table[v >> 18];
    out += table[(v >> 12) & 63];
    out += table[(v >> 6) & 63];
    out += table[v & 63];
  }
  if (i + 1 == bytes.size()) {
    const unsigned v = bytes[i] << 16;
    out += table[v >> 18];
    out += table[(v >> 12) & 63];
    out += "==";
  } else if (i + 2 == bytes.size()) {
    const unsigned v = (bytes[i] << 16) | (bytes[i + 1] << 8);
    out += table[v >> 18];
    out += table[(v >> 12) & 63];
    out += table[(v >> 6) & 63];
    out += '=';
  }
  return out;
}

// Two frames scaled to kPairHeight, side by side on white: the canvas, each
// frame's scale, and where the second begins.
struct SideBySide {
  cv::Mat canvas;
  double query_scale = 1, match_scale = 1;
  int match_left = 0;
};

SideBySide side_by_side(const cv::Mat& query, const cv::Mat& match) {
  SideBySide pair;
  pair.query_scale = double(kPairHeight) / query.rows;
  pair.match_scale = double(kPairHeight) / match.rows;
  cv::Mat a, b;
  cv::resize(query, a, cv::Size(std::max(1, int(query.cols * pair.query_scale)), kPairHeight), 0, 0,
             cv::INTER_AREA);
  cv::resize(match, b, cv::Size(std::max(1, int(match.cols * pair.match_scale)), kPairHeight), 0, 0,
             cv::INTER_AREA);
  pair.match_left = a.cols + 8;
  pair.canvas = cv::Mat(kPairHeight, a.cols + b.cols + 8, CV_8UC3, cv::Scalar(255, 255, 255));
  a.copyTo(pair.canvas(cv::Rect(0, 0, a.cols, a.rows)));
  b.copyTo(pair.canvas(cv::Rect(pair.match_left, 0, b.cols, b.rows)));
  return pair;
}

// The two images scaled to one height, side by side, inliers as lines, as a
// data URL. Throws FileError if an image cannot be read.
std::string pair_image(const ReportLoop& loop) {
  // By name: a file, or "video#N" for a frame of a video.
  const cv::Mat query = vision::read_frame(loop.detection.query_file, vision::FramePixels::kBgr);
  const cv::Mat match = vision::read_frame(loop.detection.match_file, vision::FramePixels::kBgr);
  SideBySide pair = side_by_side(query, match);
  cv::Mat& canvas = pair.canvas;
  const double sq = pair.query_scale, sm = pair.match_scale;
  const std::size_t drawn = std::min(loop.inliers.size(), kDrawnInliers);
  for (std::size_t i = 0; i < drawn; ++i) {
    const auto& p = loop.inliers[i * loop.inliers.size() / drawn];
    const cv::Point2f pa(p[0] * float(sq), p[1] * float(sq));
    const cv::Point2f pb(p[2] * float(sm) + float(pair.match_left), p[3] * float(sm));
    cv::line(canvas, pa, pb, cv::Scalar(60, 200, 60), 1, cv::LINE_AA);
    cv::circle(canvas, pa, 3, cv::Scalar(0, 160, 255), 1, cv::LINE_AA);
    cv::circle(canvas, pb, 3, cv::Scalar(0, 160, 255), 1, cv::LINE_AA);
  }
  std::vector<unsigned char> jpeg;
  vision::media_module().encode_image(".jpg", canvas, 80, jpeg);
  return "data:image/jpeg;base64," + base64(jpeg);
}

std::string join(const std::vector<std::string>& parts) {
  std::string out;
  for (const std::string& part : parts) out += (out.empty() ? "" : ", ") + part;
  return out;
}

// "Written by binbow 0.9.0 on 2026-11-29T10:26:19Z: binbow evaluate ...",
// as much of it as is known; nothing when nothing is.
std::string provenance_paragraph(const std::string& id, const std::string& lead,
                                 const Provenance& provenance) {
  if (provenance.empty()) return "";
  std::string text = "<p class='provenance' id='" + id + "'>" + lead;
  if (!provenance.binbow_version.empty()) text += " binbow " + escape(provenance.binbow_version);
  if (!provenance.date.empty()) text += " on " + escape(provenance.date);
  if (!provenance.command.empty()) text += ": <code>" + escape(provenance.command) + "</code>";
  return text + "</p>\n";
}

// "α" for alpha; other parameters by their name.
std::string parameter_symbol(const std::string& parameter) {
  return parameter == "alpha" ? "α" : parameter;
}

std::string parameter_value(double value) {
  return format("%.4g", value);
}

// The swept values `here` (drawn at one point) as a label: "0.5", or
// "0.5, 0.8–0.9" where 0.8 and 0.9 are neighbours among all the values
// `swept` (sorted) and 0.5 is not.
std::string point_values(std::vector<double> here, const std::vector<double>& swept) {
  std::sort(here.begin(), here.end());
  std::string text;
  for (std::size_t first = 0; first < here.size();) {
    // The run of `here` that follows `swept` without a gap.
    std::size_t rank = static_cast<std::size_t>(
        std::lower_bound(swept.begin(), swept.end(), here[first]) - swept.begin());
    std::size_t last = first;
    while (last + 1 < here.size() && rank + 1 < swept.size() && swept[rank + 1] == here[last + 1]) {
      ++last;
      ++rank;
    }
    if (!text.empty()) text += ", ";
    text += parameter_value(here[first]);
    if (last > first) text += (last == first + 1 ? ", " : "–") + parameter_value(here[last]);
    first = last + 1;
  }
  return text;
}

std::string pr_curve_svg(const LoopReport& report) {
  const int w = 640, h = 470, left = 60, right = 80, top = 20, bottom = 90;
  const double pw = w - left - right, ph = h - top - bottom;
  const auto x = [&](double recall) { return left + recall * pw; };
  const auto y = [&](double precision) { return top + (1 - precision) * ph; };
  std::ostringstream svg;
  svg << "<svg xmlns='http://www.w3.org/2000/svg' width='" << w << "' height='" << h
      << "' viewBox='0 0 " << w << ' ' << h << "' role='img' aria-label='precision-recall curve'>"
      << "<rect x='" << left << "' y='" << top << "' width='" << pw << "' height='" << ph
      << "' fill='#fafafa' stroke='#888'/>";
  for (int i = 0; i <= 10; ++i) {
    const double v = i / 10.0;
    svg << "<line x1='" << x(v) << "' y1='" << top << "' x2='" << x(v) << "' y2='" << top + ph
        << "' stroke='#e4e4e4'/><line x1='" << left << "' y1='" << y(v) << "' x2='" << left + pw
        << "' y2='" << y(v) << "' stroke='#e4e4e4'/>";
    if (i % 2 == 0)
      svg << "<text x='" << x(v) << "' y='" << top + ph + 16
          << "' font-size='11' text-anchor='middle'>" << format("%.1f", v) << "</text><text x='"
          << left - 6 << "' y='" << y(v) + 4 << "' font-size='11' text-anchor='end'>"
          << format("%.1f", v) << "</text>";
  }
  svg << "<text x='" << left + pw / 2 << "' y='" << top + ph + 36
      << "' font-size='13' text-anchor='middle'>recall</text><text x='15' y='" << top + ph / 2
      << "' font-size='13' text-anchor='middle' transform='rotate(-90 15 " << top + ph / 2
      << ")'>precision</text>";
  const std::vector<PrCurvePoint> points = curve_in_recall_order(report.curve);
  const std::string symbol = escape(parameter_symbol(report.curve_parameter));
  if (!points.empty()) {
    svg << "<polyline fill='none' stroke='#1f5fbf' stroke-width='2' points='";
    for (const auto& p : points) svg << x(p.result.recall) << ',' << y(p.result.precision) << ' ';
    svg << "'/>";
    // Points at the same place share one label that names each of their
    // values: a range a–b only for values that are neighbours in the sweep,
    // never one that spans a value drawn elsewhere.
    // Labels run downwards from their point, pushed right where points are
    // closer than a line of text, with a leader line back to the point.
    std::vector<double> swept;
    for (const auto& p : points) swept.push_back(p.parameter);
    std::sort(swept.begin(), swept.end());
    constexpr double kLineHeight = 11;
    double previous_label_x = -1e9;
    for (std::size_t first = 0; first < points.size();) {
      std::size_t last = first;
      while (last + 1 < points.size() &&
             points[last + 1].result.recall == points[first].result.recall &&
             points[last + 1].result.precision == points[first].result.precision)
        ++last;
      const auto& p = points[first];
      const double px = x(p.result.recall), py = y(p.result.precision);
      std::vector<double> here;
      for (std::size_t i = first; i <= last; ++i) here.push_back(points[i].parameter);
      const std::string values = point_values(here, swept);
      svg << "<circle cx='" << px << "' cy='" << py << "' r='3.5' fill='#1f5fbf'><title>" << symbol
          << " = " << values << ": precision " << format("%.3f", p.result.precision) << ", recall "
          << format("%.3f", p.result.recall) << ", " << p.result.detections
          << " detections</title></circle>";
      const double label_x = std::max(px, previous_label_x + kLineHeight);
      previous_label_x = label_x;
      // In the lower half a label runs upwards, so that it stays inside the
      // plot, clear of the axis labels and the legend.
      const double direction = py > top + ph / 2 ? -1 : 1;
      svg << "<line x1='" << px << "' y1='" << py + 4 * direction << "' x2='" << label_x << "' y2='"
          << py + 14 * direction
          << "' stroke='#9ab'/><text class='pt' font-size='10' fill='#1f3f7f' transform='translate("
          << label_x - 4 * direction << ' ' << py + 16 * direction << ") rotate(" << 90 * direction
          << ")'>" << symbol << '=' << values << "</text>";
      first = last + 1;
    }
  }
  if (const PrCurvePoint* best = full_precision_point(report.curve))
    svg << "<circle id='full-precision-point' cx='" << x(best->result.recall) << "' cy='"
        << y(best->result.precision)
        << "' r='7' fill='none' stroke='#17702b' stroke-width='2'><title>recall at 100% "
           "precision: "
        << format("%.3f", best->result.recall) << " at " << symbol << " = "
        << parameter_value(best->parameter) << "</title></circle>";
  if (report.has_result)
    svg << "<circle cx='" << x(report.result.recall) << "' cy='" << y(report.result.precision)
        << "' r='6' fill='none' stroke='#d03030' stroke-width='2'><title>this run: precision "
        << format("%.3f", report.result.precision) << ", recall "
        << format("%.3f", report.result.recall) << "</title></circle>";
  // Legend: an entry only for a mark the chart draws.
  const double ly = h - 22;
  double lx = left;
  const auto legend_entry = [&](const std::string& marker_style, double radius,
                                const std::string& label) {
    const double text_x = lx + 2 * radius + 8;  // clear of the marker's stroke
    svg << "<g class='legend'><circle cx='" << lx + radius + 1 << "' cy='" << ly << "' r='"
        << radius << "' " << marker_style << "/><text x='" << text_x << "' y='" << ly + 4
        << "' font-size='11'>" << label << "</text></g>";
    // About 6 px a character at 11 px, then a gap.
    lx = text_x + 6.2 * static_cast<double>(label.size()) + 24;
  };
  if (!points.empty()) legend_entry("fill='#1f5fbf'", 3.5, "swept " + symbol);
  if (report.has_result)
    legend_entry("fill='none' stroke='#d03030' stroke-width='2'", 6, "this run");
  if (full_precision_point(report.curve) != nullptr)
    legend_entry("fill='none' stroke='#17702b' stroke-width='2'", 7,
                 "highest recall at 100% precision");
  svg << "</svg>";
  return svg.str();
}

// What each status means for a missed loop, for the reader of the table.
const char* status_explanation(const std::string& status) {
  static const std::pair<const char*, const char*> explanations[] = {
      {"loop-detected", "a loop was accepted, with the wrong image"},
      {"no-database-results", "no earlier image outside dislocal shares a word (or no features)"},
      {"low-normalisation-score",
       "s(v_t, v_t−Δt) below min_normalisation_score: the frame was skipped"},
      {"low-scores", "no candidate reached α"},
      {"no-islands", "no island long enough"},
      {"no-temporal-consistency", "the best island disagreed with the previous queries' islands"},
      {"no-geometric-consistency",
       "too few RANSAC inliers (min_inliers) for a fundamental matrix with the candidate"},
  };
  for (const auto& [name, text] : explanations)
    if (status == name) return text;
  return "";
}

// Tick spacing in frames: 1, 2 or 5 × 10^k, about `ticks` ticks over `frames`.
std::size_t tick_step(std::size_t frames, std::size_t ticks) {
  std::size_t step = 1;
  while (true)
    for (const std::size_t m : {1, 2, 5}) {
      if (frames / (step * m) <= ticks) return step * m;
      if (m == 5) step *= 10;
    }
}

}  // namespace

std::vector<unsigned char> similarity_png(const LoopReport& report) {
  const SimilarityMatrix& m = report.similarity;
  if (m.empty()) return {};
  const int cells = static_cast<int>(m.cells);
  const int zoom = std::max(1, 700 / cells);  // pixels per cell
  const int side = cells * zoom;
  const int left = 70, top = 46, bottom = 150;
  const int width = std::max(left + side + 30, 760);
  cv::Mat canvas(top + side + bottom, width, CV_8UC3, cv::Scalar(255, 255, 255));
  const auto colour = [](int r, int g, int b) { return cv::Scalar(b, g, r); };
  const cv::Scalar ink = colour(40, 40, 40);
  const auto text = [&](const std::string& t, cv::Point at, double size = 0.42,
                        cv::Scalar c = cv::Scalar(40, 40, 40)) {
    cv::putText(canvas, t, at, cv::FONT_HERSHEY_SIMPLEX, size, c, 1, cv::LINE_AA);
  };
  const auto text_width = [](const std::string& t, double size = 0.42) {
    int baseline = 0;
    return cv::getTextSize(t, cv::FONT_HERSHEY_SIMPLEX, size, 1, &baseline).width;
  };

  // Scores shown up to a high quantile, so that a few near-duplicate
  // neighbours do not wash out the loops.
  std::vector<float> nonzero;
  for (float v : m.scores)
    if (v > 0) nonzero.push_back(v);
  float full = 1;
  if (!nonzero.empty()) {
    const std::size_t q = std::min(nonzero.size() - 1, nonzero.size() * 98 / 100);
    std::nth_element(nonzero.begin(), nonzero.begin() + static_cast<long>(q), nonzero.end());
    full = std::max(nonzero[q], 1e-6f);
  }
  std::vector<char> truth_cells(m.cells * m.cells, 0);
  if (report.truth.frames() > 0)
    for (const std::size_t q : report.truth.loop_queries()) {
      if (q >= m.frames) break;
      for (const FrameRange& range : report.truth.earlier_match_ranges(q))
        for (std::size_t c = m.cell(range.first); c <= m.cell(range.end - 1); ++c)
          truth_cells[m.cell(q) * m.cells + c] = 1;
    }
  const auto mix = [](const cv::Vec3b& a, const cv::Vec3b& b, double t) {
    cv::Vec3b out;
    for (int i = 0; i < 3; ++i) out[i] = cv::saturate_cast<uchar>(a[i] + (b[i] - a[i]) * t);
    return out;
  };
  const cv::Vec3b white(255, 255, 255), black(25, 25, 25), light_blue(250, 200, 150),
      dark_blue(110, 35, 10);
  cv::Mat plot(side, side, CV_8UC3, cv::Scalar(255, 255, 255));
  for (int r = 0; r < cells; ++r)
    for (int c = 0; c <= r; ++c) {
      const double v = std::min(1.0, double(m.at(r, c)) / full);
      const cv::Vec3b pixel =
          truth_cells[r * m.cells + c] ? mix(light_blue, dark_blue, v) : mix(white, black, v);
      plot(cv::Rect(c * zoom, r * zoom, zoom, zoom))
          .setTo(cv::Scalar(pixel[0], pixel[1], pixel[2]));
    }
  plot.copyTo(canvas(cv::Rect(left, top, side, side)));
  cv::rectangle(canvas, cv::Rect(left - 1, top - 1, side + 2, side + 2), colour(140, 140, 140));
  cv::line(canvas, {left, top}, {left + side, top + side}, colour(190, 190, 190), 1, cv::LINE_AA);

  const auto centre = [&](std::size_t query, std::size_t match) {
    return cv::Point(left + int(m.cell(match)) * zoom + zoom / 2,
                     top + int(m.cell(query)) * zoom + zoom / 2);
  };
  // Marks grow with the cells, but stay small when cells are single pixels,
  // or thousands of loops would cover the matrix.
  const int radius = zoom >= 4 ? zoom / 2 + 2 : 2;
  const int stroke = zoom >= 4 ? 2 : 1;
  const cv::Scalar green = colour(20, 170, 40), red = colour(225, 20, 20),
                   orange = colour(255, 140, 0), unjudged = colour(170, 40, 230);
  const bool known_truth = report.truth.frames() > 0;
  // The marks drawn, for the legend.
  struct {
    int true_loops = 0, false_loops = 0, unjudged_loops = 0, missed_loops = 0,
        missed_candidates = 0;
  } drawn;
  for (const MissedLoop& miss : report.missed) {
    if (miss.query >= m.frames) continue;
    const int y = top + int(m.cell(miss.query)) * zoom + zoom / 2;
    const std::vector<cv::Point> arrow = {{left - 12, y - 4}, {left - 4, y}, {left - 12, y + 4}};
    cv::fillConvexPoly(canvas, arrow, orange, cv::LINE_AA);
    ++drawn.missed_loops;
    if (miss.match >= 0 && static_cast<std::size_t>(miss.match) < m.frames) {
      cv::drawMarker(canvas, centre(miss.query, static_cast<std::size_t>(miss.match)), orange,
                     cv::MARKER_TILTED_CROSS, 2 * radius, stroke, cv::LINE_AA);
      ++drawn.missed_candidates;
    }
  }
  for (const ReportLoop& loop : report.loops) {
    const Detection& d = loop.detection;
    if (d.query >= m.frames || d.match >= m.frames) continue;
    cv::circle(canvas, centre(d.query, d.match), radius,
               loop.verdict == 1   ? green
               : loop.verdict == 0 ? red
                                   : unjudged,
               stroke, cv::LINE_AA);
    ++(loop.verdict == 1   ? drawn.true_loops
       : loop.verdict == 0 ? drawn.false_loops
                           : drawn.unjudged_loops);
  }

  // Axes: frame numbers, query i down, earlier image j across.
  const std::size_t step = tick_step(m.frames, 10);
  for (std::size_t f = 0; f < m.frames; f += step) {
    const int at = int(double(f) / double(m.bin) * zoom + zoom / 2.0);
    const std::string label = std::to_string(f);
    cv::line(canvas, {left + at, top + side + 1}, {left + at, top + side + 5}, ink);
    text(label, {left + at - text_width(label) / 2, top + side + 18});
    cv::line(canvas, {left - 16, top + at}, {left - 20, top + at}, ink);
    text(label, {left - 24 - text_width(label), top + at + 5});
  }
  text("earlier image j",
       {left + side / 2 - text_width("earlier image j", 0.5) / 2, top + side + 38}, 0.5);
  text("query i", {8, top - 12}, 0.5);
  text("Similarity s(v_i, v_j), i > j", {left + side / 2 - 110, 22}, 0.55);

  // Legend: the score scale, then the marks.
  int y = top + side + 62;
  const int bar = 160;
  for (int i = 0; i < bar; ++i) {
    const double t = double(i) / (bar - 1);
    const cv::Vec3b g = mix(white, black, t), b = mix(light_blue, dark_blue, t);
    cv::line(canvas, {left + i, y - 10}, {left + i, y}, cv::Scalar(g[0], g[1], g[2]));
    if (known_truth)
      cv::line(canvas, {left + i, y + 6}, {left + i, y + 16}, cv::Scalar(b[0], b[1], b[2]));
  }
  cv::rectangle(canvas, cv::Rect(left - 1, y - 11, bar + 2, 12), colour(140, 140, 140));
  text("0", {left - 14, y});
  const std::string scale_end = format(">= %.3g", full);
  text(scale_end, {left + bar + 6, y});
  if (known_truth) {
    cv::rectangle(canvas, cv::Rect(left - 1, y + 5, bar + 2, 12), colour(140, 140, 140));
    // Past the scale's end value, whatever its width, so that they never touch.
    const int names_x = left + bar + 6 + text_width(scale_end) + 24;
    text("not the same place", {names_x, y});
    text("same place (ground truth)", {names_x, y + 16});
  }
  // An entry for each kind of mark the matrix shows, none for marks it lacks.
  y += 42;
  int x = left;
  const auto entry = [&](const std::string& label, int marker_width) {
    text(label, {x + marker_width, y});
    x += marker_width + text_width(label) + 24;
  };
  if (drawn.true_loops > 0) {
    cv::circle(canvas, {x + 6, y - 4}, 6, green, 2, cv::LINE_AA);
    entry("true loop", 18);
  }
  if (drawn.false_loops > 0) {
    cv::circle(canvas, {x + 6, y - 4}, 6, red, 2, cv::LINE_AA);
    entry("false loop", 18);
  }
  if (drawn.unjudged_loops > 0) {
    cv::circle(canvas, {x + 6, y - 4}, 6, unjudged, 2, cv::LINE_AA);
    entry("loop detected (no ground truth given: evaluate --report judges them)", 18);
  }
  if (drawn.missed_candidates > 0) {
    cv::drawMarker(canvas, {x + 6, y - 4}, orange, cv::MARKER_TILTED_CROSS, 12, 2, cv::LINE_AA);
    entry("missed loop: its best candidate", 18);
  }
  if (drawn.missed_loops > 0) {
    const std::vector<cv::Point> arrow = {{x, y - 8}, {x + 8, y - 4}, {x, y}};
    cv::fillConvexPoly(canvas, arrow, orange, cv::LINE_AA);
    entry("missed loop", 14);
  }
  y += 26;
  std::string note = std::to_string(m.frames) + " frames";
  if (m.bin > 1)
    note += "; one cell = " + std::to_string(m.bin) + " x " + std::to_string(m.bin) +
            " frames, their highest score";
  if (!m.every_query) note += "; sampled query rows";
  text(note, {left, y}, 0.4, colour(100, 100, 100));

  std::vector<unsigned char> bytes;
  vision::media_module().encode_image(".png", canvas, -1, bytes);
  return bytes;
}

namespace {

std::string similarity_section(const LoopReport& report, const std::string& directory) {
  const std::vector<unsigned char> png = similarity_png(report);
  const std::string path = (std::filesystem::path(directory) / "similarity.png").string();
  detail::write_file_atomically(path, png.data(), png.size());
  const SimilarityMatrix& m = report.similarity;
  std::ostringstream html;
  html << "<h2 id='similarity-matrix'>Similarity matrix</h2><figure><img id='similarity' "
          "alt='similarity matrix of the sequence with the ground truth and the detections' "
          "src='data:image/png;base64,"
       << base64(png) << "'><figcaption>BoW similarity s(v<sub>i</sub>, v<sub>j</sub>) of each "
       << "query i with every earlier image j (darker: more similar), scored with the run's "
          "vocabulary; "
       << (report.truth.frames() > 0
               ? "ground-truth cells in blue; detections circled (green true, red false); "
                 "missed ground-truth loops marked in orange (their best candidate crossed)."
               : "detections circled in purple.");
  if (m.bin > 1)
    html << " Binned: a cell covers " << m.bin << " × " << m.bin
         << " frames and shows their highest score.";
  if (!m.every_query)
    html << " Only every " << (m.frames + kMaxSimilarityQueries - 1) / kMaxSimilarityQueries
         << "th query row was scored (a bound on the work).";
  html << " Also saved as similarity.png.</figcaption></figure>\n";
  return html.str();
}

std::string sweep_table(const LoopReport& report) {
  const PrCurvePoint* best = full_precision_point(report.curve);
  std::ostringstream html;
  html << "<table id='sweep'><tr><th>" << escape(parameter_symbol(report.curve_parameter))
       << "</th><th>precision</th><th>recall</th><th>detections</th><th>true positives</th>"
          "<th>false positives</th></tr>";
  for (const PrCurvePoint& p : report.curve)
    html << "<tr" << (&p == best ? " class='best'" : "") << "><td class='n'>"
         << parameter_value(p.parameter) << "</td><td class='n'>"
         << format("%.4f", p.result.precision) << "</td><td class='n'>"
         << format("%.4f", p.result.recall) << "</td><td class='n'>" << p.result.detections
         << "</td><td class='n'>" << p.result.true_positives << "</td><td class='n'>"
         << p.result.false_positives << "</td></tr>";
  html << "</table>\n";
  return html.str();
}

// "31–35 (5)": the earlier images sharing the query's place.
std::string truth_matches(const GroundTruth& truth, std::size_t query) {
  if (query >= truth.frames()) return "–";
  const Span<FrameRange> ranges = truth.earlier_match_ranges(query);
  if (ranges.empty()) return "–";
  const std::uint32_t first = ranges[0].first, last = ranges[ranges.size() - 1].end - 1;
  std::size_t count = 0;
  for (const FrameRange& range : ranges) count += range.size();
  return first == last ? std::to_string(first)
                       : std::to_string(first) + "–" + std::to_string(last) + " (" +
                             std::to_string(count) + ")";
}

std::string missed_section(const LoopReport& report) {
  std::ostringstream html;
  html << "<h2 id='missed-loops'>Missed loops (" << report.missed.size() << " of "
       << report.result.queries_with_loops << " queries with a ground-truth loop)</h2>";
  if (report.missed.empty()) {
    html << "<p>Every ground-truth loop was found.</p>\n";
    return html.str();
  }
  // Why, in a few words: the count of each status.
  std::vector<std::pair<std::string, std::size_t>> by_status;
  for (const MissedLoop& miss : report.missed) {
    const std::string status = miss.status.empty() ? "unknown" : miss.status;
    auto it = std::find_if(by_status.begin(), by_status.end(),
                           [&](const auto& s) { return s.first == status; });
    if (it == by_status.end())
      by_status.emplace_back(status, 1);
    else
      ++it->second;
  }
  html << "<table id='missed-by-status'><tr><th>status</th><th>missed</th><th>meaning</th></tr>";
  for (const auto& [status, count] : by_status)
    html << "<tr><td class='s'>" << escape(status) << "</td><td class='n'>" << count << "</td><td>"
         << escape(status_explanation(status)) << "</td></tr>";
  html << "</table>";
  const bool known_truth = report.truth.frames() > 0;
  html << "<table id='missed'><tr><th>query</th><th>file</th>"
       << (known_truth ? "<th>ground-truth matches</th>" : "")
       << "<th>features</th><th>status</th><th>best candidate</th><th>candidate right</th>"
          "<th>η</th><th>correspondences</th><th>inliers</th></tr>";
  for (const MissedLoop& miss : report.missed) {
    const char* right = miss.candidate_right == 1   ? "<span class='tp'>yes</span>"
                        : miss.candidate_right == 0 ? "<span class='fp'>no</span>"
                                                    : "–";
    const std::string query = std::to_string(miss.query);
    html << "<tr id='missed-" << miss.query << "'><td class='n'>"
         << (report.has_explanations ? "<a href='#explain-row-" + query + "'>" + query + "</a>"
                                     : query)
         << "</td><td>" << escape(miss.file) << "</td>";
    if (known_truth) html << "<td class='n'>" << truth_matches(report.truth, miss.query) << "</td>";
    html << "<td class='n'>" << (miss.features < 0 ? "unknown" : std::to_string(miss.features))
         << "</td><td class='s'>" << (miss.status.empty() ? "unknown" : escape(miss.status))
         << "</td><td class='n'>" << (miss.match < 0 ? "none" : std::to_string(miss.match))
         << "</td><td>" << right << "</td><td class='n'>"
         << (miss.match < 0 ? "–" : format("%.3f", miss.normalised_score)) << "</td><td class='n'>"
         << (!geometrically_checked(miss) ? "–"
             : miss.correspondences < 0   ? "unknown"
                                          : std::to_string(miss.correspondences))
         << "</td><td class='n'>"
         << (!geometrically_checked(miss) ? "–"
             : miss.inliers < 0           ? "unknown"
                                          : std::to_string(miss.inliers))
         << "</td></tr>";
  }
  html << "</table>\n";
  return html.str();
}

// The two frames of an explained case side by side, rejected
// correspondences in thin red, inliers in green over them, as a data URL.
// Throws FileError if an image cannot be read.
std::string explained_image(const LoopExplanation& e) {
  const cv::Mat query = vision::read_frame(e.query_file, vision::FramePixels::kBgr);
  // No image to pair it with (no candidate at all): the query alone.
  const cv::Mat match = e.match_file.empty()
                            ? cv::Mat(query.rows, 1, CV_8UC3, cv::Scalar(255, 255, 255))
                            : vision::read_frame(e.match_file, vision::FramePixels::kBgr);
  SideBySide pair = side_by_side(query, match);
  cv::Mat& canvas = pair.canvas;
  const double sq = pair.query_scale, sm = pair.match_scale;
  const auto ends = [&](const ExplainedCorrespondence& c) {
    return std::make_pair(
        cv::Point2f(c.points[0] * float(sq), c.points[1] * float(sq)),
        cv::Point2f(c.points[2] * float(sm) + float(pair.match_left), c.points[3] * float(sm)));
  };
  for (const ExplainedCorrespondence& c : e.correspondences)
    if (!c.inlier) {
      const auto [pa, pb] = ends(c);
      cv::line(canvas, pa, pb, cv::Scalar(40, 40, 230), 1, cv::LINE_AA);
      cv::circle(canvas, pa, 2, cv::Scalar(40, 40, 230), cv::FILLED, cv::LINE_AA);
      cv::circle(canvas, pb, 2, cv::Scalar(40, 40, 230), cv::FILLED, cv::LINE_AA);
    }
  // Thick inlier lines while few, so that they stand out; thin when many would merge.
  const int inlier_width =
      std::count_if(e.correspondences.begin(), e.correspondences.end(),
                    [](const ExplainedCorrespondence& c) { return c.inlier; }) > 40
          ? 1
          : 2;
  for (const ExplainedCorrespondence& c : e.correspondences)
    if (c.inlier) {
      const auto [pa, pb] = ends(c);
      cv::line(canvas, pa, pb, cv::Scalar(60, 210, 60), inlier_width, cv::LINE_AA);
      cv::circle(canvas, pa, 3, cv::Scalar(0, 160, 255), 1, cv::LINE_AA);
      cv::circle(canvas, pb, 3, cv::Scalar(0, 160, 255), 1, cv::LINE_AA);
    }
  std::vector<unsigned char> jpeg;
  vision::media_module().encode_image(".jpg", canvas, 85, jpeg);
  return "data:image/jpeg;base64," + base64(jpeg);
}

std::string case_name(const LoopExplanation& e) {
  if (e.false_loop && e.missed) return "false loop, missed";
  return e.false_loop ? "false loop" : "missed";
}

std::string explained_figure(const LoopExplanation& e) {
  std::ostringstream html;
  html << "<figure class='explain' id='explain-" << e.query << "'><figcaption><b>query " << e.query;
  if (e.drawn_match >= 0) html << " ↔ " << e.drawn_match;
  html << "</b> (" << escape(case_name(e))
       << (e.drawn_match >= 0 && e.drawn_match == e.detected_match ? ", the reported loop"
           : e.drawn_match == e.true_match                         ? ", a ground-truth match"
                                                                   : "")
       << "): <span class='why'>" << escape(e.reason) << "</span></figcaption>";
  try {
    html << "<img alt='query " << e.query << " and image " << e.drawn_match << "' src='"
         << explained_image(e) << "'>";
  } catch (const FileError& error) {
    html << "<p>(images not readable: " << escape(error.what()) << ")</p>";
  }
  if (e.has_check) {
    std::size_t inliers = 0;
    for (const ExplainedCorrespondence& c : e.correspondences) inliers += c.inlier;
    html << "<p class='legend'><span style='color:#2a9d2a'>&#9644; inliers</span> (" << inliers
         << " of " << e.check_inliers << " drawn), <span style='color:#e02828'>&#9644; rejected "
         << "correspondences</span> (" << e.correspondences.size() - inliers << " of "
         << e.check_correspondences - e.check_inliers << " drawn)"
         << (e.check_rerun ? "; this check was run for the report with the run's parameters "
                             "(the detector never checked this pair)"
                           : "")
         << "</p><table class='measures'><tr><th>test</th><th>value</th><th>parameter</th>"
            "<th>threshold</th><th>result</th></tr>";
    for (const CheckMeasure& m : e.measures)
      html << "<tr><td>" << escape(m.note.empty() ? m.name : m.name + " (" + m.note + ")")
           << "</td><td class='n'>" << format(m.whole ? "%.0f" : "%.3f", m.value) << "</td><td>"
           << escape(m.parameter) << "</td><td class='n'>"
           << format(m.whole ? "%.0f" : "%.3f", m.threshold) << "</td><td>"
           << (m.passed ? "<span class='tp'>passed</span>" : "<span class='fp'>failed</span>")
           << "</td></tr>";
    html << "</table>";
  }
  html << "<ol class='steps'>";
  for (const std::string& step : e.steps) html << "<li>" << escape(step) << "</li>";
  html << "</ol></figure>\n";
  return html.str();
}

std::string explained_section(const LoopReport& report) {
  const auto& cases = report.explanations;
  std::ostringstream html;
  html << "<h2 id='explained'>Why: every false loop and every miss (" << cases.size() << ")</h2>";
  if (!report.explanations_note.empty())
    html << "<p class='note'>" << escape(report.explanations_note) << "</p>";
  if (cases.empty()) {
    html << "<p>No false loop and no miss.</p>\n";
    return html.str();
  }
  html << "<p>Each case names the stage that accepted the false loop or lost the ground-truth "
          "match, with the numbers it compared (detection re-run with the run's parameters). "
       << "The first " << std::min(cases.size(), kExplainedPictures)
       << " cases are drawn below (at most " << kExplainedPictures
       << "); every case is a row of this table.</p>";
  html << "<table id='explained-table'><tr><th>query</th><th>case</th><th>reported</th>"
          "<th>ground-truth match</th><th>stage</th><th>why</th></tr>";
  for (std::size_t i = 0; i < cases.size(); ++i) {
    const LoopExplanation& e = cases[i];
    const std::string query = std::to_string(e.query);
    html << "<tr id='explain-row-" << e.query << "'><td class='n'>"
         << (i < kExplainedPictures ? "<a href='#explain-" + query + "'>" + query + "</a>" : query)
         << "</td><td>" << (e.false_loop ? "<span class='fp'>" : "<span>") << escape(case_name(e))
         << "</span></td><td class='n'>"
         << (e.detected_match < 0 ? "–" : std::to_string(e.detected_match)) << "</td><td class='n'>"
         << (e.true_match < 0 ? "–" : std::to_string(e.true_match)) << "</td><td class='s'>"
         << to_string(e.stage) << "</td><td>" << escape(e.reason) << "</td></tr>";
  }
  html << "</table>\n";
  for (std::size_t i = 0; i < cases.size() && i < kExplainedPictures; ++i)
    html << explained_figure(cases[i]);
  if (cases.size() > kExplainedPictures)
    html << "<p>Cases after the first " << kExplainedPictures
         << " are listed in the table only, to keep the page small.</p>\n";
  return html.str();
}

}  // namespace

std::string write_loop_report(const std::string& directory, const LoopReport& report) {
  std::error_code error;
  std::filesystem::create_directories(directory, error);
  if (error) throw FileError(directory, "cannot create the report directory: " + error.message());
  std::ostringstream html;
  html << "<!DOCTYPE html>\n<html lang='en'><head><meta charset='utf-8'><title>"
       << escape(report.title) << "</title><style>"
       << "body{font-family:sans-serif;margin:24px;color:#222;max-width:1400px}"
       << "table{border-collapse:collapse;margin:8px 0 20px}td,th{border:1px solid "
          "#ccc;padding:3px 8px;"
       << "text-align:left;font-size:13px}th{background:#f0f0f0}td.n{text-align:right}"
       << ".tp{color:#17702b}.fp{color:#b02020;font-weight:bold}pre{background:#f6f6f6;padding:8px}"
       << "figure{margin:10px 0 18px}figcaption{font-size:13px;max-width:900px}img{max-width:100%}"
       << ".side{display:flex;flex-wrap:wrap;gap:24px;align-items:flex-start}"
       << "tr.best td{background:#e3f4e6;font-weight:bold}td.s{white-space:nowrap}"
       << "figure.explain{border-top:1px solid #ddd;padding-top:8px}figcaption .why{color:#444}"
       << "ol.steps{font-size:13px;margin:4px 0}p.legend{font-size:13px;margin:4px 0}"
       << "p.provenance{font-size:13px;color:#555}p.provenance code{word-break:break-all}"
       << "</style></head><body>\n<h1>" << escape(report.title) << "</h1>\n";
  html << provenance_paragraph("provenance", "Written by", report.provenance);
  html << provenance_paragraph("run-provenance", "Loops detected by", report.run_provenance);

  if (!report.facts.empty()) {
    html << "<table>";
    for (const auto& [key, value] : report.facts)
      html << "<tr><th>" << escape(key) << "</th><td>" << escape(value) << "</td></tr>";
    html << "</table>\n";
  }
  if (report.has_result) {
    const auto& r = report.result;
    html << "<h2>Precision and recall</h2><table id='result'>"
         << "<tr><th>precision</th><td class='n'>" << format("%.4f", r.precision) << "</td></tr>"
         << "<tr><th>recall</th><td class='n'>" << format("%.4f", r.recall) << "</td></tr>"
         << "<tr><th>detections</th><td class='n'>" << r.detections << "</td></tr>"
         << "<tr><th>true positives</th><td class='n'>" << r.true_positives << "</td></tr>"
         << "<tr><th>false positives</th><td class='n'>" << r.false_positives << "</td></tr>"
         << "<tr><th>queries with a ground-truth loop</th><td class='n'>" << r.queries_with_loops
         << "</td></tr></table>\n";
  }
  if (!report.curve.empty() || report.has_result) {
    html << "<h2>Precision–recall curve</h2>";
    if (!report.curve.empty()) {
      html << "<p id='full-precision'>Swept: " << escape(report.curve_parameter) << " ("
           << report.curve.size() << " points), drawn in recall order. Recall at 100% precision: "
           << format("%.4f", report.recall_at_full_precision);
      if (const PrCurvePoint* best = full_precision_point(report.curve)) {
        html << ", reached at " << escape(parameter_symbol(report.curve_parameter)) << " = "
             << parameter_value(best->parameter);
        std::vector<std::string> also;
        for (const PrCurvePoint& p : report.curve)
          if (&p != best && p.result.false_positives == 0 && p.result.detections > 0 &&
              p.result.recall == best->result.recall)
            also.push_back(parameter_value(p.parameter));
        if (!also.empty())
          html << " (also at "
               << (also.size() <= 4 ? join(also) : also.front() + ", …, " + also.back()) << ")";
      }
      html << ".</p>";
    }
    html << "<div class='side'>" << pr_curve_svg(report);
    if (!report.curve.empty()) html << sweep_table(report);
    html << "</div>\n";
  }
  if (!report.similarity.empty()) html << similarity_section(report, directory);
  if (report.has_result) html << missed_section(report);
  if (report.has_explanations) html << explained_section(report);
  if (!report.params_json.empty())
    html << "<h2>Parameters</h2><pre id='params'>" << escape(report.params_json) << "</pre>\n";
  if (!report.timing.empty()) {
    html << "<h2>Time per frame</h2><table id='timing'><tr><th>stage</th><th>mean ms</th>"
         << "<th>median ms</th><th>max ms</th></tr>";
    for (const StageTiming& t : report.timing)
      html << "<tr><td>" << escape(t.stage) << "</td><td class='n'>" << format("%.3f", t.mean())
           << "</td><td class='n'>" << format("%.3f", t.median()) << "</td><td class='n'>"
           << format("%.3f", t.max()) << "</td></tr>";
    html << "</table>\n";
  }
  html << "<h2>Detections (" << report.loops.size() << ")</h2><table id='detections'><tr>"
       << "<th>query</th><th>match</th><th>query file</th><th>match file</th><th>score</th>"
       << "<th>inliers</th><th>verdict</th></tr>";
  for (const ReportLoop& loop : report.loops) {
    const auto& d = loop.detection;
    const char* verdict = loop.verdict == 1   ? "<span class='tp'>true</span>"
                          : loop.verdict == 0 ? "<span class='fp'>false</span>"
                                              : "–";
    html << "<tr><td class='n'><a href='#loop-" << d.query << "-" << d.match << "'>" << d.query
         << "</a></td><td class='n'>" << d.match << "</td><td>" << escape(d.query_file)
         << "</td><td>" << escape(d.match_file) << "</td><td class='n'>" << format("%.4f", d.score)
         << "</td><td class='n'>" << d.inliers << "</td><td>" << verdict << "</td></tr>";
  }
  html << "</table>\n<h2>Loops</h2>\n";
  std::size_t drawn = 0;
  for (const ReportLoop& loop : report.loops) {
    // The table above still lists every loop.
    if (drawn == kDrawnLoops) {
      html << "<p>Only the first " << kDrawnLoops << " loops are drawn.</p>";
      break;
    }
    ++drawn;
    const auto& d = loop.detection;
    html << "<figure id='loop-" << d.query << "-" << d.match << "'>";
    try {
      const std::string image = pair_image(loop);
      html << "<img alt='query " << d.query << " and match " << d.match << "' src='" << image
           << "'>";
    } catch (const FileError& e) {
      html << "<p>(images not readable: " << escape(e.what()) << ")</p>";
    }
    html << "<figcaption>query " << d.query << " (" << escape(d.query_file) << ") ↔ match "
         << d.match << " (" << escape(d.match_file)
         << "): " << std::min(loop.inliers.size(), kDrawnInliers) << " of " << d.inliers
         << " inliers drawn, score " << format("%.4f", d.score)
         << (loop.verdict == 1   ? ", true loop"
             : loop.verdict == 0 ? ", FALSE loop"
                                 : "")
         << "</figcaption></figure>\n";
  }
  html << "<p style='font-size:12px;color:#777'>Generated by binbow.</p></body></html>\n";
  const std::string path = (std::filesystem::path(directory) / "index.html").string();
  const std::string text = html.str();
  detail::write_file_atomically(path, text.data(), text.size());
  return path;
}

LoopReport make_loop_report(const std::vector<SequenceFrame>& frames,
                            const LoopDetectorParams& params, const GroundTruth* truth) {
  LoopReport report;
  report.title = "binbow loop detection";
  report.params_json = params.to_json();
  report.timing = stage_timings(frames);
  std::vector<Detection> detections;
  for (const SequenceFrame& frame : frames) {
    const LoopResult& r = frame.result;
    if (!r.detection()) continue;
    detections.push_back(
        {r.query, r.match, frame.file, frame.match_file, r.normalised_score, r.inliers.size()});
    const int verdict = truth == nullptr ? -1 : truth->is_loop(r.query, r.match) ? 1 : 0;
    report.loops.push_back({detections.back(), frame.inlier_points, verdict});
  }
  report.facts = {{"frames", std::to_string(frames.size())},
                  {"loops", std::to_string(detections.size())}};
  if (truth != nullptr) {
    report.has_result = true;
    report.result = evaluate_detections(detections, *truth);
    std::vector<FrameRecord> records;
    records.reserve(frames.size());
    for (const SequenceFrame& frame : frames) records.push_back(frame_record(frame));
    report.missed = missed_loops(records, detections, *truth);
    report.truth = *truth;
  }
  return report;
}

LoopReport make_loop_report(const std::vector<SequenceFrame>& frames,
                            const LoopDetectorParams& params, const GroundTruth* truth,
                            const SimilarityMatrix& similarity) {
  LoopReport report = make_loop_report(frames, params, truth);
  report.similarity = similarity;
  return report;
}

}  // namespace binbow::loop
