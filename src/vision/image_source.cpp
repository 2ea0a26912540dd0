// ImageSource and read_grey_image: every input kind turned into grey frames.
#include "binbow/vision/image_source.h"

#include <sys/stat.h>

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <string>
#include <system_error>
#include <utility>

#include <opencv2/imgproc.hpp>

#include "binbow/error.h"
#include "binbow/vision/features.h"
#include "core/file_io.h"
#include "core/regular_file.h"
#include "vision/image_header.h"
#include "vision/jpeg_decoder.h"
#include "vision/media_module.h"
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

cv::Mat to_grey(const cv::Mat& image) {
  if (image.channels() == 1) return image;
  cv::Mat grey;
  cv::cvtColor(image, grey, image.channels() == 4 ? cv::COLOR_BGRA2GRAY : cv::COLOR_BGR2GRAY);
  return grey;
}

// Opens a video file with the first file backend that can; throws FileError.
std::unique_ptr<media::Video> open_video_file(const std::string& path) {
  std::unique_ptr<media::Video> video;
  try {
    video = media_module().open_video(path);
  } catch (const cv::Exception& e) {
    throw FileError(path, "cannot open video: " + e.msg);
  }
  if (!video) throw FileError(path, "cannot open as an image or a video");
  return video;
}

// The frame rate a video reports, 0 if none.
double reported_frame_rate(const media::Video& video) {
  const double fps = video.fps();
  return std::isfinite(fps) && fps > 0 ? fps : 0;
}

// The frame size max_width gives a file or video frame of `width` x `height`.
cv::Size size_after_max_width(int width, int height, int max_width) {
  if (max_width <= 0 || width <= max_width) return {width, height};
  const double scale = static_cast<double>(max_width) / width;
  return {max_width, std::max(1, static_cast<int>(std::lround(height * scale)))};
}

// `image` (the file's `file_size`, or smaller when libjpeg scaled it down
// while decoding) at the size max_width gives the file.
cv::Mat limit_width(const cv::Mat& image, cv::Size file_size, int max_width) {
  const cv::Size size = size_after_max_width(file_size.width, file_size.height, max_width);
  if (image.size() == size) return image;
  cv::Mat resized;
  cv::resize(image, resized, size, 0, 0, cv::INTER_AREA);
  return resized;
}

// The size limit_width() gives a frame of `width` x `height`.
std::uint64_t pixels_after_max_width(std::uint64_t width, std::uint64_t height, int max_width) {
  if (max_width <= 0 || width <= static_cast<std::uint64_t>(max_width)) return width * height;
  const double scale = static_cast<double>(max_width) / static_cast<double>(width);
  const auto scaled_height =
      std::max<long long>(1, std::llround(static_cast<double>(height) * scale));
  return static_cast<std::uint64_t>(max_width) * static_cast<std::uint64_t>(scaled_height);
}

// Throws FileError naming `path` when a frame of `width` x `height` (already
// within max_pixels) reaches feature extraction with more pixels than
// options.max_extracted_pixels.
void check_extracted_pixels(const std::string& path, const char* what, std::uint64_t width,
                            std::uint64_t height, const ImageSourceOptions& options) {
  if (options.max_extracted_pixels == 0) return;
  const std::uint64_t pixels = pixels_after_max_width(width, height, options.max_width);
  if (pixels <= options.max_extracted_pixels) return;
  std::string size = describe_size(width, height) + " pixels";
  if (pixels != width * height)
    size += " (" + std::to_string(pixels) + " after downscaling to the maximum width)";
  const std::string reason = options.extraction_limit_reason.empty()
                                 ? "the limit for feature extraction"
                                 : options.extraction_limit_reason;
  throw FileError(path, std::string(what) + " of " + size + " is more than " +
                            std::to_string(options.max_extracted_pixels) + " pixels, " + reason +
                            "; downscale it (--max-width) or raise the limit (--max-pixels)");
}

