#include "binbow/vision/features.h"

#include <algorithm>
#include <bitset>
#include <cstdint>
#include <fstream>
#include <string>
#include <thread>
#include <vector>

#include <gtest/gtest.h>
#include <opencv2/features2d.hpp>
#include <opencv2/imgproc.hpp>

#include "binbow/error.h"
#include "binbow/vision/image_source.h"
#include "support/test_support.h"
#include "vision/brief_pattern.h"

namespace binbow::vision {
namespace {

using test::shared_data;

cv::Mat grey(const std::string& relative) {
  return read_grey_image(shared_data(relative));
}

// DVision::BRIEF written out plainly: whole-image 9x9 sigma-2 Gaussian, bit i
// set when the first point of test i is darker than the second, stored in a
// std::bitset as DVision/DBoW2 do.
std::bitset<256> reference_brief(const cv::Mat& smoothed, int x, int y,
                                 const BriefPattern& pattern) {
  std::bitset<256> bits;
  for (std::size_t i = 0; i < 256; ++i) {
    const int x1 = x + pattern.x1[i], y1 = y + pattern.y1[i];
    const int x2 = x + pattern.x2[i], y2 = y + pattern.y2[i];
    if (x1 < 0 || y1 < 0 || x2 < 0 || y2 < 0 || x1 >= smoothed.cols || x2 >= smoothed.cols ||
        y1 >= smoothed.rows || y2 >= smoothed.rows) {
      continue;
    }
    if (smoothed.at<std::uint8_t>(y1, x1) < smoothed.at<std::uint8_t>(y2, x2)) bits.set(i);
  }
  return bits;
}

// Our bytes from a DBoW2 descriptor string, by the rule in features.h.
std::vector<std::uint8_t> bytes_from_dbow2_string(const std::string& text) {
  std::vector<std::uint8_t> bytes(text.size() / 8, 0);
  for (std::size_t i = 0; i < text.size(); ++i) {
    if (text[text.size() - 1 - i] == '1') bytes[i / 8] |= static_cast<std::uint8_t>(1u << (i % 8));
  }
  return bytes;
}

TEST(BriefPattern, BuiltInEqualsThePatternFile) {
  const BriefPattern file =
      load_brief_pattern(shared_data("vins-lite-brief-vocab/brief_pattern.yml"));
  const BriefPattern& built_in = default_brief_pattern();
  EXPECT_EQ(file.tests(), 256u);
  EXPECT_EQ(file.x1, built_in.x1);
  EXPECT_EQ(file.y1, built_in.y1);
  EXPECT_EQ(file.x2, built_in.x2);
  EXPECT_EQ(file.y2, built_in.y2);
  EXPECT_EQ(built_in.radius(), 24);  // a 48x48 patch
  const BriefPattern::Extent extent = built_in.extent();
  EXPECT_EQ(extent.min_x, -24);
  EXPECT_EQ(extent.min_y, -23);
  EXPECT_EQ(extent.max_x, 24);
  EXPECT_EQ(extent.max_y, 24);
}

TEST(BriefPattern, BadFilesGiveFileError) {
  test::TempDir dir;
  const auto write = [&](const std::string& name, const std::string& text) {
    std::ofstream(dir.file(name)) << text;
    return dir.file(name);
  };
  const std::string cases[] = {
      write("missing_key.yml", "%YAML:1.0\nx1: [1, 2, 3, 4, 5, 6, 7, 8]\n"),
      write("unequal.yml",
            "%YAML:1.0\nx1: [1,2,3,4,5,6,7,8]\ny1: [1,2,3,4,5,6,7,8]\nx2: [1,2,3,4,5,6,7,8]\n"
            "y2: [1,2,3]\n"),
      write("not_multiple.yml", "%YAML:1.0\nx1: [1]\ny1: [1]\nx2: [1]\ny2: [1]\n"),
      write("huge.yml",
            "%YAML:1.0\nx1: [1,2,3,4,5,6,7,100000]\ny1: [1,2,3,4,5,6,7,8]\nx2: "
            "[1,2,3,4,5,6,7,8]\ny2: [1,2,3,4,5,6,7,8]\n"),
      write("garbage.yml", "%YAML:1.0\nx1: [ {{{ \n\x01\x02"),
      write("empty.yml", ""),
      dir.file("absent.yml"),
  };
  for (const std::string& path : cases) {
    BriefOptions options;
    options.pattern_file = path;
    try {
      make_brief_extractor(options);
      ADD_FAILURE() << "accepted " << path;
    } catch (const FileError& e) {
      EXPECT_EQ(e.path(), path) << e.what();
    }
  }
}

// Bit-exactness with DVision::BRIEF on real images, through the full pipeline;
// with keep_border_corners, tests outside the image are 0 bits.
TEST(Brief, BitExactWithTheReferenceDefinition) {
  const BriefPattern& pattern = default_brief_pattern();
  for (const bool keep_border : {false, true})
    for (const char* image_name : {"dbow2-demo-images/image1.png", "rtabmap-samples/samples/12.jpg",
                                   "opencv-doc-samples/graf1.png"}) {
      SCOPED_TRACE(image_name);
      SCOPED_TRACE(keep_border ? "border corners kept" : "inside corners only");
      const cv::Mat image = grey(image_name);
      BriefOptions options;
      options.max_features = 0;  // all corners: covers the image border too
      options.keep_border_corners = keep_border;
      const Features features = make_brief_extractor(options)->extract(image);
      ASSERT_GT(features.keypoints.size(), 150u);
      std::size_t at_border = 0;
      ASSERT_EQ(features.descriptors.rows(), features.keypoints.size());
      ASSERT_EQ(features.descriptors.code_size(), 32u);

      cv::Mat smoothed;
      cv::GaussianBlur(image, smoothed, cv::Size(9, 9), 2, 2);
      for (std::size_t k = 0; k < features.keypoints.size(); ++k) {
        const Keypoint& keypoint = features.keypoints[k];
        const int x = static_cast<int>(keypoint.x), y = static_cast<int>(keypoint.y);
        // DLoopDetector's pattern: x from -24 to +24, y from -23 to +24.
        const bool inside = x >= 24 && y >= 23 && x < image.cols - 24 && y < image.rows - 24;
        if (!keep_border) {
          ASSERT_TRUE(inside) << x << "," << y;
        }
        at_border += inside ? 0 : 1;
        const std::bitset<256> expected = reference_brief(smoothed, x, y, pattern);
        // What DBoW2 writes for this descriptor, read back by the documented rule.
        const std::vector<std::uint8_t> expected_bytes =
            bytes_from_dbow2_string(expected.to_string());
        ASSERT_TRUE(
            std::equal(expected_bytes.begin(), expected_bytes.end(), features.descriptors.row(k)))
            << "keypoint " << k << " at " << x << "," << y;
        for (std::size_t i = 0; i < 256; ++i) {
          ASSERT_EQ(expected[i], ((features.descriptors.row(k)[i / 8] >> (i % 8)) & 1) != 0);
        }
      }
      if (keep_border) {
        EXPECT_GT(at_border, 0u) << "no border corner was checked";
      }
    }
}

// Isolated bright dots on black are FAST corners exactly at the dots.
cv::Mat dots(cv::Size size, const std::vector<cv::Point>& points) {
  cv::Mat image(size, CV_8U, cv::Scalar(0));
  for (const cv::Point& p : points) image.at<std::uint8_t>(p) = 255;
  return image;
}

std::vector<cv::Point> keypoint_positions(const Features& features) {
  std::vector<cv::Point> positions;
  for (const Keypoint& k : features.keypoints)
    positions.emplace_back(static_cast<int>(k.x), static_cast<int>(k.y));
  std::sort(positions.begin(), positions.end(),
            [](cv::Point a, cv::Point b) { return a.x != b.x ? a.x < b.x : a.y < b.y; });
  return positions;
}

// The margin is the pattern's extent on each side (x from -24 to +24, y from
// -23 to +24 for the built-in pattern), not its radius on every side: corners
// in row 23 have every test inside the image and are kept.
TEST(Brief, MarginIsThePatternExtentPerSide) {
  const std::vector<cv::Point> kept = {{24, 50}, {40, 75}, {50, 23}, {75, 40}};
  const std::vector<cv::Point> dropped = {{23, 60}, {60, 22}, {60, 76}, {76, 60}};
  std::vector<cv::Point> all = kept;
  all.insert(all.end(), dropped.begin(), dropped.end());
  const cv::Mat image = dots({100, 100}, all);
  BriefOptions options;
  options.max_features = 0;
  EXPECT_EQ(keypoint_positions(make_brief_extractor(options)->extract(image)), kept);
  options.keep_border_corners = true;
  EXPECT_EQ(keypoint_positions(make_brief_extractor(options)->extract(image)).size(), all.size());

  // A custom pattern's own extent: x from -5 to +3, y from -4 to +7 (FAST
  // finds no corner within 3 pixels of the border).
  test::TempDir dir;
  const std::string pattern = dir.file("pattern.yml");
  std::ofstream(pattern)
      << "%YAML:1.0\nx1: [-5, 0, 0, 0, 0, 0, 0, 0]\ny1: [-4, 0, 0, 0, 0, 0, 0, 0]\n"
         "x2: [3, 1, 1, 1, 1, 1, 1, 1]\ny2: [7, 1, 1, 1, 1, 1, 1, 1]\n";
  options.pattern_file = pattern;
  options.keep_border_corners = false;
  const std::vector<cv::Point> custom_kept = {{5, 4}, {16, 12}};  // 16 + 3 < 20, 12 + 7 < 20
  const std::vector<cv::Point> custom_dropped = {{4, 12}, {12, 3}, {17, 6}, {10, 13}};
  all = custom_kept;
  all.insert(all.end(), custom_dropped.begin(), custom_dropped.end());
  const Features custom = make_brief_extractor(options)->extract(dots({20, 20}, all));
  EXPECT_EQ(keypoint_positions(custom), custom_kept);
}

TEST(Brief, KeepsTheStrongestFastCornersInside) {
  const cv::Mat image = grey("dbow2-demo-images/image1.png");
  std::vector<cv::KeyPoint> corners;
  cv::FAST(image, corners, 10, true);
  std::vector<float> inside;
  for (const cv::KeyPoint& corner : corners) {
    if (corner.pt.x >= 24 && corner.pt.y >= 23 && corner.pt.x < image.cols - 24 &&
        corner.pt.y < image.rows - 24) {
      inside.push_back(corner.response);
    }
  }
  std::sort(inside.rbegin(), inside.rend());
  ASSERT_GT(inside.size(), 300u);

  const Features features = make_brief_extractor()->extract(image);
  ASSERT_EQ(features.keypoints.size(), 300u);
  for (std::size_t i = 0; i < 300; ++i) {
    EXPECT_EQ(features.keypoints[i].response, inside[i]) << i;
    EXPECT_EQ(features.keypoints[i].angle, -1.f);
    EXPECT_EQ(features.keypoints[i].octave, 0);
  }
  // The pattern file and the built-in pattern give the same descriptors.
  BriefOptions from_file;
  from_file.pattern_file = shared_data("vins-lite-brief-vocab/brief_pattern.yml");
  const Features again = make_brief_extractor(from_file)->extract(image);
  ASSERT_EQ(again.descriptors.rows(), 300u);
  EXPECT_TRUE(std::equal(again.descriptors.data(), again.descriptors.data() + 300 * 32,
                         features.descriptors.data()));
}

TEST(Brief, NonMaxSuppressionOffGivesMoreCorners) {
  const cv::Mat image = grey("dbow2-demo-images/image1.png");
  BriefOptions options;
  options.max_features = 0;
  const std::size_t suppressed = make_brief_extractor(options)->extract(image).keypoints.size();
  options.non_max_suppression = false;
  const std::size_t all = make_brief_extractor(options)->extract(image).keypoints.size();
  EXPECT_GT(all, suppressed);
}

TEST(Extractors, EmptyAndFlatImagesGiveEmptyFeatures) {
  for (const char* name : {"brief", "orb", "akaze", "brisk"}) {
    SCOPED_TRACE(name);
    const auto extractor = make_extractor(name);
    for (const cv::Mat& image :
         {cv::Mat(), cv::Mat(480, 640, CV_8UC1, cv::Scalar(128)),
          cv::Mat(10, 10, CV_8UC1, cv::Scalar(0)), cv::Mat(1, 1, CV_8UC1, cv::Scalar(7))}) {
      const Features features = extractor->extract(image);
      EXPECT_TRUE(features.keypoints.empty());
      EXPECT_TRUE(features.descriptors.empty());
      EXPECT_EQ(features.descriptors.code_size(), extractor->code_size());
    }
    EXPECT_THROW(extractor->extract(cv::Mat(10, 10, CV_8UC3)), InvalidArgument);
    EXPECT_THROW(extractor->extract(cv::Mat(10, 10, CV_32FC1)), InvalidArgument);
  }
  EXPECT_THROW(make_extractor("sift"), InvalidArgument);
}

// The list tools offer as choices is exactly what make_extractor() builds.
TEST(Extractors, NamesListEveryExtractorOrbFirst) {
  const std::vector<std::string> names = extractor_names();
  EXPECT_EQ(names, (std::vector<std::string>{"orb", "brief", "akaze", "brisk"}));
  for (const std::string& name : names) EXPECT_EQ(make_extractor(name)->name(), name);
  try {
    make_extractor("sift");
    ADD_FAILURE() << "sift accepted";
  } catch (const InvalidArgument& e) {
    EXPECT_NE(std::string(e.what()).find("expected one of orb, brief, akaze, brisk"),
              std::string::npos)
        << e.what();
  }
}

TEST(Extractors, CodeSizesAndCounts) {
  const cv::Mat image = grey("dbow2-demo-images/image1.png");
  struct Case {
    const char* name;
    std::size_t code_size;
    std::size_t max_features;
  };
  for (const Case& c : {Case{"brief", 32, 300}, Case{"orb", 32, 1000}, Case{"akaze", 61, 400},
                        Case{"brisk", 64, 400}}) {
    SCOPED_TRACE(c.name);
    const auto extractor = make_extractor(c.name, static_cast<int>(c.max_features));
    EXPECT_EQ(extractor->name(), c.name);
    EXPECT_EQ(extractor->code_size(), c.code_size);
    const Features features = extractor->extract(image);
    EXPECT_GT(features.keypoints.size(), c.max_features / 4);
    EXPECT_LE(features.keypoints.size(), c.max_features);
    EXPECT_EQ(features.descriptors.rows(), features.keypoints.size());
    EXPECT_EQ(features.descriptors.code_size(), c.code_size);
  }
  OrbOptions orb;
  orb.max_features = 200;
  EXPECT_LE(make_orb_extractor(orb)->extract(image).keypoints.size(), 200u);
  orb.levels = 0;
  EXPECT_THROW(make_orb_extractor(orb), InvalidArgument);
}

TEST(Extractors, ConcurrentCallsGiveTheSameResult) {
  const cv::Mat image = grey("rtabmap-samples/samples/5.jpg");
  for (const char* name : {"brief", "orb", "brisk"}) {
    SCOPED_TRACE(name);
    const auto extractor = make_extractor(name);
    const Features expected = extractor->extract(image);
    std::vector<Features> results(4);
    std::vector<std::thread> threads;
    for (Features& result : results) {
      threads.emplace_back([&] { result = extractor->extract(image); });
    }
    for (std::thread& thread : threads) thread.join();
    for (const Features& result : results) {
      ASSERT_EQ(result.descriptors.rows(), expected.descriptors.rows());
      EXPECT_TRUE(std::equal(result.descriptors.data(),
                             result.descriptors.data() +
                                 expected.descriptors.rows() * expected.descriptors.code_size(),
                             expected.descriptors.data()));
    }
  }
}

TEST(Extractors, OpenCvConversionsRoundTrip) {
  std::vector<cv::KeyPoint> keypoints = {cv::KeyPoint(1.5f, 2.5f, 7, 30, 0.5f, 2),
                                         cv::KeyPoint(10, 20, 31, -1, 9, 0)};
  cv::Mat descriptors(2, 3, CV_8UC1);
  for (int i = 0; i < 6; ++i) descriptors.data[i] = static_cast<uchar>(i * 11);
  const Features features = features_from_opencv(keypoints, descriptors, 99);
  ASSERT_EQ(features.descriptors.code_size(), 3u);
  EXPECT_EQ(features.descriptors.row(1)[2], 55);
  const std::vector<cv::KeyPoint> back = to_opencv(features.keypoints);
  ASSERT_EQ(back.size(), 2u);
  EXPECT_EQ(back[0].pt, keypoints[0].pt);
  EXPECT_EQ(back[0].angle, 30);
  EXPECT_EQ(back[0].octave, 2);
  EXPECT_EQ(features_from_opencv({}, cv::Mat(), 61).descriptors.code_size(), 61u);
  EXPECT_THROW(features_from_opencv(keypoints, cv::Mat(2, 3, CV_32FC1), 3), InvalidArgument);
  EXPECT_THROW(features_from_opencv(keypoints, cv::Mat(3, 3, CV_8UC1), 3), InvalidArgument);
  EXPECT_THROW(make_opencv_extractor(nullptr, "none"), InvalidArgument);
  EXPECT_THROW(make_opencv_extractor(cv::SIFT::create(), "sift"), InvalidArgument);
}

// Each extractor's measured memory per pixel (docs/limits.md) sets the most
// pixels it extracts within the default budget: only AKAZE's is below the
// decoder's 100 MP (a 16 MP image, measured at 1.8 GB, passes; 25 MP does not).
TEST(FeatureExtractor, MemoryPerPixelSetsEachExtractorsPixelLimit) {
  for (const std::string& name : extractor_names()) {
    const auto extractor = make_extractor(name);
    ASSERT_GT(extractor->bytes_per_pixel(), 0) << name;
    EXPECT_EQ(extractor->max_pixels(),
              static_cast<std::uint64_t>(static_cast<double>(kDefaultExtractionMemoryBytes) /
                                         extractor->bytes_per_pixel()))
        << name;
    EXPECT_EQ(extractor->max_pixels(std::uint64_t{1} << 20),
              static_cast<std::uint64_t>((1 << 20) / extractor->bytes_per_pixel()))
        << name;
    if (name != "akaze") {
      EXPECT_GE(extractor->max_pixels(), kDefaultMaxImagePixels) << name;
    }
  }
  const auto akaze = make_extractor("akaze");
  EXPECT_GT(akaze->max_pixels(), 16'000'000u);
  EXPECT_LT(akaze->max_pixels(), 25'000'000u);
  EXPECT_EQ(make_opencv_extractor(cv::ORB::create(), "orb")->max_pixels(), UINT64_MAX);
  EXPECT_EQ(make_opencv_extractor(cv::ORB::create(), "orb", 0, 4)->bytes_per_pixel(), 4);
}

}  // namespace
}  // namespace binbow::vision
