// binbow_media: OpenCV's imgcodecs and videoio, and matio, behind media::Api.
#include <algorithm>
#include <string>
#include <vector>

#include <opencv2/imgcodecs.hpp>
#include <opencv2/videoio.hpp>
#include <opencv2/videoio/registry.hpp>

#include "media/media_api.h"

namespace binbow::media {
namespace {

// The video-file backends of this OpenCV, in order of preference. CAP_ANY
// would also try camera backends (gPhoto2 probes USB devices and leaks) and
// CAP_IMAGES, which reads a file name as a printf pattern.
const std::vector<int>& file_backends() {
  static const std::vector<int> backends = [] {
    std::vector<int> available;
    for (const int backend : {cv::CAP_FFMPEG, cv::CAP_GSTREAMER, cv::CAP_OPENCV_MJPEG}) {
      if (cv::videoio_registry::hasBackend(static_cast<cv::VideoCaptureAPIs>(backend))) {
        available.push_back(backend);
      }
    }
    if (available.empty()) available.push_back(cv::CAP_ANY);
    return available;
  }();
  return backends;
}

class CaptureVideo final : public Video {
 public:
  bool open(const std::string& path) {
    path_ = path;
    for (const int backend : file_backends())
      if (capture_.open(path, backend)) return true;
    return false;
  }
  bool grab() override { return capture_.grab(); }
  bool retrieve(cv::Mat& image) override { return capture_.retrieve(image); }
  double width() const override { return capture_.get(cv::CAP_PROP_FRAME_WIDTH); }
  double height() const override { return capture_.get(cv::CAP_PROP_FRAME_HEIGHT); }
  double frame_count() const override { return capture_.get(cv::CAP_PROP_FRAME_COUNT); }
  double fps() const override { return capture_.get(cv::CAP_PROP_FPS); }
  // Seeking is exact for intra-only codecs and OpenCV's FFmpeg backend; a
  // backend that cannot seek, or lands elsewhere, is read from the start.
  bool seek(long long frame) override {
    const auto target = static_cast<double>(frame);
    if (frame == 0) return true;
    if (capture_.set(cv::CAP_PROP_POS_FRAMES, target) &&
        capture_.get(cv::CAP_PROP_POS_FRAMES) == target)
      return true;
    if (!open(path_)) return false;
    long long skipped = 0;
    while (skipped < frame && capture_.grab()) ++skipped;
    return skipped == frame;
  }

 private:
  cv::VideoCapture capture_;
  std::string path_;
};

cv::Mat decode_image(const std::uint8_t* data, std::size_t size, bool grey) {
  return cv::imdecode(cv::Mat(1, static_cast<int>(size), CV_8UC1, const_cast<std::uint8_t*>(data)),
                      grey ? cv::IMREAD_GRAYSCALE : cv::IMREAD_COLOR);
}

std::string decode_grey_pixels(const std::uint8_t* data, std::size_t size, GreyPixels& image) {
  try {
    const cv::Mat grey = decode_image(data, size, true);
    image.width = grey.cols;
    image.height = grey.rows;
    image.pixels.resize(grey.total());
    for (int row = 0; row < grey.rows; ++row)
      std::copy_n(grey.ptr<std::uint8_t>(row), grey.cols,
                  image.pixels.data() + static_cast<std::size_t>(row) * grey.cols);
    return {};
  } catch (const cv::Exception& e) {
    return e.msg;
  }
}

bool encode_image(const std::string& extension, const cv::Mat& image, int jpeg_quality,
                  std::vector<std::uint8_t>& bytes) {
  return cv::imencode(extension, image, bytes, {cv::IMWRITE_JPEG_QUALITY, jpeg_quality});
}

bool write_image(const std::string& path, const cv::Mat& image) {
  return cv::imwrite(path, image);
}

bool have_image_writer(const std::string& path) {
  return cv::haveImageWriter(path);
}

bool have_image_reader(const std::string& path) {
  return cv::haveImageReader(path);
}

std::unique_ptr<Video> open_video(const std::string& path) {
  auto video = std::make_unique<CaptureVideo>();
  if (!video->open(path)) return nullptr;
  return video;
}

const Api kApi{kApiVersion,        BINBOW_VERSION,        decode_image,      decode_grey_pixels,
               encode_image,       write_image,           have_image_writer, have_image_reader,
               open_video,         &::Mat_Open,           &::Mat_Close,      &::Mat_VarReadNextInfo,
               &::Mat_VarReadData, &::Mat_VarReadDataAll, &::Mat_VarFree};

}  // namespace
}  // namespace binbow::media

extern "C" __attribute__((visibility("default"))) const binbow::media::Api* binbow_media_api() {
  return &binbow::media::kApi;
}
