// The interface between binbow_vision and binbow_media, the module that
// holds OpenCV's imgcodecs and videoio and matio. Those libraries (GDAL,
// GStreamer, FFmpeg, HDF5 and GUI toolkits behind them: over 200 shared
// objects) would otherwise be loaded and initialised at the start of every
// program linking binbow_vision, even one that reads no image. The module is
// loaded with dlopen the first time one of these functions is needed
// (vision/media_module.h). Both sides are built by the same build, so the
// interface may use C++ types; the version check refuses a module of another
// build. Functions throw cv::Exception as OpenCV does (its type lives in
// libopencv_core, shared by both sides), never binbow's exceptions.
#pragma once

#include <cstddef>
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include <matio.h>
#include <opencv2/core.hpp>

namespace binbow::media {

// Raised whenever Api changes.
inline constexpr int kApiVersion = 2;

// An open video file (cv::VideoCapture with a file backend).
class Video {
 public:
  virtual ~Video() = default;
  virtual bool grab() = 0;
  virtual bool retrieve(cv::Mat& image) = 0;
  // As the container reports them; negative, 0 or NaN when unknown.
  virtual double width() const = 0;
  virtual double height() const = 0;
  virtual double frame_count() const = 0;
  virtual double fps() const = 0;
  // Positions the video so that the next grab() reads frame `frame` (counted
  // from 0); false when the backend cannot seek or lands elsewhere.
  virtual bool seek(long long frame) = 0;
};

// 8-bit grey pixels, row by row, without OpenCV's types: for callers that
// link no OpenCV (the ground-truth images of `binbow evaluate`).
struct GreyPixels {
  int width = 0, height = 0;
  std::vector<std::uint8_t> pixels;  // width * height
};

struct Api {
  int version;
  const char* binbow_version;
  // cv::imdecode of `size` bytes as 8-bit grey (IMREAD_GRAYSCALE) or BGR
  // (IMREAD_COLOR); empty when OpenCV cannot decode them.
  cv::Mat (*decode_image)(const std::uint8_t* data, std::size_t size, bool grey);
  // decode_image to grey, into `image`; catches cv::Exception and returns
  // its message instead (empty on success, and when the bytes are no image,
  // which leaves `image` empty).
  std::string (*decode_grey_pixels)(const std::uint8_t* data, std::size_t size, GreyPixels& image);
  // cv::imencode to the format of `extension` (".png", ".jpg"); JPEG at
  // `jpeg_quality` (0-100).
  bool (*encode_image)(const std::string& extension, const cv::Mat& image, int jpeg_quality,
                       std::vector<std::uint8_t>& bytes);
  // cv::imwrite, and cv::haveImageWriter: whether OpenCV writes the format
  // of a file name's extension.
  bool (*write_image)(const std::string& path, const cv::Mat& image);
  bool (*have_image_writer)(const std::string& path);
  // cv::haveImageReader: whether a file's content is an image OpenCV decodes.
  bool (*have_image_reader)(const std::string& path);
  // The video opened with the first file backend that can (FFmpeg,
  // GStreamer, OpenCV's MJPEG; never a camera backend); nullptr if none can.
  std::unique_ptr<Video> (*open_video)(const std::string& path);
  // matio's reading functions.
  decltype(&::Mat_Open) mat_open;
  decltype(&::Mat_Close) mat_close;
  decltype(&::Mat_VarReadNextInfo) mat_var_read_next_info;
  decltype(&::Mat_VarReadData) mat_var_read_data;
  decltype(&::Mat_VarReadDataAll) mat_var_read_data_all;
  decltype(&::Mat_VarFree) mat_var_free;
};

}  // namespace binbow::media

// The module's one exported symbol.
extern "C" const binbow::media::Api* binbow_media_api();
inline constexpr const char* kBinbowMediaApiSymbol = "binbow_media_api";
