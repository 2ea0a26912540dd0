#include "vision/jpeg_decoder.h"

#include <filesystem>
#include <string>
#include <vector>

#include <gtest/gtest.h>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "support/test_support.h"

namespace binbow::vision {
namespace {

std::vector<std::string> real_jpegs() {
  std::vector<std::string> paths;
  for (const char* folder : {"rtabmap-samples/samples", "opencv-doc-samples"})
    for (const auto& entry : std::filesystem::directory_iterator(test::shared_data(folder)))
      if (entry.path().extension() == ".jpg") paths.push_back(entry.path().string());
  return paths;
}

DecodedJpeg decode(const std::vector<std::uint8_t>& bytes, bool grey, int max_width = 0) {
  return decode_jpeg(bytes.data(), bytes.size(), grey, max_width);
}

bool same_pixels(const cv::Mat& a, const cv::Mat& b) {
  return a.size() == b.size() && a.type() == b.type() && cv::norm(a, b, cv::NORM_INF) == 0;
}

// The same libjpeg, the same settings (JCS_GRAYSCALE, JCS_EXT_BGR, the
// default integer inverse DCT): the pixels are exactly OpenCV's.
TEST(DecodeJpeg, GreyAndBgrAreExactlyOpenCVs) {
  const std::vector<std::string> paths = real_jpegs();
  ASSERT_GE(paths.size(), 85u) << "rtabmap-samples and opencv-doc-samples JPEGs are missing";
  for (const std::string& path : paths) {
    SCOPED_TRACE(path);
    const std::vector<std::uint8_t> bytes = test::read_file(path);
    const DecodedJpeg grey = decode(bytes, true);
    ASSERT_TRUE(grey.problem.empty()) << grey.problem;
    EXPECT_TRUE(same_pixels(grey.image, cv::imread(path, cv::IMREAD_GRAYSCALE)));
    EXPECT_EQ(grey.full_size, grey.image.size());
    const DecodedJpeg bgr = decode(bytes, false);
    EXPECT_TRUE(same_pixels(bgr.image, cv::imread(path, cv::IMREAD_COLOR)));
  }
}

TEST(DecodeJpeg, ProgressiveIsCheckedThenDecoded) {
  const cv::Mat frame = cv::imread(test::shared_data("rtabmap-samples/samples/7.jpg"));
  ASSERT_FALSE(frame.empty());
  std::vector<std::uint8_t> progressive;
  ASSERT_TRUE(cv::imencode(".jpg", frame, progressive, {cv::IMWRITE_JPEG_PROGRESSIVE, 1}));
  const DecodedJpeg decoded = decode(progressive, true);
  ASSERT_TRUE(decoded.problem.empty()) << decoded.problem;
  EXPECT_TRUE(same_pixels(decoded.image, cv::imdecode(progressive, cv::IMREAD_GRAYSCALE)));
  progressive.resize(progressive.size() * 2 / 3);
  EXPECT_EQ(decode(progressive, true).problem, "Premature end of JPEG file");
}

// The one-pass check (each MCU's coefficients as libjpeg decodes them)
// refuses exactly the files jpeg_decoding_problem's separate pass refuses,
// and the per-thread decompressor decodes the next file as if new.
TEST(DecodeJpeg, RefusesWhatTheSeparateCheckRefuses) {
  const std::string path = test::shared_data("rtabmap-samples/samples/1.jpg");
  const std::vector<std::uint8_t> jpeg = test::read_file(path);
  const cv::Mat expected = cv::imread(path, cv::IMREAD_GRAYSCALE);
  std::size_t sos = 0;
  while (sos + 3 < jpeg.size() && !(jpeg[sos] == 0xFF && jpeg[sos + 1] == 0xDA)) ++sos;
  ASSERT_LT(sos + 3, jpeg.size()) << "no start of scan";
  const std::size_t scan = sos + 2 + (std::size_t{jpeg[sos + 2]} << 8 | jpeg[sos + 3]);
  const std::size_t end = jpeg.size() - 2;
  constexpr std::size_t kDamaged = 60;
  std::size_t refused = 0;
  for (std::size_t k = 0; k < kDamaged; ++k) {
    std::vector<std::uint8_t> damaged = jpeg;
    const std::size_t at = scan + (end - scan) * (k + 1) / (kDamaged + 1);
    damaged[at] ^= 0xFF;
    damaged[at + 1] ^= 0x55;
    const std::string separate = jpeg_decoding_problem(damaged.data(), damaged.size());
    const DecodedJpeg decoded = decode(damaged, true);
    EXPECT_EQ(decoded.problem.empty(), separate.empty())
        << "damage " << k << ": one pass '" << decoded.problem << "', separate '" << separate
        << "'";
    EXPECT_EQ(decoded.image.empty(), !decoded.problem.empty());
    refused += decoded.problem.empty() ? 0 : 1;
    EXPECT_TRUE(same_pixels(decode(jpeg, true).image, expected)) << "after damage " << k;
  }
  EXPECT_GE(refused, kDamaged / 2);
}

// An APP1 Exif segment with only the orientation tag, after the SOI marker.
std::vector<std::uint8_t> with_orientation(const std::vector<std::uint8_t>& jpeg, int orientation) {
  std::string tiff("MM\0\x2A\0\0\0\x08", 8);             // big-endian, first directory at 8
  tiff += std::string("\0\x01", 2);                      // one entry:
  tiff += std::string("\x01\x12\0\x03\0\0\0\x01\0", 9);  // tag 274, SHORT, count 1
  tiff += static_cast<char>(orientation);
  tiff += std::string(6, '\0');  // padding, no next directory
  const std::string body = std::string("Exif\0\0", 6) + tiff;
  std::string out(jpeg.begin(), jpeg.begin() + 2);
  out += "\xFF\xE1";
  out += static_cast<char>(0);
  out += static_cast<char>(body.size() + 2);
  out += body;
  out.append(jpeg.begin() + 2, jpeg.end());
  return {out.begin(), out.end()};
}

TEST(DecodeJpeg, TurnsAsExifOrientationSaysAsOpenCVDoes) {
  cv::Mat image(48, 64, CV_8UC1);
  for (int y = 0; y < image.rows; ++y)
    for (int x = 0; x < image.cols; ++x)
      image.at<std::uint8_t>(y, x) = cv::saturate_cast<std::uint8_t>(x * 3 + y);
  std::vector<std::uint8_t> jpeg;
  ASSERT_TRUE(cv::imencode(".jpg", image, jpeg));
  for (int orientation = 1; orientation <= 8; ++orientation) {
    SCOPED_TRACE(orientation);
    const std::vector<std::uint8_t> turned = with_orientation(jpeg, orientation);
    EXPECT_EQ(jpeg_exif_orientation(turned.data(), turned.size()), orientation);
    const DecodedJpeg decoded = decode(turned, true);
    ASSERT_TRUE(decoded.problem.empty()) << decoded.problem;
    const cv::Mat opencv = cv::imdecode(turned, cv::IMREAD_GRAYSCALE);
    EXPECT_EQ(decoded.image.size(), orientation >= 5 ? cv::Size(48, 64) : cv::Size(64, 48));
    EXPECT_TRUE(same_pixels(decoded.image, opencv));
    EXPECT_EQ(decoded.full_size, decoded.image.size());
  }
  EXPECT_EQ(jpeg_exif_orientation(jpeg.data(), jpeg.size()), 1);
}

// max_width lets libjpeg decode at 1/2, 1/4 or 1/8 of the size, never
// narrower than twice max_width (so that the final area resampling still
// averages); the result is close to resizing the whole image.
TEST(DecodeJpeg, MaxWidthScalesInTheInverseDct) {
  const std::string path = test::shared_data("rtabmap-samples/samples/3.jpg");  // 512x384
  const std::vector<std::uint8_t> bytes = test::read_file(path);
  const cv::Mat full = cv::imread(path, cv::IMREAD_GRAYSCALE);
  ASSERT_EQ(full.size(), cv::Size(512, 384));
  for (const auto& [max_width, width] : std::vector<std::pair<int, int>>{{0, 512},
                                                                         {600, 512},
                                                                         {256, 512},
                                                                         {200, 512},
                                                                         {128, 256},
                                                                         {100, 256},
                                                                         {64, 128},
                                                                         {32, 64},
                                                                         {10, 64}}) {
    SCOPED_TRACE(max_width);
    const DecodedJpeg decoded = decode(bytes, true, max_width);
    ASSERT_EQ(decoded.image.cols, width);
    EXPECT_EQ(decoded.image.rows, width * 3 / 4);
    EXPECT_EQ(decoded.full_size, full.size());
    cv::Mat resized;
    cv::resize(full, resized, decoded.image.size(), 0, 0, cv::INTER_AREA);
    cv::Mat difference;
    cv::absdiff(resized, decoded.image, difference);
    EXPECT_LT(cv::mean(difference)[0], 2.0);
  }
}

}  // namespace
}  // namespace binbow::vision
