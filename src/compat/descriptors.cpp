// DBoW2's descriptor classes FORB and FBrief.
#include <cstdint>
#include <sstream>
#include <stdexcept>

#include "binbow/compat/FBrief.h"
#include "binbow/compat/FORB.h"
#include "binbow/compat/detail/descriptor_bytes.h"
#include "binbow/descriptors.h"

namespace DBoW2 {

namespace {
const unsigned char* orb_bytes(const cv::Mat& d, std::size_t& size) {
  if (d.type() != CV_8U || d.rows != 1)
    throw std::invalid_argument("an ORB descriptor must be one row of CV_8U bytes, not " +
                                std::to_string(d.rows) + " rows of type " +
                                std::to_string(d.type()));
  size = static_cast<std::size_t>(d.cols);
  return d.ptr<unsigned char>(0);
}
}  // namespace

namespace binbow_detail {
void append_descriptor_bytes(const cv::Mat& d, std::size_t code_size,
                             std::vector<unsigned char>& out) {
  std::size_t size = 0;
  const unsigned char* bytes = orb_bytes(d, size);
  if (code_size != 0 && size != code_size)
    throw std::invalid_argument("a descriptor of " + std::to_string(size) +
                                " bytes does not fit a vocabulary of " + std::to_string(code_size) +
                                "-byte words");
  out.insert(out.end(), bytes, bytes + size);
}

void descriptor_from_bytes(const unsigned char* bytes, std::size_t code_size, cv::Mat& d) {
  d.create(1, static_cast<int>(code_size), CV_8U);
  std::copy(bytes, bytes + code_size, d.ptr<unsigned char>(0));
}
}  // namespace binbow_detail

void FORB::meanValue(const std::vector<pDescriptor>& descriptors, TDescriptor& mean) {
  if (descriptors.empty()) {
    mean.release();
    return;
  }
  if (descriptors.size() == 1) {
    mean = descriptors[0]->clone();
    return;
  }
  std::vector<std::size_t> ones(L * 8, 0);
  for (pDescriptor descriptor : descriptors) {
    std::size_t size = 0;
    const unsigned char* bytes = orb_bytes(*descriptor, size);
    for (std::size_t bit = 0; bit < ones.size() && bit / 8 < size; ++bit)
      if ((bytes[bit / 8] >> (7 - bit % 8)) & 1u) ++ones[bit];
  }
  mean = cv::Mat::zeros(1, L, CV_8U);
  unsigned char* out = mean.ptr<unsigned char>(0);
  const std::size_t half_rounded_up = (descriptors.size() + 1) / 2;
  for (std::size_t bit = 0; bit < ones.size(); ++bit)
    if (ones[bit] >= half_rounded_up)
      out[bit / 8] |= static_cast<unsigned char>(0x80u >> (bit % 8));
}

double FORB::distance(const TDescriptor& a, const TDescriptor& b) {
  std::size_t size_a = 0, size_b = 0;
  const unsigned char* pa = orb_bytes(a, size_a);
  const unsigned char* pb = orb_bytes(b, size_b);
  if (size_a != size_b)
    throw std::invalid_argument("FORB::distance of descriptors of " + std::to_string(size_a) +
                                " and " + std::to_string(size_b) + " bytes");
  return static_cast<double>(binbow::hamming_distance(pa, pb, size_a));
}

std::string FORB::toString(const TDescriptor& a) {
  std::size_t size = 0;
  const unsigned char* bytes = orb_bytes(a, size);
  std::ostringstream out;
  for (std::size_t i = 0; i < size; ++i) out << static_cast<int>(bytes[i]) << " ";
  return out.str();
}

void FORB::fromString(TDescriptor& a, const std::string& s) {
  a.create(1, L, CV_8U);
  unsigned char* bytes = a.ptr<unsigned char>(0);
  std::istringstream in(s);
  for (int i = 0; i < L; ++i) {
    int value = 0;
    if (in >> value) bytes[i] = static_cast<unsigned char>(value);
  }
}

void FORB::toMat32F(const std::vector<TDescriptor>& descriptors, cv::Mat& mat) {
  if (descriptors.empty()) {
    mat.release();
    return;
  }
  mat.create(static_cast<int>(descriptors.size()), L * 8, CV_32F);
  for (std::size_t i = 0; i < descriptors.size(); ++i) {
    std::size_t size = 0;
    const unsigned char* bytes = orb_bytes(descriptors[i], size);
    float* row = mat.ptr<float>(static_cast<int>(i));
    for (std::size_t bit = 0; bit < static_cast<std::size_t>(L) * 8; ++bit)
      row[bit] = bit / 8 < size && ((bytes[bit / 8] >> (7 - bit % 8)) & 1u) ? 1.f : 0.f;
  }
}

void FORB::toMat32F(const cv::Mat& descriptors, cv::Mat& mat) {
  descriptors.convertTo(mat, CV_32F);
}

void FORB::toMat8U(const std::vector<TDescriptor>& descriptors, cv::Mat& mat) {
  mat.create(static_cast<int>(descriptors.size()), L, CV_8U);
  for (std::size_t i = 0; i < descriptors.size(); ++i) {
    std::size_t size = 0;
    const unsigned char* bytes = orb_bytes(descriptors[i], size);
    if (size != static_cast<std::size_t>(L))
      throw std::invalid_argument("FORB::toMat8U needs descriptors of 32 bytes, not " +
                                  std::to_string(size));
    std::copy(bytes, bytes + size, mat.ptr<unsigned char>(static_cast<int>(i)));
  }
}

void FBrief::meanValue(const std::vector<pDescriptor>& descriptors, TDescriptor& mean) {
  mean.reset();
  std::vector<std::size_t> ones(L, 0);
  for (pDescriptor descriptor : descriptors)
    for (std::size_t bit = 0; bit < ones.size(); ++bit) ones[bit] += descriptor->test(bit);
  const std::size_t half = descriptors.size() / 2;
  for (std::size_t bit = 0; bit < ones.size(); ++bit)
    if (ones[bit] > half) mean.set(bit);
}

double FBrief::distance(const TDescriptor& a, const TDescriptor& b) {
  return static_cast<double>((a ^ b).count());
}

std::string FBrief::toString(const TDescriptor& a) {
  return a.to_string();
}

void FBrief::fromString(TDescriptor& a, const std::string& s) {
  if (s.size() != static_cast<std::size_t>(L) || s.find_first_not_of("01") != std::string::npos)
    throw std::invalid_argument("FBrief::fromString needs 256 characters '0' or '1'");
  a = TDescriptor(s);
}

void FBrief::toMat32F(const std::vector<TDescriptor>& descriptors, cv::Mat& mat) {
  if (descriptors.empty()) {
    mat.release();
    return;
  }
  mat.create(static_cast<int>(descriptors.size()), L, CV_32F);
  for (std::size_t i = 0; i < descriptors.size(); ++i) {
    float* row = mat.ptr<float>(static_cast<int>(i));
    for (std::size_t bit = 0; bit < static_cast<std::size_t>(L); ++bit)
      row[bit] = descriptors[i].test(bit) ? 1.f : 0.f;
  }
}

}  // namespace DBoW2
