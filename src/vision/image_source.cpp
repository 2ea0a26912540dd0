// ImageSource and read_grey_image: every input kind turned into grey frames.
#include "binbow/vision/image_source.h"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <string>
#include <system_error>
#include <utility>

#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <opencv2/videoio.hpp>
#include <opencv2/videoio/registry.hpp>

#include "binbow/error.h"
#include "vision/image_header.h"
#include "vision/natural_order.h"

namespace binbow::vision {
namespace fs = std::filesystem;

namespace {

std::string lowercase_extension(const fs::path& path) {
  std::string extension = path.extension().string();
  std::transform(extension.begin(), extension.end(), extension.begin(),
                 [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  return extension;
}

bool is_one_of(const std::string& extension, std::initializer_list<const char*> extensions) {
  return std::any_of(extensions.begin(), extensions.end(),
                     [&](const char* candidate) { return extension == candidate; });
}

// The still-image formats OpenCV's imgcodecs can be built with.
bool has_image_extension(const fs::path& path) {
  return is_one_of(
      lowercase_extension(path),
      {".jpg", ".jpeg", ".jpe",  ".png",  ".bmp", ".dib", ".pbm", ".pgm", ".ppm", ".pxm", ".pnm",
       ".pfm", ".tif",  ".tiff", ".webp", ".jp2", ".exr", ".hdr", ".pic", ".sr",  ".ras", ".avif"});
}

bool has_video_extension(const fs::path& path) {
  return is_one_of(lowercase_extension(path),
                   {".avi", ".mp4", ".m4v", ".mov", ".mkv", ".webm", ".mpg", ".mpeg", ".wmv",
                    ".flv", ".ogv", ".3gp", ".ts", ".mts", ".mjpeg", ".mjpg", ".gif"});
}

bool has_list_extension(const fs::path& path) {
  return is_one_of(lowercase_extension(path), {".txt", ".lst", ".list"});
}

std::vector<std::uint8_t> read_whole_file(const std::string& path) {
  std::ifstream stream(path, std::ios::binary);
  if (!stream) throw FileError(path, "cannot open for reading");
  stream.seekg(0, std::ios::end);
  const std::streamoff size = stream.tellg();
  if (size < 0) throw FileError(path, "cannot determine the file size");
  stream.seekg(0, std::ios::beg);
  std::vector<std::uint8_t> bytes(static_cast<std::size_t>(size));
  if (size > 0 && !stream.read(reinterpret_cast<char*>(bytes.data()), size)) {
    throw FileError(path, "read error");
  }
  return bytes;
}

// Inside a JPEG's entropy-coded data every 0xFF byte is followed by 0x00 or a
// restart marker, so the last start-of-scan (FF DA) marker must be followed by
// an end-of-image (FF D9) marker in a complete file.
bool jpeg_is_complete(const std::vector<std::uint8_t>& bytes) {
  std::size_t last_scan = bytes.size(), last_end = bytes.size();
  for (std::size_t i = bytes.size(); i-- > 1;) {
    if (bytes[i - 1] != 0xFF) continue;
    if (bytes[i] == 0xD9 && last_end == bytes.size()) last_end = i;
    if (bytes[i] == 0xDA) {
      last_scan = i;
      break;
    }
  }
  return last_scan < bytes.size() && last_end < bytes.size() && last_end > last_scan;
}

cv::Mat to_grey(const cv::Mat& image) {
  if (image.channels() == 1) return image;
  cv::Mat grey;
  cv::cvtColor(image, grey, image.channels() == 4 ? cv::COLOR_BGRA2GRAY : cv::COLOR_BGR2GRAY);
  return grey;
}

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

// Opens a video file with the first backend that can; throws FileError.
void open_video_file(cv::VideoCapture& capture, const std::string& path) {
  bool opened = false;
  try {
    for (const int backend : file_backends()) {
      if ((opened = capture.open(path, backend))) break;
    }
  } catch (const cv::Exception& e) {
    throw FileError(path, "cannot open video: " + e.msg);
  }
  if (!opened) throw FileError(path, "cannot open as an image or a video");
}

// The frame rate a video reports, 0 if none.
double reported_frame_rate(const cv::VideoCapture& capture) {
  const double fps = capture.get(cv::CAP_PROP_FPS);
  return std::isfinite(fps) && fps > 0 ? fps : 0;
}

cv::Mat limit_width(const cv::Mat& image, int max_width) {
  if (max_width <= 0 || image.cols <= max_width) return image;
  const double scale = static_cast<double>(max_width) / image.cols;
  const int height = std::max(1, static_cast<int>(std::lround(image.rows * scale)));
  cv::Mat resized;
  cv::resize(image, resized, cv::Size(max_width, height), 0, 0, cv::INTER_AREA);
  return resized;
}

// The checks of read_grey_image, then decoding with `imread_flags`.
cv::Mat read_checked_image(const std::string& path, int imread_flags) {
  std::error_code error;
  if (fs::is_directory(path, error)) throw FileError(path, "is a directory, not an image");
  if (!fs::exists(path, error)) throw FileError(path, "no such file");
  const std::vector<std::uint8_t> bytes = read_whole_file(path);
  if (bytes.empty()) throw FileError(path, "empty file (0 bytes), not an image");
  const bool jpeg = bytes.size() >= 2 && bytes[0] == 0xFF && bytes[1] == 0xD8;
  if (jpeg && !jpeg_is_complete(bytes)) {
    throw FileError(path, "truncated JPEG (no end-of-image marker after the last scan)");
  }
  if (const auto declared = declared_dimensions(bytes)) {
    if (declared->width == 0 || declared->height == 0) {
      throw FileError(path, "image header declares 0 pixels (" + std::to_string(declared->width) +
                                "x" + std::to_string(declared->height) + ")");
    }
    if (declared->width * declared->height > max_pixels_for_file_size(bytes.size())) {
      throw FileError(path, "image header declares " + std::to_string(declared->width) + "x" +
                                std::to_string(declared->height) + " pixels, more than " +
                                std::to_string(bytes.size()) + " bytes can hold");
    }
  }
  cv::Mat image;
  try {
    image = cv::imdecode(bytes, imread_flags);
  } catch (const cv::Exception& e) {
    throw FileError(path, "cannot decode image: " + e.msg);
  }
  if (image.empty()) {
    throw FileError(path,
                    "cannot decode image (unknown format, corrupted, truncated or 0x0 pixels)");
  }
  return image;
}

cv::Mat to_pixels(const cv::Mat& image, FramePixels pixels) {
  if (pixels == FramePixels::kGrey) return to_grey(image);
  if (image.channels() == 3) return image;
  cv::Mat bgr;
  cv::cvtColor(image, bgr, image.channels() == 4 ? cv::COLOR_BGRA2BGR : cv::COLOR_GRAY2BGR);
  return bgr;
}

// Splits "VIDEO#N" into VIDEO and N; false for any other form.
bool split_video_frame_name(const std::string& name, std::string& video, long long& frame) {
  const std::size_t hash = name.rfind('#');
  constexpr std::size_t kMaxDigits = 18;  // fits a long long
  if (hash == std::string::npos || hash == 0 || hash + 1 == name.size() ||
      name.size() - hash - 1 > kMaxDigits) {
    return false;
  }
  const auto digit = [](unsigned char c) { return std::isdigit(c) != 0; };
  if (!std::all_of(name.begin() + static_cast<long>(hash) + 1, name.end(), digit)) return false;
  video = name.substr(0, hash);
  frame = std::stoll(name.substr(hash + 1));
  return true;
}

cv::Mat read_video_frame(const std::string& path, long long frame) {
  cv::VideoCapture capture;
  open_video_file(capture, path);
  cv::Mat image;
  try {
    // Seeking is exact for intra-only codecs and OpenCV's FFmpeg backend; a
    // backend that cannot seek, or lands elsewhere, is read from the start.
    const auto target = static_cast<double>(frame);
    const bool sought = frame == 0 || (capture.set(cv::CAP_PROP_POS_FRAMES, target) &&
                                       capture.get(cv::CAP_PROP_POS_FRAMES) == target);
    if (!sought) {
      open_video_file(capture, path);
      long long skipped = 0;
      while (skipped < frame && capture.grab()) ++skipped;
    }
    capture.read(image);
  } catch (const cv::Exception& e) {
    throw FileError(path, "cannot read frame " + std::to_string(frame) + ": " + e.msg);
  }
  if (image.empty()) {
    throw FileError(path, "has no frame " + std::to_string(frame) +
                              " (frames are counted from 0) or cannot decode it");
  }
  return image;
}

}  // namespace

cv::Mat read_grey_image(const std::string& path) {
  return to_grey(read_checked_image(path, cv::IMREAD_GRAYSCALE));
}

cv::Mat read_frame(const std::string& name, FramePixels pixels) {
  std::error_code error;
  std::string video;
  long long frame = 0;
  if (!fs::exists(name, error) && split_video_frame_name(name, video, frame) &&
      fs::is_regular_file(video, error)) {
    return to_pixels(read_video_frame(video, frame), pixels);
  }
  const int flags = pixels == FramePixels::kGrey ? cv::IMREAD_GRAYSCALE : cv::IMREAD_COLOR;
  return to_pixels(read_checked_image(name, flags), pixels);
}

struct ImageSource::Impl {
  struct Input {
    std::string path;
    bool video = false;
    double frame_rate = -1;  // videos: as reported (0: none), -1 until read
  };

  std::vector<Input> inputs;
  ImageSourceOptions options;
  std::size_t next_input = 0;
  std::size_t frames_seen = 0;  // before the stride
  std::size_t frames_kept = 0;
  // The video being read, if any.
  cv::VideoCapture capture;
  std::string video_path;
  long long video_frame = -1;
  double video_step = 1;   // video frames per sampled frame (video_fps)
  double next_sample = 0;  // video frame number of the next sample

  void add(const std::string& path, const std::string* list) {
    std::error_code error;
    const fs::file_status status = fs::status(path, error);
    if (!fs::exists(status)) {
      if (list != nullptr) throw FileError(*list, "lists '" + path + "', which does not exist");
      throw FileError(path, "no such file or directory");
    }
    if (fs::is_directory(status)) {
      add_directory(path);
    } else if (has_image_extension(path)) {
      inputs.push_back({path, false});
    } else if (has_video_extension(path)) {
      inputs.push_back({path, true});
    } else if (has_list_extension(path)) {
      if (list != nullptr) throw FileError(*list, "lists '" + path + "'; lists do not nest");
      add_list(path);
    } else if (cv::haveImageReader(path)) {
      inputs.push_back({path, false});
    } else {
      inputs.push_back({path, true});  // anything else: let cv::VideoCapture try
    }
  }

  void add_directory(const std::string& directory) {
    std::vector<std::string> names;
    std::error_code error;
    for (fs::directory_iterator it(directory, error), end; !error && it != end;
         it.increment(error)) {
      const std::string name = it->path().filename().string();
      std::error_code type_error;
      if (name.empty() || name[0] == '.' || !it->is_regular_file(type_error)) continue;
      if (has_image_extension(it->path())) names.push_back(name);
    }
    if (error) throw FileError(directory, "cannot list directory: " + error.message());
    if (names.empty()) throw FileError(directory, "directory holds no image files");
    std::sort(names.begin(), names.end(), natural_less);
    for (const std::string& name : names)
      inputs.push_back({(fs::path(directory) / name).string(), false});
  }

  void add_list(const std::string& list) {
    std::ifstream stream(list);
    if (!stream) throw FileError(list, "cannot open list for reading");
    const fs::path base = fs::path(list).parent_path();
    const std::size_t before = inputs.size();
    std::string line;
    while (std::getline(stream, line)) {
      const auto not_space = [](unsigned char c) { return !std::isspace(c); };
      line.erase(line.begin(), std::find_if(line.begin(), line.end(), not_space));
      line.erase(std::find_if(line.rbegin(), line.rend(), not_space).base(), line.end());
      if (line.empty() || line[0] == '#') continue;
      const fs::path entry(line);
      add((entry.is_absolute() ? entry : base / entry).string(), &list);
    }
    if (stream.bad()) throw FileError(list, "read error");
    if (inputs.size() == before) throw FileError(list, "list names no images");
  }

  bool keep_next() { return frames_seen++ % options.stride == 0; }

  bool next_video_frame(Frame& frame) {
    while (capture.grab()) {
      ++video_frame;
      if (static_cast<double>(video_frame) + 1e-9 < next_sample) continue;
      next_sample += video_step;
      if (!keep_next()) continue;
      cv::Mat image;
      if (!capture.retrieve(image) || image.empty()) {
        throw FileError(video_path, "cannot decode frame " + std::to_string(video_frame));
      }
      deliver(frame, to_grey(image), video_path + "#" + std::to_string(video_frame));
      return true;
    }
    capture.release();
    return false;
  }

  void open_video(const std::string& path) {
    video_path = path;
    video_frame = -1;
    next_sample = 0;
    open_video_file(capture, path);
    const double fps = reported_frame_rate(capture);
    video_step = (options.video_fps > 0 && fps > options.video_fps) ? fps / options.video_fps : 1;
  }

  void deliver(Frame& frame, const cv::Mat& grey, std::string name) {
    frame.image = limit_width(grey, options.max_width);
    frame.name = std::move(name);
    frame.index = frames_kept++;
    frame.scale = static_cast<double>(frame.image.cols) / grey.cols;
  }

  bool next(Frame& frame) {
    for (;;) {
      if (capture.isOpened()) {
        if (next_video_frame(frame)) return true;
        continue;
      }
      if (next_input >= inputs.size()) return false;
      const Input& input = inputs[next_input++];
      if (input.video) {
        open_video(input.path);
        continue;
      }
      if (!keep_next()) continue;
      deliver(frame, read_grey_image(input.path), input.path);
      return true;
    }
  }
};

ImageSource::ImageSource(const std::vector<std::string>& inputs, ImageSourceOptions options)
    : impl_(std::make_unique<Impl>()) {
  if (inputs.empty()) throw InvalidArgument("ImageSource: no inputs given");
  if (options.stride == 0) options.stride = 1;
  if (options.max_width < 0) throw InvalidArgument("ImageSource: max_width must be >= 0");
  impl_->options = options;
  for (const std::string& input : inputs) impl_->add(input, nullptr);
}

ImageSource::ImageSource(ImageSource&&) noexcept = default;
ImageSource& ImageSource::operator=(ImageSource&&) noexcept = default;
ImageSource::~ImageSource() = default;

bool ImageSource::next(Frame& frame) {
  return impl_->next(frame);
}

long long ImageSource::size() const {
  const bool has_video = std::any_of(impl_->inputs.begin(), impl_->inputs.end(),
                                     [](const Impl::Input& input) { return input.video; });
  if (has_video) return -1;
  const auto stride = static_cast<long long>(impl_->options.stride);
  return (static_cast<long long>(impl_->inputs.size()) + stride - 1) / stride;
}

double ImageSource::frame_rate() const {
  double rate = 0;
  for (Impl::Input& input : impl_->inputs) {
    if (!input.video) return 0;
    if (input.frame_rate < 0) {
      cv::VideoCapture capture;
      open_video_file(capture, input.path);
      input.frame_rate = reported_frame_rate(capture);
    }
    if (input.frame_rate == 0 || (rate != 0 && input.frame_rate != rate)) return 0;
    rate = input.frame_rate;
  }
  const ImageSourceOptions& options = impl_->options;
  if (options.video_fps > 0) rate = std::min(rate, options.video_fps);
  return rate / static_cast<double>(options.stride);
}

}  // namespace binbow::vision