// The checks of read_grey_image (and check_extracted_pixels when `options`
// is given), then decoding to grey or BGR. With `options`, a JPEG may be
// decoded smaller, down to twice its size after options->max_width;
// `file_size` receives the size of the whole image (as oriented).
cv::Mat read_checked_image(const std::string& path, bool grey, std::uint64_t max_pixels,
                           const ImageSourceOptions* options = nullptr,
                           cv::Size* file_size = nullptr) {
  const std::string bytes = binbow::detail::read_regular_file(path, kMaxImageFileBytes);
  const auto* data = reinterpret_cast<const std::uint8_t*>(bytes.data());
  const ImageDimensions declared = check_image_header(path, bytes, max_pixels);
  if (options != nullptr)
    check_extracted_pixels(path, "image", declared.width, declared.height, *options);
  check_image_allocation(path, declared, bytes.size(), max_pixels);
  cv::Mat image;
  cv::Size full_size;
  if (std::strcmp(declared.format, "jpeg") == 0) {
    DecodedJpeg decoded =
        decode_jpeg(data, bytes.size(), grey, options != nullptr ? options->max_width : 0);
    if (!decoded.problem.empty()) throw FileError(path, "damaged JPEG: " + decoded.problem);
    image = std::move(decoded.image);  // empty for the CMYK JPEGs OpenCV converts
    full_size = decoded.full_size;
  }
  try {
    if (image.empty()) image = media_module().decode_image(data, bytes.size(), grey);
  } catch (const cv::Exception& e) {
    throw FileError(path, "cannot decode image: " + e.msg);
  }
  if (image.empty()) {
    throw FileError(path,
                    "cannot decode image (unknown format, corrupted, truncated or 0x0 pixels)");
  }
  // The decoder read the same header; a larger result means this reader was misled.
  check_pixel_count(path, "decoded image", static_cast<std::uint64_t>(image.cols),
                    static_cast<std::uint64_t>(image.rows), max_pixels);
  if (file_size != nullptr) *file_size = full_size.empty() ? image.size() : full_size;
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
  const std::unique_ptr<media::Video> video = open_video_file(path);
  cv::Mat image;
  try {
    if (video->seek(frame) && video->grab()) video->retrieve(image);
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

ImageSourceOptions limit_for_extractor(ImageSourceOptions options,
                                       const FeatureExtractor& extractor) {
  if (options.max_extracted_pixels != 0 || !(extractor.bytes_per_pixel() > 0)) return options;
  options.max_extracted_pixels = extractor.max_pixels();
  char reason[160];
  std::snprintf(reason, sizeof reason,
                "the most %s extracts within %.3g GiB of memory (about %g bytes a pixel)",
                extractor.name().c_str(),
                static_cast<double>(kDefaultExtractionMemoryBytes) / (1 << 30),
                extractor.bytes_per_pixel());
  options.extraction_limit_reason = reason;
  return options;
}

cv::Mat read_grey_image(const std::string& path, std::uint64_t max_pixels) {
  return to_grey(read_checked_image(path, true, max_pixels));
}

cv::Mat read_frame(const std::string& name, FramePixels pixels) {
  std::error_code error;
  std::string video;
  long long frame = 0;
  if (!fs::exists(name, error) && split_video_frame_name(name, video, frame) &&
      fs::is_regular_file(video, error)) {
    return to_pixels(read_video_frame(video, frame), pixels);
  }
  return to_pixels(read_checked_image(name, pixels == FramePixels::kGrey, kDefaultMaxImagePixels),
                   pixels);
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
  std::unique_ptr<media::Video> video;
  std::string video_path;
  long long video_frame = -1;
  long long video_declared_frames = 0;  // CAP_PROP_FRAME_COUNT; 0 when unknown
  std::size_t unreadable_frames = 0;
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
    } else if (!fs::is_regular_file(status)) {
      // A FIFO or a device would block or never end; videos are regular files too.
      struct stat st {};
      const char* kind =
          ::stat(path.c_str(), &st) == 0 ? detail::file_kind(st.st_mode) : "a special file";
      const std::string problem = std::string("is ") + kind + ", not a regular file or a directory";
      if (list != nullptr) throw FileError(*list, "lists '" + path + "', which " + problem);
      throw FileError(path, problem);
    } else if (has_image_extension(path)) {
      inputs.push_back({path, false});
    } else if (has_video_extension(path)) {
      inputs.push_back({path, true});
    } else if (has_list_extension(path)) {
      if (list != nullptr) throw FileError(*list, "lists '" + path + "'; lists do not nest");
      add_list(path);
    } else if (media_module().have_image_reader(path)) {
      inputs.push_back({path, false});
    } else {
      inputs.push_back({path, true});  // anything else: let the video backends try
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
    while (video->grab()) {
      ++video_frame;
      if (static_cast<double>(video_frame) + 1e-9 < next_sample) continue;
      next_sample += video_step;
      if (!keep_next()) continue;
      cv::Mat image;
      std::string name = video_path + "#" + std::to_string(video_frame);
      const std::size_t index = frames_kept++;
      if (!video->retrieve(image) || image.empty()) {
        const std::string problem = "cannot decode frame " + std::to_string(video_frame);
        if (!options.skip_unreadable) throw FileError(video_path, problem);
        deliver_unreadable(frame, std::move(name), index, problem);
        return true;
      }
      const cv::Mat grey = to_grey(image);
      deliver(frame, grey, grey.size(), std::move(name), index);
      return true;
    }
    // The backend stops at the first frame it cannot decode: what the
    // container declared and was not read is reported, not silently lost.
    if (video_declared_frames > video_frame + 1) {
      unreadable_frames += static_cast<std::size_t>(video_declared_frames - (video_frame + 1));
    }
    video.reset();
    return false;
  }

  void open_video(const std::string& path) {
    video_path = path;
    video_frame = -1;
    next_sample = 0;
    video = open_video_file(path);
    const double width = video->width();
    const double height = video->height();
    if (width >= 0 && height >= 0 && width < 1e12 && height < 1e12) {
      check_pixel_count(path, "video", static_cast<std::uint64_t>(width),
                        static_cast<std::uint64_t>(height), options.max_pixels);
      check_extracted_pixels(path, "video frame", static_cast<std::uint64_t>(width),
                             static_cast<std::uint64_t>(height), options);
    }
    const double declared = video->frame_count();
    video_declared_frames =
        std::isfinite(declared) && declared > 0 && declared < 1e15 ? std::llround(declared) : 0;
    const double fps = reported_frame_rate(*video);
    video_step = (options.video_fps > 0 && fps > options.video_fps) ? fps / options.video_fps : 1;
  }

  // `grey` of a file or video frame of `file_size`.
  void deliver(Frame& frame, const cv::Mat& grey, cv::Size file_size, std::string name,
               std::size_t index) {
    frame.image = limit_width(grey, file_size, options.max_width);
    frame.name = std::move(name);
    frame.index = index;
    frame.scale = static_cast<double>(frame.image.cols) / file_size.width;
    frame.unreadable.clear();
  }

  static void deliver_unreadable(Frame& frame, std::string name, std::size_t index,
                                 std::string problem) {
    frame.image.release();
    frame.name = std::move(name);
    frame.index = index;
    frame.scale = 1;
    frame.unreadable = std::move(problem);
  }

  bool next(Frame& frame) {
    for (;;) {
      if (video) {
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
      // The index is taken first: a frame that fails keeps it, so the frames
      // after it are numbered as in the sequence.
      const std::size_t index = frames_kept++;
      cv::Mat image;
      cv::Size file_size;
      try {
        image = read_checked_image(input.path, true, options.max_pixels, &options, &file_size);
      } catch (const FileError& e) {
        if (!options.skip_unreadable) throw;
        deliver_unreadable(frame, input.path, index, e.problem());
        return true;
      }
      deliver(frame, to_grey(image), file_size, input.path, index);
      return true;
    }
  }
};

ImageSource::ImageSource(const std::vector<std::string>& inputs, ImageSourceOptions options)
    : impl_(std::make_unique<Impl>()) {
  if (inputs.empty()) throw InvalidArgument("ImageSource: no inputs given");
  if (options.stride == 0) options.stride = 1;
  if (options.stride > kMaxStride)
    throw InvalidArgument("ImageSource: stride must be at most " + std::to_string(kMaxStride));
  if (options.max_width < 0 || options.max_width > kMaxFrameWidth)
    throw InvalidArgument("ImageSource: max_width must be in [0, " +
                          std::to_string(kMaxFrameWidth) + "]");
  if (!(options.video_fps >= 0 && options.video_fps <= kMaxVideoFps))
    throw InvalidArgument("ImageSource: video_fps must be in [0, " +
                          std::to_string(static_cast<int>(kMaxVideoFps)) + "]");
  if (options.max_pixels == 0) throw InvalidArgument("ImageSource: max_pixels must be >= 1");
  impl_->options = options;
  for (const std::string& input : inputs) impl_->add(input, nullptr);
}

ImageSource::ImageSource(ImageSource&&) noexcept = default;
ImageSource& ImageSource::operator=(ImageSource&&) noexcept = default;
ImageSource::~ImageSource() = default;

bool ImageSource::next(Frame& frame) {
  return impl_->next(frame);
}

std::size_t ImageSource::unreadable_frames() const noexcept {
  return impl_->unreadable_frames;
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
      input.frame_rate = reported_frame_rate(*open_video_file(input.path));
    }
    if (input.frame_rate == 0 || (rate != 0 && input.frame_rate != rate)) return 0;
    rate = input.frame_rate;
  }
  const ImageSourceOptions& options = impl_->options;
  if (options.video_fps > 0) rate = std::min(rate, options.video_fps);
  return rate / static_cast<double>(options.stride);
}

}  // namespace binbow::vision
