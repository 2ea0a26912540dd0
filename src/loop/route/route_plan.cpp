#include <algorithm>
#include <cmath>
#include <limits>
#include <opencv2/features2d.hpp>
#include <random>
#include <string>

#include "binbow/error.h"
#include "binbow/loop/route.h"

namespace binbow::loop {
namespace {

constexpr double kPi = 3.14159265358979323846;

// std::mt19937_64's output is fixed by the standard; the standard
// distributions are not, so these are written out.
class RouteRandom {
 public:
  explicit RouteRandom(std::uint64_t seed) : engine_(seed) {}
  double uniform() { return static_cast<double>(engine_() >> 11) * 0x1.0p-53; }  // [0, 1)
  double uniform(double low, double high) { return low + (high - low) * uniform(); }
  double symmetric(double half_width) { return uniform(-half_width, half_width); }
  std::size_t index(std::size_t count) {  // [0, count), count > 0
    return std::min(count - 1, static_cast<std::size_t>(uniform() * static_cast<double>(count)));
  }
  std::uint64_t bits() { return engine_(); }

 private:
  std::mt19937_64 engine_;
};

// A camera pose relative to its place: the view's centre offset (in frame
// sizes), zoom (view size / frame size; > 1 sees more), roll (radians) and
// perspective (the depth slope across the half width and height).
struct Pose {
  double pan_x = 0, pan_y = 0, zoom = 1, roll = 0, tilt_x = 0, tilt_y = 0;
};

Pose lerp(const Pose& a, const Pose& b, double t) {
  const auto mix = [t](double u, double v) { return u + (v - u) * t; };
  return {mix(a.pan_x, b.pan_x), mix(a.pan_y, b.pan_y),   mix(a.zoom, b.zoom),
          mix(a.roll, b.roll),   mix(a.tilt_x, b.tilt_x), mix(a.tilt_y, b.tilt_y)};
}

// Frame f of a visit of `length` frames, moving from `start` to `end`.
Pose visit_pose(const Pose& start, const Pose& end, std::size_t f, std::size_t length) {
  return lerp(start, end,
              length > 1 ? static_cast<double>(f) / static_cast<double>(length - 1) : 0.0);
}

Pose scaled(const Pose& p, double s) {
  return {p.pan_x * s, p.pan_y * s, 1 + (p.zoom - 1) * s, p.roll * s, p.tilt_x * s, p.tilt_y * s};
}

using Matrix = std::array<double, 9>;

Matrix multiply(const Matrix& a, const Matrix& b) {
  Matrix c{};
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j)
      for (int k = 0; k < 3; ++k) c[i * 3 + j] += a[i * 3 + k] * b[k * 3 + j];
  return c;
}

// Frame pixels → photograph pixels: centre the frame, tilt, scale to the
// view, roll, move to the place's centre plus the pan.
Matrix homography(const Pose& p, const cv::Rect2d& cell, int width, int height) {
  const double hw = width / 2.0, hh = height / 2.0;
  const Matrix centre{1, 0, -hw, 0, 1, -hh, 0, 0, 1};
  const Matrix tilt{1, 0, 0, 0, 1, 0, p.tilt_x / hw, p.tilt_y / hh, 1};
  const double c = std::cos(p.roll) * p.zoom, s = std::sin(p.roll) * p.zoom;
  const Matrix rotate{c, -s, 0, s, c, 0, 0, 0, 1};
  const double x = cell.x + cell.width / 2 + p.pan_x * width;
  const double y = cell.y + cell.height / 2 + p.pan_y * height;
  const Matrix move{1, 0, x, 0, 1, y, 0, 0, 1};
  return multiply(move, multiply(rotate, multiply(tilt, centre)));
}

cv::Point2d apply(const Matrix& h, double x, double y) {
  const double w = h[6] * x + h[7] * y + h[8];
  return {(h[0] * x + h[1] * y + h[2]) / w, (h[3] * x + h[4] * y + h[5]) / w};
}

std::array<cv::Point2d, 4> corners(const Matrix& h, int width, int height) {
  return {apply(h, 0, 0), apply(h, width, 0), apply(h, width, height), apply(h, 0, height)};
}

// Inside the cell with a margin of 2 pixels, so that bilinear sampling
// near the view's edge never reads a pixel of the next cell.
bool inside(const Matrix& h, const cv::Rect2d& cell, int width, int height) {
  constexpr double kMargin = 2;
  for (const cv::Point2d& p : corners(h, width, height))
    if (!(p.x >= cell.x + kMargin && p.y >= cell.y + kMargin &&
          p.x <= cell.x + cell.width - kMargin && p.y <= cell.y + cell.height - kMargin))
      return false;
  return true;
}

// The largest halving of a visit's poses towards the place's centre (the
// same for all its frames, so the camera moves smoothly) that keeps every
// view inside the cell; the centred view always is.
double fit_visit(const Pose& start, const Pose& end, std::size_t length, const cv::Rect2d& cell,
                 int width, int height) {
  double s = 1;
  for (int attempt = 0; attempt < 12; ++attempt, s /= 2) {
    bool all_inside = true;
    for (std::size_t f = 0; f < length && all_inside; ++f)
      all_inside =
          inside(homography(scaled(visit_pose(start, end, f, length), s), cell, width, height),
                 cell, width, height);
    if (all_inside) return s;
  }
  return 0;
}

// First visits: close to the place's canonical view. Revisits: another
// viewpoint. Within a visit the camera drifts from a start to an end pose.
Pose draw_viewpoint(RouteRandom& random, bool revisit) {
  Pose p;
  const double pan = revisit ? 0.18 : 0.06;
  p.pan_x = random.symmetric(pan);
  p.pan_y = random.symmetric(pan);
  p.zoom = revisit ? random.uniform(0.75, 1.2) : random.uniform(0.92, 1.08);
  p.roll = random.symmetric((revisit ? 15.0 : 4.0) * kPi / 180);
  const double tilt = revisit ? 0.12 : 0.03;
  p.tilt_x = random.symmetric(tilt);
  p.tilt_y = random.symmetric(tilt);
  return p;
}

Pose draw_drift(RouteRandom& random, const Pose& start) {
  Pose p = start;
  p.pan_x += random.symmetric(0.1);
  p.pan_y += random.symmetric(0.1);
  p.zoom *= random.uniform(0.92, 1.08);
  p.roll += random.symmetric(4 * kPi / 180);
  return p;
}

struct Photometric {
  double gain, bias, gamma, blur_sigma, noise_sigma;
};

Photometric draw_photometric(RouteRandom& random, bool revisit) {
  if (!revisit)
    return {random.uniform(0.9, 1.1), random.symmetric(8), random.uniform(0.9, 1.1),
            random.uniform(0, 0.5), random.uniform(0, 2)};
  return {random.uniform(0.55, 1.45), random.symmetric(30), random.uniform(0.7, 1.4),
          random.uniform(0, 1.8), random.uniform(0, 8)};
}

void require(bool ok, const std::string& what) {
  if (!ok) throw InvalidArgument("route: " + what);
}

}  // namespace

