// Reading image sequences: image files, directories, videos and text lists.
#pragma once

#include <cstddef>
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include <opencv2/core.hpp>

namespace binbow::vision {

struct Frame {
  cv::Mat image;          // 8-bit grey
  std::string name;       // file path, or "video.mp4#123" for video frames (see read_frame)
  std::size_t index = 0;  // 0-based position in the sequence (after stride)
  // Pixels of `image` per pixel of the file or video frame: below 1 when
  // max_width downscaled it. Divide image coordinates by it for the file's.
  double scale = 1;
  // With ImageSourceOptions::skip_unreadable, why this frame could not be
  // read (FileError::problem; `image` is then empty); empty for a frame read.
  std::string unreadable;
};

class FeatureExtractor;

// The default largest image (or video frame) decoded, in pixels: a 10000 ×
// 10000 image. Decoding allocates at least a byte per pixel, often more.
inline constexpr std::uint64_t kDefaultMaxImagePixels = 100'000'000;
// Image files are read whole before decoding; larger files are refused.
inline constexpr std::uint64_t kMaxImageFileBytes = std::uint64_t{2} << 30;
// The largest ImageSourceOptions::stride, max_width and video_fps that
// ImageSource accepts (InvalidArgument beyond); the CLI's flags and Python's
// detect_loops check the same bounds.
inline constexpr std::size_t kMaxStride = 1'000'000;
inline constexpr int kMaxFrameWidth = 1'000'000;
inline constexpr double kMaxVideoFps = 1000;

struct ImageSourceOptions {
  std::size_t stride =
      1;              // keep every stride-th frame (counted over the whole sequence); 0 acts as 1
  int max_width = 0;  // downscale wider frames to this width (aspect kept); 0 keeps the size
  // Videos only: sample at most this many frames per second of video time,
  // before the stride applies; 0 keeps every frame. Ignored when the video
  // does not report its frame rate.
  double video_fps = 0;
  // Images and video frames with more pixels are refused (FileError) from
  // their header, before anything is decoded. Must be ≥ 1.
  std::uint64_t max_pixels = kDefaultMaxImagePixels;
  // Frames that would reach feature extraction with more pixels — counted
  // after max_width's downscaling — are refused too, from the header, with
  // `extraction_limit_reason` in the message (e.g. "akaze extracts within
  // 2 GiB ..."). 0: no such limit. limit_for_extractor() sets both.
  std::uint64_t max_extracted_pixels = 0;
  std::string extraction_limit_reason;
  // An image that cannot be read (damaged, truncated, over a limit) or a
  // video frame that cannot be decoded is delivered as a frame with an empty
  // image and Frame::unreadable set, keeping its index, instead of an error.
  // Inputs that cannot be listed or opened (a missing file, a video that
  // does not open) are still errors.
  bool skip_unreadable = false;
};

// `options` with max_extracted_pixels (and its reason) set to what
// `extractor` extracts within kDefaultExtractionMemoryBytes
// (FeatureExtractor::max_pixels), unless max_extracted_pixels is already set
// or the extractor's memory per pixel is not known.
ImageSourceOptions limit_for_extractor(ImageSourceOptions options,
                                       const FeatureExtractor& extractor);

// A sequence of frames from several inputs, in order. Each input is an image
// file (any format OpenCV reads), a directory (its image files, not
// recursively, in natural order: 2.jpg before 10.jpg; hidden files skipped), a
// video file (through cv::VideoCapture) or a text list (.txt, .lst, .list) of
// one image, directory or video per line (relative paths are relative to the
// list; blank lines and lines starting with '#' are skipped; lists do not nest).
// Frames are converted to 8-bit grey and resized as the options ask.
// The constructor expands directories and lists, throwing FileError naming
// the path for anything missing, unreadable, neither a regular file nor a
// directory (a FIFO, a socket, a device: they could block forever), or a
// directory without images; InvalidArgument for an empty input list.
class ImageSource {
 public:
  explicit ImageSource(const std::vector<std::string>& inputs, ImageSourceOptions options = {});
  ImageSource(ImageSource&&) noexcept;
  ImageSource& operator=(ImageSource&&) noexcept;
  ~ImageSource();

  // The next frame, or false at the end. Throws FileError naming the file
  // when an image cannot be decoded (unless skip_unreadable) or a video
  // cannot be opened; the source can continue with the next frame after such
  // an error, which keeps the index of the frame that failed.
  bool next(Frame& frame);
  // Number of frames, when known before reading (-1 otherwise).
  long long size() const;
  // Video frames the containers declared (CAP_PROP_FRAME_COUNT) but the
  // backend could not decode: a damaged video ends early without an error
  // from OpenCV. Counted when a video ends; an estimate for containers that
  // do not store their frame count.
  std::size_t unreadable_frames() const noexcept;
  // Frames delivered per second of video time, when every input is a video
  // and all report the same frame rate: that rate, capped at video_fps, then
  // divided by the stride. 0 when unknown (an input is an image, the rates
  // differ, or a video reports none). Opens each video once to read its rate;
  // throws FileError naming a video that cannot be opened.
  double frame_rate() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

// Reads one image file as 8-bit grey. Throws FileError naming the file when it
// is missing, not a regular file (a directory, a FIFO, a device), empty (0
// bytes), larger than kMaxImageFileBytes, of a format whose size cannot be
// read from its header (see docs/limits.md), declares 0 pixels or more than
// `max_pixels` (checked before decoding), is a PNG/JPEG declaring more than
// ~1100 pixels per byte of file (a decompression bomb), is a JPEG libjpeg
// warns about (truncated, corrupt data: OpenCV would fill the rest grey),
// cannot be decoded by OpenCV, or decodes to 0×0 pixels.
cv::Mat read_grey_image(const std::string& path, std::uint64_t max_pixels = kDefaultMaxImagePixels);

enum class FramePixels { kGrey, kBgr };  // 8-bit, 1 or 3 channels

// Reads one frame by the name ImageSource gave it (Frame::name), at the size
// of the file: an image file, or "VIDEO#N" for frame N of a video, counted
// from 0 over every frame of the video (before video_fps and the stride),
// when no file has that whole name. Image files get read_grey_image's
// checks. Throws FileError naming the file when it cannot be read or the
// video has no frame N.
cv::Mat read_frame(const std::string& name, FramePixels pixels = FramePixels::kGrey);

}  // namespace binbow::vision
