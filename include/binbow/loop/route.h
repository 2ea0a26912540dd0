// Synthetic routes with exact ground truth: a camera walking through
// photographs, for measuring loop detection on thousands of frames where
// real sequences with ground truth are short or cannot be shipped.
//
// Each photograph is cut into a grid of disjoint cells; a textured cell is a
// place. A visit is a few consecutive frames looking at one place while the
// camera moves (pan, zoom, roll and a little perspective: a homography per
// frame); the route visits new places and, later, revisits some of them from
// other viewpoints with other exposure, noise and blur. Every view of a place
// lies inside its cell, and views of one place overlap, so the ground truth is
// exact by construction: two frames of different visits show the same scene
// exactly when they view the same place. Frames of one visit are one
// continuous view, not loops (as in the usual loop ground truths); visits are
// shorter than the loop detector's default `dislocal` and a revisit comes
// min_revisit_gap frames after the place's previous visit at the earliest.
//
// Everything is deterministic: the same photographs, options and seed give
// byte-identical frames, ground truth and route description.
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <functional>
#include <string>
#include <utility>
#include <vector>

#include <opencv2/core.hpp>

namespace binbow::loop {

struct RouteOptions {
  std::size_t frames = 2000;  // route length [1, 1e7]
  // Frame size in pixels [32, 4096]. A place is a cell of cell_margin × this
  // size in photograph pixels, viewed at about one frame pixel per photograph
  // pixel (zoom 1).
  int width = 400;
  int height = 300;
  std::uint64_t seed = 1;
  // Frames per visit [1, 1000], chosen uniformly; the default maximum stays
  // below the detector's default dislocal (20 frames), so frames of one visit
  // are never candidates of each other.
  int min_visit_frames = 5;
  int max_visit_frames = 12;
  // Chance that a visit revisits a place seen before [0, 1]; once every place
  // has been visited, every visit is a revisit.
  double revisit_probability = 0.35;
  // Frames from the end of a place's visit to the start of its next visit,
  // at least (when no place qualifies, the least recently visited one is
  // revisited) [0, 1e7].
  std::size_t min_revisit_gap = 100;
  // Cell size / view size [1.2, 4]: the room views have to move in.
  double cell_margin = 1.3;
  // FAST corners (threshold 20) a cell's central frame-sized window needs
  // to be a place; blank sky or blur is not [0, 1e6].
  int min_place_corners = 100;
  int jpeg_quality = 90;  // [1, 100]
};

// Throws InvalidArgument naming the first option out of its range.
void check_route_options(const RouteOptions& options);

// A cell of a photograph, in its pixels.
struct RoutePlace {
  std::size_t photograph = 0;  // index into the route's photographs
  cv::Rect2d cell;
};

// One frame: the view and how it was photographed.
struct RouteFrame {
  std::size_t place = 0;
  std::size_t visit = 0;  // visits numbered in route order from 0
  bool revisit = false;   // the place was visited before
  // Row-major 3×3 homography from frame pixels (x, y, 1) to photograph
  // pixels; the frame's four corners map inside the place's cell, 2 pixels
  // from its edges (what the frame's pixels are interpolated from).
  std::array<double, 9> homography{};
  // Photometric: v' = gain × 255 × (v / 255)^gamma + bias, then Gaussian
  // blur of blur_sigma pixels, then Gaussian noise of noise_sigma grey levels
  // drawn from noise_seed; 0 sigma: none.
  double gain = 1, bias = 0, gamma = 1, blur_sigma = 0, noise_sigma = 0;
  std::uint64_t noise_seed = 0;
};

struct Route {
  RouteOptions options;
  std::vector<std::string> photographs;  // as given (names for the description)
  std::vector<RoutePlace> places;
  std::vector<RouteFrame> frames;

  // The ground truth: every (query, match), query > match, 0-based frame
  // indices, of frames of different visits to one place; sorted by query,
  // then match.
  std::vector<std::pair<std::size_t, std::size_t>> loop_pairs() const;
  // loop_pairs().size(), counted without listing them.
  std::uint64_t loop_pair_count() const;
  // Where frame i's four corners (top-left, top-right, bottom-right,
  // bottom-left, at the pixel edges) land in its photograph.
  std::array<cv::Point2d, 4> view_corners(std::size_t frame) const;
};

// The places of grey photographs (8-bit, one channel): each photograph's
// grid of cells of cell_margin × the frame size, centred, keeping the cells
// with at least min_place_corners FAST corners in their central window. In
// photograph order, then row by row.
std::vector<RoutePlace> route_places(const std::vector<cv::Mat>& photographs,
                                     const RouteOptions& options);

// The route over `places` (at least one): which place each visit sees, the
// camera's path and the photometric conditions, all drawn from options.seed
// with generators whose output is fixed by the C++ standard (the same on
// every platform). photographs names the photographs places index.
Route plan_route(std::vector<std::string> photographs, std::vector<RoutePlace> places,
                 const RouteOptions& options);

// Frame `index` of the route, 8-bit grey, options.width × options.height,
// from its place's photograph (grey, as route_places had it).
cv::Mat render_route_frame(const Route& route, std::size_t index, const cv::Mat& photograph);

// The most ground-truth pairs make_route writes (~15 bytes each): they grow
// with the square of the visits per place, so a long route over few places
// is refused rather than filling the disk.
inline constexpr std::uint64_t kMaxRoutePairs = 20'000'000;

// (frames written, frames in all).
using RouteProgress = std::function<void(std::size_t, std::size_t)>;

// Reads the photographs (image files, directories, text lists: as
// vision::ImageSource reads them, in grey), plans the route and writes into
// `directory`, which must be new or empty (FileError otherwise):
//   frames/000000.jpg ...   the frames, named by 0-based index (what
//                           `binbow detect-loops DIR/frames` reads in order)
//   route.csv               per frame: its place, visit, photograph,
//                           homography and photometric conditions
//   places.csv              per place: photograph and cell
//   ground_truth.txt        loop_pairs() as 0-based "query match" lines
//                           (`binbow evaluate --gt` reads it), written last:
//                           a route without it is incomplete
// Throws FileError naming a photograph that cannot be read or a file that
// cannot be written; InvalidArgument when the photographs give no place or
// the ground truth would have more than kMaxRoutePairs pairs (before any
// frame is written).
Route make_route(const std::vector<std::string>& photographs, const RouteOptions& options,
                 const std::string& directory, const RouteProgress& progress = {});

}  // namespace binbow::loop
