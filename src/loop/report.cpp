#include "binbow/loop/report.h"

#include <algorithm>
#include <cstdio>
#include <filesystem>
#include <sstream>

#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "binbow/error.h"
#include "binbow/vision/image_source.h"
#include "core/file_io.h"

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

// The two images scaled to one height, side by side, inliers as lines, as a
// data URL. Throws FileError if an image cannot be read.
std::string pair_image(const ReportLoop& loop) {
  // By name: a file, or "video#N" for a frame of a video.
  const cv::Mat query = vision::read_frame(loop.detection.query_file, vision::FramePixels::kBgr);
  const cv::Mat match = vision::read_frame(loop.detection.match_file, vision::FramePixels::kBgr);
  const double sq = double(kPairHeight) / query.rows, sm = double(kPairHeight) / match.rows;
  cv::Mat a, b;
  cv::resize(query, a, cv::Size(std::max(1, int(query.cols * sq)), kPairHeight), 0, 0,
             cv::INTER_AREA);
  cv::resize(match, b, cv::Size(std::max(1, int(match.cols * sm)), kPairHeight), 0, 0,
             cv::INTER_AREA);
  cv::Mat canvas(kPairHeight, a.cols + b.cols + 8, CV_8UC3, cv::Scalar(255, 255, 255));
  a.copyTo(canvas(cv::Rect(0, 0, a.cols, a.rows)));
  b.copyTo(canvas(cv::Rect(a.cols + 8, 0, b.cols, b.rows)));
  const std::size_t drawn = std::min(loop.inliers.size(), kDrawnInliers);
  for (std::size_t i = 0; i < drawn; ++i) {
    const auto& p = loop.inliers[i * loop.inliers.size() / drawn];
    const cv::Point2f pa(p[0] * float(sq), p[1] * float(sq));
    const cv::Point2f pb(p[2] * float(sm) + float(a.cols + 8), p[3] * float(sm));
    cv::line(canvas, pa, pb, cv::Scalar(60, 200, 60), 1, cv::LINE_AA);
    cv::circle(canvas, pa, 3, cv::Scalar(0, 160, 255), 1, cv::LINE_AA);
    cv::circle(canvas, pb, 3, cv::Scalar(0, 160, 255), 1, cv::LINE_AA);
  }
  std::vector<unsigned char> jpeg;
  cv::imencode(".jpg", canvas, jpeg, {cv::IMWRITE_JPEG_QUALITY, 80});
  return "data:image/jpeg;base64," + base64(jpeg);
}

std::string pr_curve_svg(const LoopReport& report) {
  const int w = 520, h = 400, left = 60, right = 20, top = 20, bottom = 50;
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
  svg << "<text x='" << left + pw / 2 << "' y='" << h - 10
      << "' font-size='13' text-anchor='middle'>recall</text><text x='15' y='" << top + ph / 2
      << "' font-size='13' text-anchor='middle' transform='rotate(-90 15 " << top + ph / 2
      << ")'>precision</text>";
  std::vector<PrCurvePoint> points = report.curve;
  std::stable_sort(points.begin(), points.end(), [](const auto& a, const auto& b) {
    return a.result.recall < b.result.recall ||
           (a.result.recall == b.result.recall && a.result.precision > b.result.precision);
  });
  if (!points.empty()) {
    svg << "<polyline fill='none' stroke='#1f5fbf' stroke-width='2' points='";
    for (const auto& p : points) svg << x(p.result.recall) << ',' << y(p.result.precision) << ' ';
    svg << "'/>";
    for (const auto& p : points)
      svg << "<circle cx='" << x(p.result.recall) << "' cy='" << y(p.result.precision)
          << "' r='3' fill='#1f5fbf'><title>" << escape(report.curve_parameter) << " = "
          << format("%.3g", p.parameter) << ": precision " << format("%.3f", p.result.precision)
          << ", recall " << format("%.3f", p.result.recall) << "</title></circle>";
  }
  if (report.has_result)
    svg << "<circle cx='" << x(report.result.recall) << "' cy='" << y(report.result.precision)
        << "' r='6' fill='none' stroke='#d03030' stroke-width='2'><title>this run: precision "
        << format("%.3f", report.result.precision) << ", recall "
        << format("%.3f", report.result.recall) << "</title></circle>";
  svg << "</svg>";
  return svg.str();
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
       << "figure{margin:10px 0 18px}figcaption{font-size:13px}img{max-width:100%}"
       << "</style></head><body>\n<h1>" << escape(report.title) << "</h1>\n";

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
    if (!report.curve.empty())
      html << "<p>Swept: " << escape(report.curve_parameter) << " (" << report.curve.size()
           << " points). Recall at 100% precision: "
           << format("%.4f", report.recall_at_full_precision) << ".</p>";
    html << pr_curve_svg(report) << "\n";
  }
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
  }
  return report;
}

}  // namespace binbow::loop
