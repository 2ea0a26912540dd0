// Reading image sequences: image files, directories, videos and text lists.
#pragma once

#include <cstddef>
#include <memory>
#include <string>
#include <vector>

#include <opencv2/core.hpp>

namespace binbow::vision {

struct Frame {
  cv::Mat image;        // 8-bit grey
  std::string name;     // file path, or "video.mp4#123" for video frames
  std::size_t index = 0;  // 0-based position in the sequence (after stride)
};

struct ImageSourceOptions {
  std::size_t stride = 1;   // keep every stride-th frame
  int max_width = 0;        // downscale wider frames to this width; 0 keeps the size
};

// A sequence of frames from several inputs, in order. Each input is an image
// file (any format OpenCV reads), a directory (its images in natural order:
// 2.jpg before 10.jpg), a video file (through cv::VideoCapture) or a text file
// listing one path per line (relative paths are relative to the list).
class ImageSource {
 public:
  explicit ImageSource(const std::vector<std::string>& inputs, ImageSourceOptions options = {});
  ImageSource(ImageSource&&) noexcept;
  ImageSource& operator=(ImageSource&&) noexcept;
  ~ImageSource();

  // The next frame, or false at the end. Throws FileError naming the file
  // when an image cannot be decoded.
  bool next(Frame& frame);
  // Number of frames, when known before reading (-1 otherwise).
  long long size() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

// Reads one image file as 8-bit grey; throws FileError naming the file.
cv::Mat read_grey_image(const std::string& path);

}  // namespace binbow::vision
