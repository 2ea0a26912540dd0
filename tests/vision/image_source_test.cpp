#include "binbow/vision/image_source.h"

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include <sys/stat.h>

#include <gtest/gtest.h>
#include <opencv2/features2d.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <opencv2/videoio.hpp>

#include "binbow/error.h"
#include "binbow/vision/features.h"
#include "support/test_support.h"
#include "vision/image_header.h"
#include "vision/natural_order.h"

namespace binbow::vision {
namespace {

using test::TempDir;

// A 40x30 colour image whose pixels depend on `seed`, so frames differ.
cv::Mat colour_image(int seed, int width = 40, int height = 30) {
  cv::Mat image(height, width, CV_8UC3);
  for (int y = 0; y < height; ++y) {
    for (int x = 0; x < width; ++x) {
      image.at<cv::Vec3b>(y, x) = cv::Vec3b(static_cast<uchar>((x * 5 + seed * 40) % 256),
                                            static_cast<uchar>((y * 7 + seed * 20) % 256),
                                            static_cast<uchar>((x + y + seed) % 256));
    }
  }
  return image;
}

void write_text(const std::string& path, const std::string& text) {
  std::ofstream(path, std::ios::binary) << text;
}

std::vector<std::string> read_all_names(ImageSource& source) {
  std::vector<std::string> names;
  Frame frame;
  while (source.next(frame)) {
    EXPECT_EQ(frame.index, names.size());
    EXPECT_EQ(frame.image.type(), CV_8UC1);
    names.push_back(frame.name);
  }
  return names;
}

std::string filename(const std::string& path) {
  return std::filesystem::path(path).filename().string();
}

// Expects `action` to throw FileError whose message names `path`.
template <typename Action>
void expect_file_error_naming(const std::string& path, Action action) {
  try {
    action();
    ADD_FAILURE() << "no FileError for " << path;
  } catch (const FileError& e) {
    EXPECT_NE(std::string(e.what()).find(path), std::string::npos) << e.what();
    EXPECT_EQ(e.path(), path);
  }
}

TEST(NaturalOrder, DigitRunsCompareAsNumbers) {
  EXPECT_TRUE(natural_less("2.jpg", "10.jpg"));
  EXPECT_FALSE(natural_less("10.jpg", "2.jpg"));
  EXPECT_TRUE(natural_less("frame9.png", "frame10.png"));
  EXPECT_TRUE(natural_less("a.png", "B.png"));
  EXPECT_TRUE(natural_less("img2_3", "img2_10"));
  EXPECT_TRUE(natural_less("99999999999999999999999.png", "100000000000000000000000.png"));
  // Equal as numbers: total order through the exact text, never both ways.
  EXPECT_NE(natural_less("007.png", "7.png"), natural_less("7.png", "007.png"));
  EXPECT_FALSE(natural_less("x1", "x1"));

  std::vector<std::string> names = {"10.jpg", "1.jpg", "img10.png", "2.jpg", "img9.png", "20.jpg"};
  std::sort(names.begin(), names.end(), natural_less);
  EXPECT_EQ(names, (std::vector<std::string>{"1.jpg", "2.jpg", "10.jpg", "20.jpg", "img9.png",
                                             "img10.png"}));
}

TEST(ReadGreyImage, ConvertsColourToGrey) {
  TempDir dir;
  const cv::Mat colour = colour_image(3);
  ASSERT_TRUE(cv::imwrite(dir.file("c.png"), colour));
  const cv::Mat grey = read_grey_image(dir.file("c.png"));
  ASSERT_EQ(grey.type(), CV_8UC1);
  ASSERT_EQ(grey.size(), colour.size());
  cv::Mat expected;
  cv::cvtColor(colour, expected, cv::COLOR_BGR2GRAY);
  EXPECT_LE(cv::norm(grey, expected, cv::NORM_INF), 1.0);
}

TEST(ReadGreyImage, RealJpegAndPngDecode) {
  const cv::Mat jpeg = read_grey_image(test::shared_data("rtabmap-samples/samples/1.jpg"));
  EXPECT_EQ(jpeg.size(), cv::Size(512, 384));
  const cv::Mat png = read_grey_image(test::shared_data("opencv-doc-samples/graf1.png"));
  EXPECT_EQ(png.size(), cv::Size(800, 640));
  const cv::Mat exif = read_grey_image(test::shared_data("opencv-doc-samples/leuvenA.jpg"));
  EXPECT_EQ(exif.type(), CV_8UC1);
  EXPECT_FALSE(exif.empty());
}

TEST(ReadGreyImage, BadFilesGiveFileErrorNamingTheFile) {
  TempDir dir;
  write_text(dir.file("empty.png"), "");
  expect_file_error_naming(dir.file("empty.png"), [&] { read_grey_image(dir.file("empty.png")); });

  const std::vector<std::uint8_t> jpeg =
      test::read_file(test::shared_data("rtabmap-samples/samples/1.jpg"));
  ASSERT_GT(jpeg.size(), 1000u);
  test::write_file(dir.file("truncated.jpg"),
                   std::vector<std::uint8_t>(jpeg.begin(), jpeg.begin() + jpeg.size() / 2));
  expect_file_error_naming(dir.file("truncated.jpg"),
                           [&] { read_grey_image(dir.file("truncated.jpg")); });
  test::write_file(dir.file("header_only.jpg"),
                   std::vector<std::uint8_t>(jpeg.begin(), jpeg.begin() + 20));
  expect_file_error_naming(dir.file("header_only.jpg"),
                           [&] { read_grey_image(dir.file("header_only.jpg")); });

  const std::vector<std::uint8_t> png =
      test::read_file(test::shared_data("opencv-doc-samples/box.png"));
  test::write_file(dir.file("truncated.png"),
                   std::vector<std::uint8_t>(png.begin(), png.begin() + png.size() / 2));
  expect_file_error_naming(dir.file("truncated.png"),
                           [&] { read_grey_image(dir.file("truncated.png")); });

  write_text(dir.file("zero.pgm"), "P5\n0 0\n255\n");
  expect_file_error_naming(dir.file("zero.pgm"), [&] { read_grey_image(dir.file("zero.pgm")); });
  write_text(dir.file("garbage.png"), "this is not an image at all");
  expect_file_error_naming(dir.file("garbage.png"),
                           [&] { read_grey_image(dir.file("garbage.png")); });
  expect_file_error_naming(dir.file("missing.png"),
                           [&] { read_grey_image(dir.file("missing.png")); });
  expect_file_error_naming(dir.path(), [&] { read_grey_image(dir.path()); });
}

TEST(ImageHeader, DeclaredDimensionsMatchDecodedImages) {
  for (const char* name :
       {"opencv-doc-samples/graf1.png", "opencv-doc-samples/box.png",
        "opencv-doc-samples/leuvenA.jpg", "opencv-doc-samples/Blender_Suzanne1.jpg",
        "opencv-doc-samples/left01.jpg", "rtabmap-samples/samples/1.jpg"}) {
    SCOPED_TRACE(name);
    const std::string path = test::shared_data(name);
    const auto declared = declared_dimensions(test::read_file(path));
    ASSERT_TRUE(declared.has_value());
    const cv::Mat image = read_grey_image(path);
    EXPECT_EQ(declared->width, static_cast<std::uint64_t>(image.cols));
    EXPECT_EQ(declared->height, static_cast<std::uint64_t>(image.rows));
  }
  EXPECT_FALSE(declared_dimensions({0xFF, 0xD8, 0xFF}).has_value());
  EXPECT_FALSE(declared_dimensions({'B', 'M', 0, 0}).has_value());
}

// A small file whose header declares a huge image is refused before decoding.
TEST(ReadGreyImage, RefusesHeadersDeclaringMorePixelsThanTheFileCanHold) {
  TempDir dir;
  std::vector<std::uint8_t> png = test::read_file(test::shared_data("opencv-doc-samples/box.png"));
  ASSERT_GT(png.size(), 24u);
  for (int i : {16, 20}) {  // IHDR width and height: 40000
    png[i] = 0;
    png[i + 1] = 0;
    png[i + 2] = 0x9C;
    png[i + 3] = 0x40;
  }
  test::write_file(dir.file("bomb.png"), png);
  try {
    read_grey_image(dir.file("bomb.png"));
    ADD_FAILURE() << "decoded a 40000x40000 PNG header";
  } catch (const FileError& e) {
    EXPECT_NE(std::string(e.what()).find("declares 40000x40000"), std::string::npos) << e.what();
  }

  std::vector<std::uint8_t> jpeg =
      test::read_file(test::shared_data("rtabmap-samples/samples/1.jpg"));
  const auto declared = declared_dimensions(jpeg);
  ASSERT_TRUE(declared.has_value());
  // Find the SOF0 marker and set height and width to 65000.
  bool patched = false;
  for (std::size_t i = 2; i + 9 < jpeg.size() && !patched; ++i) {
    if (jpeg[i] == 0xFF && jpeg[i + 1] == 0xC0) {
      for (std::size_t at : {i + 5, i + 7}) {
        jpeg[at] = 0xFD;
        jpeg[at + 1] = 0xE8;
      }
      patched = true;
    }
  }
  ASSERT_TRUE(patched);
  test::write_file(dir.file("bomb.jpg"), jpeg);
  try {
    read_grey_image(dir.file("bomb.jpg"));
    ADD_FAILURE() << "decoded a 65000x65000 JPEG header";
  } catch (const FileError& e) {
    EXPECT_NE(std::string(e.what()).find("declares 65000x65000"), std::string::npos) << e.what();
  }
}

// Every format OpenCV reads by content: the header reader sees the size the
// decoder produces, and the pixel limit refuses the image before decoding.
TEST(ReadGreyImage, PixelLimitAppliesToEveryFormatFromItsHeader) {
  TempDir dir;
  const cv::Mat colour = colour_image(2, 96, 64);
  cv::Mat grey, real;
  cv::cvtColor(colour, grey, cv::COLOR_BGR2GRAY);
  colour.convertTo(real, CV_32FC3, 1.0 / 255);
  struct Case {
    const char* name;
    const cv::Mat* image;
  };
  for (const Case& c : {Case{"a.png", &colour}, Case{"a.jpg", &colour}, Case{"a.tif", &colour},
                        Case{"a.bmp", &colour}, Case{"a.webp", &colour}, Case{"a.pgm", &grey},
                        Case{"a.ppm", &colour}, Case{"a.pam", &colour}, Case{"a.pfm", &real},
                        Case{"a.sr", &colour}, Case{"a.hdr", &real}, Case{"a.jp2", &colour}}) {
    SCOPED_TRACE(c.name);
    const std::string path = dir.file(c.name);
    ASSERT_TRUE(cv::imwrite(path, *c.image));
    const auto declared = declared_dimensions(test::read_file(path));
    ASSERT_TRUE(declared.has_value());
    EXPECT_EQ(declared->width, 96u);
    EXPECT_EQ(declared->height, 64u);
    EXPECT_EQ(read_grey_image(path, 96 * 64).size(), cv::Size(96, 64));
    try {
      read_grey_image(path, 96 * 64 - 1);
      ADD_FAILURE() << "no pixel limit";
    } catch (const FileError& e) {
      EXPECT_NE(std::string(e.what()).find("declares 96x64 pixels, more than the limit of 6143"),
                std::string::npos)
          << e.what();
    }
  }
}

void expect_image_error_mentioning(const std::string& path, const std::string& needle) {
  try {
    read_grey_image(path);
    ADD_FAILURE() << "decoded " << path;
  } catch (const FileError& e) {
    EXPECT_NE(std::string(e.what()).find(needle), std::string::npos) << e.what();
  }
}

// Decompression bombs, crafted: small files declaring 32768x32767 (PNG) and
// 30000x30000 (TIFF) pixels are refused by the default limit in no time.
TEST(ReadGreyImage, DefaultPixelLimitRefusesSmallFilesDeclaringHugeImages) {
  TempDir dir;
  std::vector<std::uint8_t> png = test::read_file(test::shared_data("opencv-doc-samples/box.png"));
  ASSERT_GT(png.size(), 24u);
  // IHDR width 32768, height 32767; the file is padded to 1 MB so that the
  // compression-ratio check alone would let it through.
  const std::uint8_t size[8] = {0, 0, 0x80, 0x00, 0, 0, 0x7F, 0xFF};
  std::copy(size, size + 8, png.begin() + 16);
  png.resize(1'000'000, 0);
  ASSERT_LE(32768ull * 32767ull, max_pixels_for_file_size(png.size()));
  test::write_file(dir.file("bomb.png"), png);
  expect_file_error_naming(dir.file("bomb.png"), [&] { read_grey_image(dir.file("bomb.png")); });

  // Little-endian TIFF, one directory: ImageWidth and ImageLength 30000 (LONG).
  std::vector<std::uint8_t> tiff = {
      'I', 'I', 42, 0, 8, 0, 0, 0,                    // header, directory at 8
      2,   0,                                         // two entries
      0,   1,   4,  0, 1, 0, 0, 0, 0x30, 0x75, 0, 0,  // 256 ImageWidth LONG 30000
      1,   1,   4,  0, 1, 0, 0, 0, 0x30, 0x75, 0, 0,  // 257 ImageLength LONG 30000
  };
  tiff.resize(tiff.size() + 4 + 1000, 0);
  test::write_file(dir.file("bomb.tif"), tiff);
  expect_image_error_mentioning(dir.file("bomb.tif"),
                                "declares 30000x30000 pixels, more than the limit of " +
                                    std::to_string(kDefaultMaxImagePixels));

  // Found by fuzzing: a TIFF of 12090x6 pixels whose strips declare 65530
  // rows each; OpenCV sizes its strip buffer from that, 3 GB.
  std::vector<std::uint8_t> strips = {
      'I', 'I', 42, 0, 8, 0, 0, 0,                    // header, directory at 8
      3,   0,                                         // three entries
      0,   1,   3,  0, 1, 0, 0, 0, 0x3a, 0x2f, 0, 0,  // 256 ImageWidth SHORT 12090
      1,   1,   3,  0, 1, 0, 0, 0, 6,    0,    0, 0,  // 257 ImageLength SHORT 6
      22,  1,   3,  0, 1, 0, 0, 0, 0xfa, 0xff, 0, 0,  // 278 RowsPerStrip SHORT 65530
  };
  strips.resize(strips.size() + 4 + 100, 0);
  test::write_file(dir.file("strips.tif"), strips);
  expect_image_error_mentioning(dir.file("strips.tif"),
                                "strip or tile declares 12090x65530 pixels");
  // Found by fuzzing: the same with a second ImageWidth of 1 after the first.
  strips[8] = 4;
  const std::uint8_t second_width[12] = {0, 1, 3, 0, 1, 0, 0, 0, 1, 0, 0, 0};
  strips.insert(strips.begin() + 10 + 3 * 12, std::begin(second_width), std::end(second_width));
  test::write_file(dir.file("widths.tif"), strips);
  expect_image_error_mentioning(dir.file("widths.tif"),
                                "strip or tile declares 12090x65530 pixels");

  // The limit applies through ImageSource too.
  ASSERT_TRUE(cv::imwrite(dir.file("small.png"), colour_image(1, 40, 30)));
  ImageSourceOptions options;
  options.max_pixels = 1000;
  ImageSource source({dir.file("small.png")}, options);
  Frame frame;
  expect_file_error_naming(dir.file("small.png"), [&] { source.next(frame); });
}

TEST(ReadGreyImage, FormatsWhoseSizeCannotBeReadAreRefused) {
  TempDir dir;
  std::vector<std::uint8_t> dicom(132, 0);
  std::copy_n("DICM", 4, dicom.begin() + 128);
  test::write_file(dir.file("scan.dcm"), dicom);
  expect_file_error_naming(dir.file("scan.dcm"), [&] { read_grey_image(dir.file("scan.dcm")); });
}

// libjpeg warns "Premature end of JPEG file" and OpenCV returns the image with
// its lower half grey: a JPEG cut short is an error even when an end-of-image
// marker is appended to hide the cut.
TEST(ReadGreyImage, JpegCutShortWithAnEndMarkerIsAnError) {
  TempDir dir;
  std::vector<std::uint8_t> jpeg =
      test::read_file(test::shared_data("rtabmap-samples/samples/1.jpg"));
  ASSERT_GT(jpeg.size(), 1000u);
  jpeg.resize(jpeg.size() / 2);
  jpeg.push_back(0xFF);
  jpeg.push_back(0xD9);
  test::write_file(dir.file("cut.jpg"), jpeg);
  try {
    read_grey_image(dir.file("cut.jpg"));
    ADD_FAILURE() << "decoded a JPEG cut in half";
  } catch (const FileError& e) {
    EXPECT_EQ(e.path(), dir.file("cut.jpg"));
    EXPECT_NE(std::string(e.what()).find("damaged JPEG"), std::string::npos) << e.what();
  }
}

// A FIFO would block the reader forever: refused from its type, wherever it
// appears (the test would hang without the check).
TEST(ImageSource, FifosAreRefusedWithoutBlocking) {
  TempDir dir;
  ASSERT_EQ(mkfifo(dir.file("pipe.png").c_str(), 0600), 0);
  ASSERT_EQ(mkfifo(dir.file("pipe.avi").c_str(), 0600), 0);
  for (const char* name : {"pipe.png", "pipe.avi"}) {
    try {
      ImageSource source({dir.file(name)});
      ADD_FAILURE() << "accepted a FIFO";
    } catch (const FileError& e) {
      EXPECT_EQ(e.path(), dir.file(name));
      EXPECT_NE(std::string(e.what()).find("is a FIFO"), std::string::npos) << e.what();
    }
  }
  write_text(dir.file("list.txt"), "pipe.png\n");
  expect_file_error_naming(dir.file("list.txt"),
                           [&] { ImageSource source({dir.file("list.txt")}); });
  try {
    read_grey_image(dir.file("pipe.png"));
    ADD_FAILURE() << "read a FIFO";
  } catch (const FileError& e) {
    EXPECT_NE(std::string(e.what()).find("is a FIFO"), std::string::npos) << e.what();
  }
}

TEST(ImageSource, DirectoryInNaturalOrderSkippingOtherFiles) {
  TempDir dir;
  for (const char* name : {"10.png", "2.png", "1.png", ".hidden.png"}) {
    ASSERT_TRUE(cv::imwrite(dir.file(name), colour_image(1)));
  }
  write_text(dir.file("notes.md"), "not an image");
  std::filesystem::create_directory(dir.file("sub.png"));
  ImageSource source({dir.path()});
  EXPECT_EQ(source.size(), 3);
  const std::vector<std::string> names = read_all_names(source);
  ASSERT_EQ(names.size(), 3u);
  EXPECT_EQ(filename(names[0]), "1.png");
  EXPECT_EQ(filename(names[1]), "2.png");
  EXPECT_EQ(filename(names[2]), "10.png");
}

TEST(ImageSource, StrideAndMaxWidth) {
  TempDir dir;
  for (int i = 1; i <= 5; ++i) {
    ASSERT_TRUE(cv::imwrite(dir.file(std::to_string(i) + ".png"), colour_image(i, 640, 480)));
  }
  ImageSourceOptions options;
  options.stride = 2;
  options.max_width = 320;
  ImageSource source({dir.path()}, options);
  EXPECT_EQ(source.size(), 3);
  Frame frame;
  std::vector<std::string> names;
  while (source.next(frame)) {
    EXPECT_EQ(frame.image.size(), cv::Size(320, 240));
    names.push_back(filename(frame.name));
  }
  EXPECT_EQ(names, (std::vector<std::string>{"1.png", "3.png", "5.png"}));
}

TEST(ImageSource, TextListWithRelativePathsAndComments) {
  TempDir dir;
  std::filesystem::create_directory(dir.file("images"));
  ASSERT_TRUE(cv::imwrite(dir.file("images/a.png"), colour_image(1)));
  ASSERT_TRUE(cv::imwrite(dir.file("images/b.jpg"), colour_image(2)));
  write_text(dir.file("list.txt"),
             "# frames\nimages/b.jpg\r\n\n  images/a.png  \n" + dir.file("images/b.jpg") + "\n");
  ImageSource source({dir.file("list.txt")});
  EXPECT_EQ(source.size(), 3);
  const std::vector<std::string> names = read_all_names(source);
  ASSERT_EQ(names.size(), 3u);
  EXPECT_EQ(filename(names[0]), "b.jpg");
  EXPECT_EQ(filename(names[1]), "a.png");
  EXPECT_EQ(filename(names[2]), "b.jpg");
}

TEST(ImageSource, SeveralInputsInOrder) {
  TempDir dir;
  ASSERT_TRUE(cv::imwrite(dir.file("x.png"), colour_image(1)));
  ASSERT_TRUE(cv::imwrite(dir.file("y.png"), colour_image(2)));
  ImageSource source({dir.file("y.png"), dir.file("x.png"), dir.file("y.png")});
  const std::vector<std::string> names = read_all_names(source);
  ASSERT_EQ(names.size(), 3u);
  EXPECT_EQ(filename(names[0]), "y.png");
  EXPECT_EQ(filename(names[1]), "x.png");
}

// The bounds the CLI's flags and Python's detect_loops share.
TEST(ImageSource, OptionsOutOfRangeAreInvalidArguments) {
  const std::string image = test::shared_data("opencv-doc-samples/box.png");
  const auto with = [&](auto change) {
    ImageSourceOptions options;
    change(options);
    return [&image, options] { ImageSource source({image}, options); };
  };
  EXPECT_NO_THROW(with([](ImageSourceOptions& o) {
    o.stride = kMaxStride, o.max_width = kMaxFrameWidth, o.video_fps = kMaxVideoFps;
  })());
  EXPECT_THROW(with([](ImageSourceOptions& o) { o.stride = kMaxStride + 1; })(), InvalidArgument);
  EXPECT_THROW(with([](ImageSourceOptions& o) { o.max_width = -1; })(), InvalidArgument);
  EXPECT_THROW(with([](ImageSourceOptions& o) { o.max_width = kMaxFrameWidth + 1; })(),
               InvalidArgument);
  EXPECT_THROW(with([](ImageSourceOptions& o) { o.video_fps = -0.5; })(), InvalidArgument);
  EXPECT_THROW(with([](ImageSourceOptions& o) { o.video_fps = kMaxVideoFps * 2; })(),
               InvalidArgument);
}

TEST(ImageSource, BadInputsGiveFileErrorNamingThem) {
  TempDir dir;
  EXPECT_THROW(ImageSource({}), InvalidArgument);
  expect_file_error_naming(dir.file("nothing"), [&] { ImageSource source({dir.file("nothing")}); });
  std::filesystem::create_directory(dir.file("empty_dir"));
  expect_file_error_naming(dir.file("empty_dir"),
                           [&] { ImageSource source({dir.file("empty_dir")}); });
  write_text(dir.file("list.txt"), "missing.png\n");
  expect_file_error_naming(dir.file("list.txt"),
                           [&] { ImageSource source({dir.file("list.txt")}); });
  write_text(dir.file("nested.txt"), "list.txt\n");
  expect_file_error_naming(dir.file("nested.txt"),
                           [&] { ImageSource source({dir.file("nested.txt")}); });
}

TEST(ImageSource, UndecodableImageReportsItAndContinues) {
  TempDir dir;
  ASSERT_TRUE(cv::imwrite(dir.file("1.png"), colour_image(1)));
  write_text(dir.file("2.png"), "");
  ASSERT_TRUE(cv::imwrite(dir.file("3.png"), colour_image(3)));
  ImageSource source({dir.path()});
  Frame frame;
  ASSERT_TRUE(source.next(frame));
  expect_file_error_naming(dir.file("2.png"), [&] { source.next(frame); });
  ASSERT_TRUE(source.next(frame));
  EXPECT_EQ(filename(frame.name), "3.png");
  EXPECT_FALSE(source.next(frame));
}

// Writes `count` frames of 64x48 whose mean brightness is 20 * k + 10.
std::string write_video(const TempDir& dir, int count, double fps) {
  const std::string path = dir.file("clip.avi");
  cv::VideoWriter writer(path, cv::VideoWriter::fourcc('M', 'J', 'P', 'G'), fps, cv::Size(64, 48),
                         true);
  EXPECT_TRUE(writer.isOpened()) << "OpenCV cannot write MJPG .avi";
  for (int k = 0; k < count; ++k) {
    writer.write(cv::Mat(48, 64, CV_8UC3, cv::Scalar::all(20 * k + 10)));
  }
  writer.release();
  return path;
}

TEST(ImageSource, VideoFramesWithStride) {
  TempDir dir;
  const std::string video = write_video(dir, 10, 10);
  {
    ImageSource source({video});
    EXPECT_EQ(source.size(), -1);
    Frame frame;
    int count = 0;
    while (source.next(frame)) {
      EXPECT_EQ(frame.image.type(), CV_8UC1);
      EXPECT_EQ(frame.image.size(), cv::Size(64, 48));
      EXPECT_EQ(frame.name, video + "#" + std::to_string(count));
      EXPECT_NEAR(cv::mean(frame.image)[0], 20 * count + 10, 4.0);
      ++count;
    }
    EXPECT_EQ(count, 10);
  }
  {
    ImageSourceOptions options;
    options.stride = 3;
    options.max_width = 32;
    ImageSource source({video}, options);
    std::vector<std::string> names;
    Frame frame;
    while (source.next(frame)) {
      EXPECT_EQ(frame.image.size(), cv::Size(32, 24));
      names.push_back(frame.name);
    }
    EXPECT_EQ(names,
              (std::vector<std::string>{video + "#0", video + "#3", video + "#6", video + "#9"}));
  }
  {
    ImageSourceOptions options;
    options.video_fps = 5;  // half of the video's 10 fps
    ImageSource source({video}, options);
    std::vector<std::string> names;
    Frame frame;
    while (source.next(frame)) names.push_back(frame.name);
    EXPECT_EQ(names, (std::vector<std::string>{video + "#0", video + "#2", video + "#4",
                                               video + "#6", video + "#8"}));
  }
}

TEST(ImageSource, VideoAmongImagesFromAList) {
  TempDir dir;
  const std::string video = write_video(dir, 3, 10);
  ASSERT_TRUE(cv::imwrite(dir.file("still.png"), colour_image(1)));
  write_text(dir.file("all.txt"), "still.png\nclip.avi\nstill.png\n");
  ImageSource source({dir.file("all.txt")});
  const std::vector<std::string> names = read_all_names(source);
  ASSERT_EQ(names.size(), 5u);
  EXPECT_EQ(filename(names[0]), "still.png");
  EXPECT_EQ(filename(names[1]), "clip.avi#0");
  EXPECT_EQ(filename(names[3]), "clip.avi#2");
  EXPECT_EQ(filename(names[4]), "still.png");
}

// A damaged video ends early without an error from OpenCV: the frames its
// container declared but the backend could not decode are counted.
TEST(ImageSource, FramesOfADamagedVideoAreCountedAsUnreadable) {
  TempDir dir;
  const std::string video = write_video(dir, 30, 10);
  {
    ImageSource source({video});
    EXPECT_EQ(read_all_names(source).size(), 30u);
    EXPECT_EQ(source.unreadable_frames(), 0u);
  }
  std::vector<std::uint8_t> bytes = test::read_file(video);
  bytes.resize(bytes.size() / 2);
  test::write_file(dir.file("cut.avi"), bytes);
  ImageSource source({dir.file("cut.avi")});
  const std::size_t read = read_all_names(source).size();
  EXPECT_GT(read, 0u);
  EXPECT_LT(read, 30u);
  EXPECT_EQ(source.unreadable_frames(), 30u - read);
}

TEST(ImageSource, VideoFramesAboveThePixelLimitAreRefused) {
  TempDir dir;
  const std::string video = write_video(dir, 3, 10);
  ImageSourceOptions options;
  options.max_pixels = 64 * 48 - 1;
  ImageSource source({video}, options);
  Frame frame;
  expect_file_error_naming(video, [&] { source.next(frame); });
}

TEST(ImageSource, FrameRateIsTheVideosAfterSamplingAndStride) {
  TempDir dir;
  const std::string video = write_video(dir, 4, 10);
  const auto rate = [&](std::size_t stride, double video_fps, std::vector<std::string> inputs) {
    ImageSourceOptions options;
    options.stride = stride;
    options.video_fps = video_fps;
    return ImageSource(inputs, options).frame_rate();
  };
  EXPECT_DOUBLE_EQ(rate(1, 0, {video}), 10);
  EXPECT_DOUBLE_EQ(rate(1, 4, {video}), 4);
  EXPECT_DOUBLE_EQ(rate(1, 20, {video}), 10);  // video_fps above the video's rate: every frame
  EXPECT_DOUBLE_EQ(rate(2, 0, {video}), 5);
  EXPECT_DOUBLE_EQ(rate(3, 4, {video}), 4.0 / 3);
  EXPECT_DOUBLE_EQ(rate(1, 0, {video, video}), 10);
  // Still images have no rate, so a sequence with one has none.
  ASSERT_TRUE(cv::imwrite(dir.file("still.png"), colour_image(1)));
  EXPECT_EQ(rate(1, 0, {dir.file("still.png")}), 0);
  EXPECT_EQ(rate(1, 0, {video, dir.file("still.png")}), 0);

  write_text(dir.file("broken.avi"), "RIFF nonsense");
  expect_file_error_naming(dir.file("broken.avi"),
                           [&] { ImageSource({dir.file("broken.avi")}).frame_rate(); });
}

TEST(ImageSource, FrameScaleUndoesMaxWidth) {
  TempDir dir;
  ASSERT_TRUE(cv::imwrite(dir.file("wide.png"), colour_image(1, 80, 30)));
  ImageSourceOptions options;
  options.max_width = 20;
  ImageSource source({dir.file("wide.png"), write_video(dir, 1, 10)}, options);
  Frame frame;
  ASSERT_TRUE(source.next(frame));
  EXPECT_DOUBLE_EQ(frame.scale, 0.25);
  ASSERT_TRUE(source.next(frame));
  EXPECT_DOUBLE_EQ(frame.scale, 20.0 / 64);
  ImageSource full({dir.file("wide.png")});
  ASSERT_TRUE(full.next(frame));
  EXPECT_EQ(frame.scale, 1);
}

// Every frame name ImageSource gives reads back as that frame, at the size
// of the file, in grey or colour.
TEST(ReadFrame, ReadsEveryFrameByItsName) {
  TempDir dir;
  const std::string video = write_video(dir, 12, 10);
  ASSERT_TRUE(cv::imwrite(dir.file("take#2.png"), colour_image(2)));
  ImageSourceOptions options;
  options.max_width = 32;
  options.stride = 2;
  ImageSource source({video, dir.file("take#2.png")}, options);
  std::vector<std::string> names;
  Frame frame;
  while (source.next(frame)) names.push_back(frame.name);
  ASSERT_EQ(names.size(), 7u);
  // Backwards, so that every video frame is a seek away from the start.
  for (std::size_t i = names.size() - 1; i-- > 0;) {
    const cv::Mat grey = read_frame(names[i]);
    EXPECT_EQ(grey.type(), CV_8UC1) << names[i];
    EXPECT_EQ(grey.size(), cv::Size(64, 48)) << names[i];
    EXPECT_NEAR(cv::mean(grey)[0], 20.0 * (2 * i) + 10, 4.0) << names[i];
    const cv::Mat colour = read_frame(names[i], FramePixels::kBgr);
    EXPECT_EQ(colour.type(), CV_8UC3) << names[i];
    EXPECT_EQ(colour.size(), cv::Size(64, 48)) << names[i];
  }
  // A file whose name ends in "#2" is that file, not a frame of "take".
  EXPECT_EQ(names.back(), dir.file("take#2.png"));
  const cv::Mat still = read_frame(names.back(), FramePixels::kBgr);
  ASSERT_EQ(still.type(), CV_8UC3);
  EXPECT_EQ(cv::norm(still, colour_image(2), cv::NORM_INF), 0);
  EXPECT_EQ(read_frame(names.back()).type(), CV_8UC1);
}

TEST(ReadFrame, MissingFramesAndFilesAreFileErrors) {
  TempDir dir;
  const std::string video = write_video(dir, 3, 10);
  expect_file_error_naming(video, [&] { read_frame(video + "#3"); });
  expect_file_error_naming(video, [&] { read_frame(video + "#999999999999999999"); });
  expect_file_error_naming(dir.file("gone.avi#1"), [&] { read_frame(dir.file("gone.avi#1")); });
  expect_file_error_naming(video + "#x", [&] { read_frame(video + "#x"); });
  expect_file_error_naming(video + "#", [&] { read_frame(video + "#"); });
  write_text(dir.file("broken.avi"), "RIFF nonsense");
  expect_file_error_naming(dir.file("broken.avi"), [&] { read_frame(dir.file("broken.avi#0")); });
}

TEST(ImageSource, UnreadableVideoGivesFileError) {
  TempDir dir;
  write_text(dir.file("broken.avi"), "RIFF nonsense");
  ImageSource source({dir.file("broken.avi")});
  Frame frame;
  expect_file_error_naming(dir.file("broken.avi"), [&] { source.next(frame); });
}

// Bytes flipped inside the entropy-coded scan of a real frame: libjpeg
// decodes most such files without a warning (Huffman codes resynchronise)
// into a frame with shifted or garbage blocks. Those whose damage shows in
// libjpeg's warnings or in coefficients no 8-bit image has are refused,
// naming the file; JPEG has no checksum, so the others cannot be told apart.
TEST(ReadGreyImage, JpegWithDamagedScanDataIsAnError) {
  TempDir dir;
  const std::vector<std::uint8_t> jpeg =
      test::read_file(test::shared_data("rtabmap-samples/samples/1.jpg"));
  std::size_t sos = 0;
  while (sos + 3 < jpeg.size() && !(jpeg[sos] == 0xFF && jpeg[sos + 1] == 0xDA)) ++sos;
  ASSERT_LT(sos + 3, jpeg.size()) << "no start of scan";
  const std::size_t scan = sos + 2 + (std::size_t{jpeg[sos + 2]} << 8 | jpeg[sos + 3]);
  const std::size_t end = jpeg.size() - 2;  // the end-of-image marker
  ASSERT_GT(end, scan + 1000);
  constexpr std::size_t kDamaged = 40;
  std::size_t refused = 0;
  for (std::size_t k = 0; k < kDamaged; ++k) {
    std::vector<std::uint8_t> damaged = jpeg;
    const std::size_t at = scan + (end - scan) * (k + 1) / (kDamaged + 1);
    damaged[at] ^= 0xFF;
    damaged[at + 1] ^= 0x55;
    const std::string path = dir.file("damaged" + std::to_string(k) + ".jpg");
    test::write_file(path, damaged);
    try {
      read_grey_image(path);
    } catch (const FileError& e) {
      EXPECT_EQ(e.path(), path);
      EXPECT_NE(std::string(e.what()).find("damaged JPEG: Corrupt JPEG data"), std::string::npos)
          << e.what();
      ++refused;
    }
  }
  // libjpeg's warnings alone catch 19 of them.
  EXPECT_GE(refused, 27u);
  // The second one decodes with a warning-free stream but a DC term of 1116.
  EXPECT_THROW(read_grey_image(dir.file("damaged1.jpg")), FileError);
}

}  // namespace
}  // namespace binbow::vision