void check_route_options(const RouteOptions& o) {
  require(o.frames >= 1 && o.frames <= 10'000'000, "frames must be in [1, 10000000]");
  require(o.width >= 32 && o.width <= 4096 && o.height >= 32 && o.height <= 4096,
          "width and height must be in [32, 4096]");
  require(o.min_visit_frames >= 1 && o.max_visit_frames <= 1000 &&
              o.min_visit_frames <= o.max_visit_frames,
          "visit frames must satisfy 1 <= min_visit_frames <= max_visit_frames <= 1000");
  require(o.revisit_probability >= 0 && o.revisit_probability <= 1,
          "revisit_probability must be in [0, 1]");
  require(o.min_revisit_gap <= 10'000'000, "min_revisit_gap must be in [0, 10000000]");
  require(o.cell_margin >= 1.2 && o.cell_margin <= 4, "cell_margin must be in [1.2, 4]");
  require(o.min_place_corners >= 0 && o.min_place_corners <= 1'000'000,
          "min_place_corners must be in [0, 1000000]");
  require(o.jpeg_quality >= 1 && o.jpeg_quality <= 100, "jpeg_quality must be in [1, 100]");
}

std::vector<std::pair<std::size_t, std::size_t>> Route::loop_pairs() const {
  std::vector<std::vector<std::size_t>> frames_of_place(places.size());
  std::vector<std::pair<std::size_t, std::size_t>> pairs;
  for (std::size_t i = 0; i < frames.size(); ++i) {
    std::vector<std::size_t>& earlier = frames_of_place[frames[i].place];
    for (const std::size_t j : earlier)
      if (frames[j].visit != frames[i].visit) pairs.emplace_back(i, j);
    earlier.push_back(i);
  }
  return pairs;
}

std::uint64_t Route::loop_pair_count() const {
  // Per place: all pairs of its frames minus the pairs within one visit.
  std::vector<std::uint64_t> place_frames(places.size(), 0);
  std::uint64_t within_visits = 0, run = 0;
  for (std::size_t i = 0; i < frames.size(); ++i) {
    ++place_frames[frames[i].place];
    run = i > 0 && frames[i].visit == frames[i - 1].visit ? run + 1 : 1;
    within_visits += run - 1;
  }
  std::uint64_t all = 0;
  for (const std::uint64_t n : place_frames) all += n * (n - 1) / 2;
  return all - within_visits;
}

