// DVision::BRIEF of the VINS spellings (ThirdParty/DVision/BRIEF.h): the
// same descriptors as DLib's for the same image, keypoints and pairs
// (dvision_brief_golden.txt, made by DLib itself from brief_test_input.h).
#include <gtest/gtest.h>

#include <cstdlib>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include "ThirdParty/DVision/DVision.h"
#include "compat_vins/brief_test_input.h"
#include "support/test_support.h"

namespace {

struct GoldenDescriptor {
  int treat_image;
  std::size_t keypoint;
  std::string hex;
};

std::vector<GoldenDescriptor> read_golden() {
  const std::string path = binbow::test::source_path("tests/compat_vins/dvision_brief_golden.txt");
  std::ifstream file(path.c_str());
  if (!file) throw std::runtime_error(path + ": cannot open the golden file");
  std::vector<GoldenDescriptor> golden;
  std::string line;
  while (std::getline(file, line)) {
    if (line.empty() || line[0] == '#') continue;
    std::istringstream in(line);
    std::string key;
    GoldenDescriptor d;
    if (!(in >> key >> d.treat_image >> d.keypoint >> d.hex) || key != "brief" ||
        d.hex.size() != 64)
      throw std::runtime_error(path + ": bad line " + line);
    golden.push_back(d);
  }
  return golden;
}

std::string hex_of(const DVision::BRIEF::bitset& bits) {
  std::string hex;
  static const char digits[] = "0123456789abcdef";
  for (std::size_t byte = 0; byte < bits.size() / 8; ++byte) {
    unsigned value = 0;
    for (std::size_t b = 0; b < 8; ++b)
      if (bits[byte * 8 + b]) value |= 1u << b;
    hex += digits[value >> 4];
    hex += digits[value & 15];
  }
  return hex;
}

TEST(DvisionBrief, BitIdenticalToDlibWithImportedPairs) {
  const std::vector<GoldenDescriptor> golden = read_golden();
  const std::vector<cv::KeyPoint> keypoints = brief_test_input::keypoints();
  ASSERT_EQ(2 * keypoints.size(), golden.size());
  std::vector<int> x1, y1, x2, y2;
  brief_test_input::pairs(x1, y1, x2, y2);
  DVision::BRIEF brief;
  brief.importPairs(x1, y1, x2, y2);
  EXPECT_EQ(256, brief.getDescriptorLengthInBits());
  std::vector<int> ex1, ey1, ex2, ey2;
  brief.exportPairs(ex1, ey1, ex2, ey2);
  EXPECT_TRUE(ex1 == x1 && ey1 == y1 && ex2 == x2 && ey2 == y2);
  const cv::Mat image = brief_test_input::image();
  std::vector<DVision::BRIEF::bitset> treated, raw;
  brief.compute(image, keypoints, treated);  // smoothed first, as VINS calls it
  brief(image, keypoints, raw, false);       // the image as it is
  ASSERT_EQ(keypoints.size(), treated.size());
  ASSERT_EQ(keypoints.size(), raw.size());
  std::size_t set_bits = 0;
  for (const GoldenDescriptor& d : golden) {
    ASSERT_LT(d.keypoint, keypoints.size());
    const DVision::BRIEF::bitset& bits = d.treat_image ? treated[d.keypoint] : raw[d.keypoint];
    ASSERT_EQ(256u, bits.size());
    EXPECT_EQ(d.hex, hex_of(bits)) << "keypoint " << d.keypoint << " treat_image " << d.treat_image;
    set_bits += bits.count();
  }
  EXPECT_GT(set_bits, 2000u);  // the golden descriptors are not all zeros
  EXPECT_EQ(static_cast<int>((treated[5] ^ treated[6]).count()),
            DVision::BRIEF::distance(treated[5], treated[6]));
}

TEST(DvisionBrief, RandomPairsStayInThePatch) {
  const DVision::BRIEF close(128, 32);
  std::vector<int> x1, y1, x2, y2;
  close.exportPairs(x1, y1, x2, y2);
  ASSERT_EQ(128u, x1.size());
  for (std::size_t i = 0; i < x1.size(); ++i)
    for (int v : {x1[i], y1[i], x2[i], y2[i]}) EXPECT_LE(std::abs(v), 16);
  EXPECT_EQ(DVision::BRIEF::RANDOM_CLOSE, close.getType());
  EXPECT_EQ(32, close.getPatchSize());
  EXPECT_THROW(DVision::BRIEF(256, 1), std::invalid_argument);
}

}  // namespace
