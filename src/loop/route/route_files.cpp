#include <cinttypes>
#include <cstdio>
#include <filesystem>
#include <string>
#include <vector>

#include "binbow/error.h"
#include "binbow/loop/route.h"
#include "binbow/vision/image_source.h"
#include "core/file_io.h"
#include "core/output_path.h"
#include "vision/media_module.h"

namespace binbow::loop {
namespace {

namespace fs = std::filesystem;

// Fixed formats (no locale, %.17g round-trips a double), so the same route
// gives the same bytes.
std::string csv_number(double v) {
  char text[32];
  std::snprintf(text, sizeof text, "%.17g", v);
  return text;
}

// A CSV field: quoted when it holds a comma, a quote or a line break.
std::string csv_field(const std::string& s) {
  if (s.find_first_of(",\"\r\n") == std::string::npos) return s;
  std::string quoted = "\"";
  for (const char c : s) quoted += c == '"' ? std::string("\"\"") : std::string(1, c);
  return quoted + "\"";
}

void write_text(const std::string& path, const std::string& text) {
  detail::write_file_atomically(path, text.data(), text.size());
}

std::string route_csv(const Route& route) {
  std::string text =
      "frame,place,visit,revisit,photograph,h00,h01,h02,h10,h11,h12,h20,h21,h22,gain,bias,gamma,"
      "blur_sigma,noise_sigma,noise_seed\n";
  for (std::size_t i = 0; i < route.frames.size(); ++i) {
    const RouteFrame& f = route.frames[i];
    text += std::to_string(i) + "," + std::to_string(f.place) + "," + std::to_string(f.visit) +
            "," + (f.revisit ? "1" : "0") + "," + std::to_string(route.places[f.place].photograph);
    for (const double h : f.homography) text += "," + csv_number(h);
    for (const double v : {f.gain, f.bias, f.gamma, f.blur_sigma, f.noise_sigma})
      text += "," + csv_number(v);
    text += "," + std::to_string(f.noise_seed) + "\n";
  }
  return text;
}

std::string places_csv(const Route& route) {
  std::string text = "place,photograph,file,x,y,width,height\n";
  for (std::size_t p = 0; p < route.places.size(); ++p) {
    const RoutePlace& place = route.places[p];
    text += std::to_string(p) + "," + std::to_string(place.photograph) + "," +
            csv_field(route.photographs[place.photograph]) + "," + csv_number(place.cell.x) + "," +
            csv_number(place.cell.y) + "," + csv_number(place.cell.width) + "," +
            csv_number(place.cell.height) + "\n";
  }
  return text;
}

std::string ground_truth_text(const Route& route) {
  std::string text =
      "# binbow make-route ground truth, 0-based: query match = frames/<query>.jpg shows the "
      "place frames/<match>.jpg shows, on another visit\n";
  for (const auto& [query, match] : route.loop_pairs())
    text += std::to_string(query) + " " + std::to_string(match) + "\n";
  return text;
}

std::string frame_name(std::size_t index) {
  char name[32];
  std::snprintf(name, sizeof name, "%06zu.jpg", index);
  return name;
}

void write_frame(const std::string& path, const cv::Mat& image, int quality) {
  std::vector<std::uint8_t> bytes;
  if (!vision::media_module().encode_image(".jpg", image, quality, bytes))
    throw FileError(path, "cannot encode the frame as JPEG");
  // Plain writes: thousands of frames, each synced, would take minutes;
  // ground_truth.txt, written last and atomically, marks the route complete.
  std::FILE* file = std::fopen(path.c_str(), "wb");
  if (!file) throw FileError(path, "cannot create the file");
  const bool written = std::fwrite(bytes.data(), 1, bytes.size(), file) == bytes.size();
  if (std::fclose(file) != 0 || !written) throw FileError(path, "cannot write the file");
}

}  // namespace

Route make_route(const std::vector<std::string>& photographs, const RouteOptions& options,
                 const std::string& directory, const RouteProgress& progress) {
  check_route_options(options);
  std::error_code error;
  if (fs::exists(directory, error) && !fs::is_empty(directory, error))
    throw FileError(directory, "is not empty; a route is written into a new or empty directory");
  std::vector<cv::Mat> images;
  std::vector<std::string> names;
  vision::ImageSource source(photographs);
  for (vision::Frame frame; source.next(frame);) {
    images.push_back(frame.image);
    names.push_back(frame.name);
  }
  std::vector<RoutePlace> places = route_places(images, options);
  if (places.empty())
    throw InvalidArgument("make-route: no place in the " + std::to_string(images.size()) +
                          " photographs: each needs a cell of " +
                          std::to_string(options.cell_margin) + " x the frame size with " +
                          std::to_string(options.min_place_corners) +
                          " corners (larger or more textured photographs, or smaller frames)");
  Route route = plan_route(std::move(names), std::move(places), options);
  const std::uint64_t pairs = route.loop_pair_count();
  if (pairs > kMaxRoutePairs)
    throw InvalidArgument("make-route: the ground truth would list " + std::to_string(pairs) +
                          " pairs, more than " + std::to_string(kMaxRoutePairs) + ": " +
                          std::to_string(route.places.size()) +
                          " places are revisited too often in " + std::to_string(options.frames) +
                          " frames (fewer frames, or more photographs)");

  detail::prepare_output_directory(directory);
  const std::string frames = (fs::path(directory) / "frames").string();
  detail::prepare_output_directory(frames);
  for (std::size_t i = 0; i < route.frames.size(); ++i) {
    const cv::Mat& photograph = images[route.places[route.frames[i].place].photograph];
    write_frame((fs::path(frames) / frame_name(i)).string(),
                render_route_frame(route, i, photograph), options.jpeg_quality);
    if (progress) progress(i + 1, route.frames.size());
  }
  write_text((fs::path(directory) / "route.csv").string(), route_csv(route));
  write_text((fs::path(directory) / "places.csv").string(), places_csv(route));
  write_text((fs::path(directory) / "ground_truth.txt").string(), ground_truth_text(route));
  return route;
}

}  // namespace binbow::loop