std::array<cv::Point2d, 4> Route::view_corners(std::size_t frame) const {
  return corners(frames.at(frame).homography, options.width, options.height);
}

std::vector<RoutePlace> route_places(const std::vector<cv::Mat>& photographs,
                                     const RouteOptions& options) {
  check_route_options(options);
  const double cell_width = options.width * options.cell_margin;
  const double cell_height = options.height * options.cell_margin;
  std::vector<RoutePlace> places;
  for (std::size_t k = 0; k < photographs.size(); ++k) {
    const cv::Mat& photo = photographs[k];
    if (photo.type() != CV_8UC1) throw InvalidArgument("route_places: photographs must be grey");
    const int columns = static_cast<int>(photo.cols / cell_width);
    const int rows = static_cast<int>(photo.rows / cell_height);
    const double x0 = (photo.cols - columns * cell_width) / 2;
    const double y0 = (photo.rows - rows * cell_height) / 2;
    for (int r = 0; r < rows; ++r)
      for (int c = 0; c < columns; ++c) {
        const cv::Rect2d cell(x0 + c * cell_width, y0 + r * cell_height, cell_width, cell_height);
        const cv::Rect window(
            static_cast<int>(std::floor(cell.x + (cell_width - options.width) / 2)),
            static_cast<int>(std::floor(cell.y + (cell_height - options.height) / 2)),
            options.width, options.height);
        std::vector<cv::KeyPoint> corners;
        if (options.min_place_corners > 0) cv::FAST(photo(window), corners, 20, true);
        if (corners.size() >= static_cast<std::size_t>(options.min_place_corners))
          places.push_back({k, cell});
      }
  }
  return places;
}

Route plan_route(std::vector<std::string> photographs, std::vector<RoutePlace> places,
                 const RouteOptions& options) {
  check_route_options(options);
  if (places.empty()) throw InvalidArgument("route: no place to visit");
  Route route;
  route.options = options;
  route.photographs = std::move(photographs);
  route.places = std::move(places);
  RouteRandom random(options.seed);

  // New places are met in a shuffled order (Fisher-Yates).
  std::vector<std::size_t> order(route.places.size());
  for (std::size_t i = 0; i < order.size(); ++i) order[i] = i;
  for (std::size_t i = order.size(); i > 1; --i) std::swap(order[i - 1], order[random.index(i)]);

  constexpr std::size_t kNever = std::numeric_limits<std::size_t>::max();
  std::vector<std::size_t> last_end(route.places.size(), kNever);  // frame after its last visit
  std::size_t next_new = 0, visit = 0;
  std::vector<std::size_t> eligible;
  while (route.frames.size() < options.frames) {
    const std::size_t now = route.frames.size();
    eligible.clear();
    std::size_t oldest = kNever;
    for (std::size_t p = 0; p < route.places.size(); ++p) {
      if (last_end[p] == kNever) continue;
      if (now - last_end[p] >= options.min_revisit_gap) eligible.push_back(p);
      if (oldest == kNever || last_end[p] < last_end[oldest]) oldest = p;
    }
    const bool new_left = next_new < order.size();
    const bool revisit =
        !new_left || (!eligible.empty() && random.uniform() < options.revisit_probability);
    std::size_t place;
    if (!revisit)
      place = order[next_new++];
    else if (!eligible.empty())
      place = eligible[random.index(eligible.size())];
    else
      place = oldest;

    const std::size_t span = static_cast<std::size_t>(options.max_visit_frames) -
                             static_cast<std::size_t>(options.min_visit_frames) + 1;
    const std::size_t length =
        std::min(options.frames - now,
                 static_cast<std::size_t>(options.min_visit_frames) + random.index(span));
    const cv::Rect2d& cell = route.places[place].cell;
    const Pose start = draw_viewpoint(random, revisit);
    const Pose end = draw_drift(random, start);
    const Photometric light = draw_photometric(random, revisit);
    const double s = fit_visit(start, end, length, cell, options.width, options.height);
    for (std::size_t f = 0; f < length; ++f) {
      RouteFrame frame;
      frame.place = place;
      frame.visit = visit;
      frame.revisit = revisit;
      frame.homography = homography(scaled(visit_pose(start, end, f, length), s), cell,
                                    options.width, options.height);
      frame.gain = light.gain;
      frame.bias = light.bias;
      frame.gamma = light.gamma;
      frame.blur_sigma = light.blur_sigma;
      frame.noise_sigma = light.noise_sigma;
      frame.noise_seed = random.bits();
      route.frames.push_back(frame);
    }
    last_end[place] = route.frames.size();
    ++visit;
  }
  return route;
}

}  // namespace binbow::loop
