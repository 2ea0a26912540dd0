// DBoW2 compatibility layer: descriptors of every type the templates accept,
// turned into the bytes binbow's vocabulary compares, and back. Not meant to
// be used directly.
//
// cv::Mat rows are their bytes. Bitsets (std::bitset<N>, and any type with
// size() and test(i), such as boost::dynamic_bitset<>: DLib's and VINS's
// BRIEF) become bytes with bit i of the bitset in bit i % 8 (least
// significant first) of byte i / 8: the order of DBoW2's YAML bit strings and
// of VINS's binary vocabularies, so the same bits in a cv::Mat row or in a
// bitset give the same words. Boost is never included here: a
// boost::dynamic_bitset is accepted wherever the user's code has one.
//
// C++11; the standard library and OpenCV core only (see DBoW2.h).
#ifndef BINBOW_COMPAT_DBOW2_DETAIL_DESCRIPTOR_BYTES_H
#define BINBOW_COMPAT_DBOW2_DETAIL_DESCRIPTOR_BYTES_H

#include <bitset>
#include <cstddef>
#include <opencv2/core.hpp>
#include <sstream>
#include <stdexcept>
#include <string>
#include <type_traits>
#include <utility>
#include <vector>

namespace DBoW2 {
namespace binbow_detail {

// Appends the descriptor's bytes to `out`. Throws std::invalid_argument
// unless `d` is one row of `code_size` CV_8U bytes (of any length when
// `code_size` is 0).
void append_descriptor_bytes(const cv::Mat& d, std::size_t code_size,
                             std::vector<unsigned char>& out);
void descriptor_from_bytes(const unsigned char* bytes, std::size_t code_size, cv::Mat& d);

// The error of a bitset whose length is not the vocabulary's.
inline std::invalid_argument bitset_size_error(std::size_t bits, std::size_t code_size) {
  std::ostringstream message;
  if (code_size == 0)
    message << "a bitset descriptor of " << bits << " bits is not a whole number of bytes";
  else
    message << "a bitset descriptor of " << bits << " bits does not fit a vocabulary of "
            << code_size * 8 << "-bit words";
  return std::invalid_argument(message.str());
}

// Bitsets: std::bitset<N>, boost::dynamic_bitset<> and any other type with
// size() and test(i). `code_size` as for cv::Mat, in bytes.
template <class Bits>
auto append_descriptor_bytes(const Bits& d, std::size_t code_size, std::vector<unsigned char>& out)
    -> decltype(static_cast<std::size_t>(d.size()), static_cast<bool>(d.test(0)), void()) {
  const std::size_t bits = static_cast<std::size_t>(d.size());
  if (bits % 8 != 0 || (code_size != 0 && bits != code_size * 8))
    throw bitset_size_error(bits, code_size);
  for (std::size_t byte = 0; byte < bits / 8; ++byte) {
    unsigned value = 0;
    for (std::size_t bit = 0; bit < 8; ++bit)
      if (d.test(byte * 8 + bit)) value |= 1u << bit;
    out.push_back(static_cast<unsigned char>(value));
  }
}

template <std::size_t N>
void descriptor_from_bytes(const unsigned char* bytes, std::size_t code_size, std::bitset<N>& d) {
  if (code_size * 8 != N) throw bitset_size_error(N, code_size);
  d.reset();
  for (std::size_t bit = 0; bit < N; ++bit)
    if ((bytes[bit / 8] >> (bit % 8)) & 1u) d.set(bit);
}

// Resizable bitsets (boost::dynamic_bitset<>): as long as the words.
template <class Bits>
auto descriptor_from_bytes(const unsigned char* bytes, std::size_t code_size, Bits& d)
    -> decltype(d.resize(std::size_t(0)), d.reset(), d.set(std::size_t(0)), void()) {
  d.resize(code_size * 8);
  d.reset();
  for (std::size_t bit = 0; bit < code_size * 8; ++bit)
    if ((bytes[bit / 8] >> (bit % 8)) & 1u) d.set(bit);
}

// Whether the templates accept descriptors of type D: selects the member
// templates of TemplatedVocabulary and TemplatedDatabase that take them.
template <class D>
struct is_descriptor {
 private:
  template <class T>
  static char test(decltype(append_descriptor_bytes(std::declval<const T&>(), std::size_t(0),
                                                    std::declval<std::vector<unsigned char>&>()))*);
  template <class T>
  static long test(...);

 public:
  static const bool value = sizeof(test<D>(0)) == 1;
};

// R for descriptor types D, nothing otherwise: the return type of those
// member templates.
template <class D, class R = void>
struct if_descriptor : std::enable_if<is_descriptor<D>::value, R> {};

}  // namespace binbow_detail
}  // namespace DBoW2

#endif