namespace binbow::vision {
namespace {

// A solid grey PNG: a few hundred KB however large (a decompression bomb's shape).
void write_solid_png(const std::string& path, int width, int height) {
  ASSERT_TRUE(cv::imwrite(path, cv::Mat(height, width, CV_8UC1, cv::Scalar(128))));
}

// The FileError `source.next` throws, which must name `path`.
std::string refusal_of(ImageSource& source, const std::string& path) {
  Frame frame;
  try {
    source.next(frame);
  } catch (const FileError& e) {
    EXPECT_EQ(e.path(), path);
    return e.what();
  }
  ADD_FAILURE() << "no FileError for " << path;
  return {};
}

TEST(ImageSource, ImagesAboveTheExtractorsMemoryBudgetAreRefusedBeforeDecoding) {
  TempDir dir;
  const auto akaze = make_extractor("akaze");
  const ImageSourceOptions options = limit_for_extractor({}, *akaze);
  ASSERT_EQ(options.max_extracted_pixels, akaze->max_pixels());
  const std::string limit = std::to_string(akaze->max_pixels());
  // 100 MP (the decoder's limit) and 25 MP: AKAZE would need 12 and 3 GB.
  for (const auto& [side, size] :
       {std::pair<int, std::string>{10000, "10000x10000"}, {5000, "5000x5000"}}) {
    const std::string path = dir.file(size + ".png");
    write_solid_png(path, side, side);
    ImageSource source({path}, options);
    const std::string message = refusal_of(source, path);
    for (const std::string& part : {"image of " + size + " pixels is more than " + limit +
                                        " pixels, the most akaze extracts within 2 GiB",
                                    std::string("--max-width"), std::string("--max-pixels")})
      EXPECT_NE(message.find(part), std::string::npos) << message;
  }
  // Downscaled below the limit, it is read.
  ImageSourceOptions narrow = options;
  narrow.max_width = 1000;
  ImageSource downscaled({dir.file("5000x5000.png")}, narrow);
  Frame frame;
  ASSERT_TRUE(downscaled.next(frame));
  EXPECT_EQ(frame.image.size(), cv::Size(1000, 1000));
  // A limit set beforehand is kept: the caller accepts the memory.
  ImageSourceOptions raised;
  raised.max_extracted_pixels = 30'000'000;
  ASSERT_EQ(limit_for_extractor(raised, *akaze).max_extracted_pixels, 30'000'000u);
  ImageSource accepted({dir.file("5000x5000.png")}, limit_for_extractor(raised, *akaze));
  ASSERT_TRUE(accepted.next(frame));
  EXPECT_EQ(frame.image.size(), cv::Size(5000, 5000));
  // The extractors whose memory per pixel is small are bound by max_pixels alone.
  for (const char* name : {"orb", "brief", "brisk"}) {
    ImageSource source({dir.file("5000x5000.png")}, limit_for_extractor({}, *make_extractor(name)));
    EXPECT_TRUE(source.next(frame)) << name;
  }
  // An extractor built elsewhere has no known cost, so no limit of its own.
  const auto unknown = make_opencv_extractor(cv::AKAZE::create(), "custom");
  EXPECT_EQ(limit_for_extractor({}, *unknown).max_extracted_pixels, 0u);
}

TEST(ImageSource, VideoFramesAboveTheExtractionLimitAreRefusedWhenOpened) {
  TempDir dir;
  const std::string path = dir.file("clip.avi");
  cv::VideoWriter writer(path, cv::VideoWriter::fourcc('M', 'J', 'P', 'G'), 5, cv::Size(64, 48),
                         true);
  ASSERT_TRUE(writer.isOpened());
  for (int k = 0; k < 3; ++k) writer.write(cv::Mat(48, 64, CV_8UC3, cv::Scalar::all(50 * k)));
  writer.release();
  ImageSourceOptions options;
  options.max_extracted_pixels = 64 * 48 - 1;
  ImageSource source({path}, options);
  EXPECT_NE(refusal_of(source, path).find("video frame of 64x48 pixels is more than 3071 pixels"),
            std::string::npos);
  options.max_width = 32;  // 32x24 after downscaling
  ImageSource downscaled({path}, options);
  EXPECT_EQ(read_all_names(downscaled).size(), 3u);
}

TEST(ImageSource, SkipUnreadableDeliversTheFrameEmptyAtItsIndex) {
  TempDir dir;
  ASSERT_TRUE(cv::imwrite(dir.file("1.png"), colour_image(1)));
  ASSERT_TRUE(cv::imwrite(dir.file("2.jpg"), colour_image(2)));
  std::vector<std::uint8_t> jpeg = test::read_file(dir.file("2.jpg"));
  jpeg.resize(jpeg.size() / 2);
  test::write_file(dir.file("2.jpg"), jpeg);
  ASSERT_TRUE(cv::imwrite(dir.file("3.png"), colour_image(3)));
  ImageSourceOptions options;
  options.skip_unreadable = true;
  ImageSource source({dir.path()}, options);
  Frame frame;
  ASSERT_TRUE(source.next(frame));
  EXPECT_TRUE(frame.unreadable.empty());
  ASSERT_TRUE(source.next(frame));
  EXPECT_EQ(frame.name, dir.file("2.jpg"));
  EXPECT_EQ(frame.index, 1u);
  EXPECT_TRUE(frame.image.empty());
  EXPECT_EQ(frame.unreadable.rfind("damaged JPEG", 0), 0u) << frame.unreadable;
  ASSERT_TRUE(source.next(frame));
  EXPECT_EQ(filename(frame.name), "3.png");
  EXPECT_EQ(frame.index, 2u);
  EXPECT_TRUE(frame.unreadable.empty());
  EXPECT_FALSE(source.next(frame));

  // Strict, the error names the file and the frames after it keep their index.
  ImageSource strict({dir.path()});
  ASSERT_TRUE(strict.next(frame));
  expect_file_error_naming(dir.file("2.jpg"), [&] { strict.next(frame); });
  ASSERT_TRUE(strict.next(frame));
  EXPECT_EQ(frame.index, 2u);
}

}  // namespace
}  // namespace binbow::vision
