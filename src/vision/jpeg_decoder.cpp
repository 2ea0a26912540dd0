#include "vision/jpeg_decoder.h"

#include <csetjmp>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <new>

#if defined(__x86_64__)
#include <immintrin.h>
#endif

#include <jpeglib.h>
// libjpeg's module interfaces: each MCU's coefficients are checked as the
// entropy decoder (jpeg_entropy_decoder::decode_mcu) delivers them. Where the
// -dev package does not install this header, every JPEG is checked in a
// separate pass first.
#if __has_include(<jpegint.h>)
#include <jpegint.h>
#define BINBOW_JPEG_ONE_PASS_CHECK 1
#else
#define BINBOW_JPEG_ONE_PASS_CHECK 0
#endif

namespace binbow::vision {
namespace {

// libjpeg reports through callbacks that must not return on errors; the
// standard way out of C code is longjmp back to the caller's setjmp. Only
// trivially destructible objects live between the two.
struct ErrorManager {
  jpeg_error_mgr base;
  std::jmp_buf escape;
  char message[JMSG_LENGTH_MAX];
};

[[noreturn]] void fail(j_common_ptr info) {
  auto* errors = reinterpret_cast<ErrorManager*>(info->err);
  (*info->err->format_message)(info, errors->message);
  std::longjmp(errors->escape, 1);
}

// Level -1 is a warning (corrupt or missing data that libjpeg papers over);
// higher levels are trace messages.
void emit(j_common_ptr info, int level) {
  if (level < 0) fail(info);
}

// The largest magnitude of a dequantised DCT coefficient of 8-bit samples:
// the DC term of a block of -128s is -1024, and no AC term is larger. The
// encoder rounds to the nearest multiple of the quantiser, hence one more
// quantiser of slack.
bool coefficient_possible(JCOEF coefficient, unsigned quantiser) {
  return static_cast<unsigned long>(std::labs(coefficient)) * quantiser <= 1024UL + quantiser;
}

bool block_possible(const JCOEF* block, const JQUANT_TBL* table) {
  for (int k = 0; k < DCTSIZE2; ++k)
    if (!coefficient_possible(block[k], table != nullptr ? table->quantval[k] : 1)) return false;
  return true;
}

// Entropy-decodes every block (no inverse DCT, no colour conversion) and
// checks each coefficient; jpeg_finish_decompress then reads on to the end
// of the image, where libjpeg counts bytes the scan left unread.
bool check_all(jpeg_decompress_struct& info, ErrorManager& errors, const std::uint8_t* data,
               std::size_t size) {
  if (setjmp(errors.escape) != 0) return false;
  jpeg_mem_src(&info, data, static_cast<unsigned long>(size));
  jpeg_read_header(&info, TRUE);
  jvirt_barray_ptr* coefficients = jpeg_read_coefficients(&info);
  for (int c = 0; c < info.num_components; ++c) {
    const jpeg_component_info& component = info.comp_info[c];
    for (JDIMENSION y = 0; y < component.height_in_blocks; ++y) {
      const JBLOCKARRAY row = (*info.mem->access_virt_barray)(reinterpret_cast<j_common_ptr>(&info),
                                                              coefficients[c], y, 1, FALSE);
      for (JDIMENSION x = 0; x < component.width_in_blocks; ++x)
        if (!block_possible(row[0][x], component.quant_table)) {
          std::snprintf(errors.message, sizeof errors.message,
                        "Corrupt JPEG data: block %u,%u of component %d decodes to a "
                        "coefficient no 8-bit image has",
                        static_cast<unsigned>(x), static_cast<unsigned>(y), c);
          return false;
        }
    }
  }
  jpeg_finish_decompress(&info);
  return true;
}

// coefficient_possible over a block, as |c| <= limit <=> (c + limit) mod
// 2^16 <= 2 limit (limit < 2^15): one add and one unsigned comparison per
// coefficient, 8 or 16 at a time. Most coefficients are 0, and checking them
// one by one would cost a third of the decoding.
bool block_within(const JCOEF* block, const std::uint16_t* limits, const std::uint16_t* spans) {
#if defined(__x86_64__)
  __m128i outside = _mm_setzero_si128();
  for (int k = 0; k < DCTSIZE2; k += 8) {
    const __m128i c = _mm_loadu_si128(reinterpret_cast<const __m128i*>(block + k));
    const __m128i limit = _mm_loadu_si128(reinterpret_cast<const __m128i*>(limits + k));
    const __m128i span = _mm_loadu_si128(reinterpret_cast<const __m128i*>(spans + k));
    outside = _mm_or_si128(outside, _mm_subs_epu16(_mm_add_epi16(c, limit), span));
  }
  return _mm_movemask_epi8(_mm_cmpeq_epi8(outside, _mm_setzero_si128())) == 0xFFFF;
#else
  unsigned outside = 0;
  for (int k = 0; k < DCTSIZE2; ++k)
    outside |=
        static_cast<std::uint16_t>(static_cast<std::uint16_t>(block[k]) + limits[k]) > spans[k];
  return outside == 0;
#endif
}

#if defined(__x86_64__)
__attribute__((target("avx2"))) bool block_within_avx2(const JCOEF* block,
                                                       const std::uint16_t* limits,
                                                       const std::uint16_t* spans) {
  __m256i outside = _mm256_setzero_si256();
  for (int k = 0; k < DCTSIZE2; k += 16) {
    const __m256i c = _mm256_loadu_si256(reinterpret_cast<const __m256i*>(block + k));
    const __m256i limit = _mm256_loadu_si256(reinterpret_cast<const __m256i*>(limits + k));
    const __m256i span = _mm256_loadu_si256(reinterpret_cast<const __m256i*>(spans + k));
    outside = _mm256_or_si256(outside, _mm256_subs_epu16(_mm256_add_epi16(c, limit), span));
  }
  return _mm256_testz_si256(outside, outside) != 0;
}
#endif

using BlockCheck = bool (*)(const JCOEF*, const std::uint16_t*, const std::uint16_t*);

BlockCheck best_block_check() {
#if defined(__x86_64__)
  if (__builtin_cpu_supports("avx2")) return block_within_avx2;
#endif
  return block_within;
}

using DecodeMcu = boolean (*)(j_decompress_ptr, JBLOCKROW*);

// One libjpeg decompressor, kept per thread: creating one allocates its
// memory pools, a measurable part of decoding a small frame.
struct Decompressor {
  jpeg_decompress_struct info{};
  ErrorManager errors{};
  DecodeMcu decode_mcu = nullptr;  // libjpeg's, wrapped by checked_decode_mcu
  // Per component of the scan: the largest possible magnitude of each
  // quantised coefficient (coefficient_possible's bound, divided out), and
  // twice that.
  std::uint16_t limits[MAX_COMPS_IN_SCAN][DCTSIZE2] = {};
  std::uint16_t spans[MAX_COMPS_IN_SCAN][DCTSIZE2] = {};
  BlockCheck block_check = best_block_check();

  Decompressor() {
    info.err = jpeg_std_error(&errors.base);
    errors.base.error_exit = fail;
    errors.base.emit_message = emit;
    info.client_data = this;
    if (setjmp(errors.escape) != 0) throw std::bad_alloc();  // the only failure
    jpeg_create_decompress(&info);
  }
  ~Decompressor() { jpeg_destroy_decompress(&info); }
  Decompressor(const Decompressor&) = delete;
  Decompressor& operator=(const Decompressor&) = delete;
};

#if BINBOW_JPEG_ONE_PASS_CHECK
// libjpeg's decode_mcu, then the check of every block of the MCU: all
// components, also those a grey output does not need (they are
// entropy-decoded all the same).
boolean checked_decode_mcu(j_decompress_ptr info, JBLOCKROW* blocks) {
  auto* decompressor = static_cast<Decompressor*>(info->client_data);
  if (!decompressor->decode_mcu(info, blocks)) return FALSE;
  for (int b = 0; b < info->blocks_in_MCU; ++b) {
    const int in_scan = info->MCU_membership[b];
    if (!decompressor->block_check(blocks[b][0], decompressor->limits[in_scan],
                                   decompressor->spans[in_scan])) {
      const jpeg_component_info* component = info->cur_comp_info[in_scan];
      ErrorManager& errors = decompressor->errors;
      std::snprintf(errors.message, sizeof errors.message,
                    "Corrupt JPEG data: a block of component %d in MCU row %u decodes to a "
                    "coefficient no 8-bit image has",
                    component->component_index, static_cast<unsigned>(info->input_iMCU_row));
      std::longjmp(errors.escape, 1);
    }
  }
  return TRUE;
}

// Wraps the entropy decoder of a started single-scan decompression with
// checked_decode_mcu, for the quantisation tables of its scan.
void check_while_decoding(Decompressor& decompressor) {
  jpeg_decompress_struct& info = decompressor.info;
  for (int c = 0; c < info.comps_in_scan; ++c) {
    const JQUANT_TBL* table = info.cur_comp_info[c]->quant_table;
    for (int k = 0; k < DCTSIZE2; ++k) {
      // A quantiser of 0 makes every coefficient 0 once dequantised.
      const unsigned quantiser = table != nullptr ? table->quantval[k] : 1;
      const unsigned limit = quantiser == 0 ? 32767 : (1024 + quantiser) / quantiser;
      decompressor.limits[c][k] = static_cast<std::uint16_t>(limit);
      decompressor.spans[c][k] = static_cast<std::uint16_t>(2 * limit);
    }
  }
  decompressor.decode_mcu = info.entropy->decode_mcu;
  info.entropy->decode_mcu = checked_decode_mcu;
}
#endif

// Reads big- or little-endian integers inside [data, data + size).
struct TiffBytes {
  const std::uint8_t* data;
  std::size_t size;
  bool little_endian;
  bool has(std::size_t at, std::size_t count) const { return at <= size && count <= size - at; }
  unsigned read(std::size_t at, unsigned count) const {
    unsigned value = 0;
    for (unsigned i = 0; i < count; ++i)
      value = (value << 8) | data[at + (little_endian ? count - 1 - i : i)];
    return value;
  }
};

// The orientation tag of the Exif segment's first directory, 1 if none.
int exif_orientation(const std::uint8_t* tiff, std::size_t size) {
  if (size < 8 || !((tiff[0] == 'I' && tiff[1] == 'I') || (tiff[0] == 'M' && tiff[1] == 'M')))
    return 1;
  const TiffBytes b{tiff, size, tiff[0] == 'I'};
  const std::size_t directory = b.read(4, 4);
  if (!b.has(directory, 2)) return 1;
  const unsigned entries = b.read(directory, 2);
  constexpr unsigned kOrientationTag = 274, kShortType = 3;
  for (unsigned i = 0; i < entries; ++i) {
    const std::size_t entry = directory + 2 + std::size_t{12} * i;
    if (!b.has(entry, 12)) return 1;
    if (b.read(entry, 2) != kOrientationTag) continue;
    if (b.read(entry + 2, 2) != kShortType) return 1;
    const unsigned orientation = b.read(entry + 8, 2);
    return orientation >= 1 && orientation <= 8 ? static_cast<int>(orientation) : 1;
  }
  return 1;
}

// `image` turned as Exif orientation `orientation` asks, as OpenCV does.
cv::Mat orient(const cv::Mat& image, int orientation) {
  cv::Mat turned;
  switch (orientation) {
    case 2:
      cv::flip(image, turned, 1);
      return turned;
    case 3:
      cv::flip(image, turned, -1);
      return turned;
    case 4:
      cv::flip(image, turned, 0);
      return turned;
    case 5:
      cv::transpose(image, turned);
      return turned;
    case 6:
      cv::transpose(image, turned);
      cv::flip(turned, turned, 1);
      return turned;
    case 7:
      cv::transpose(image, turned);
      cv::flip(turned, turned, -1);
      return turned;
    case 8:
      cv::transpose(image, turned);
      cv::flip(turned, turned, 0);
      return turned;
    default:
      return image;
  }
}

// The largest of 1, 2, 4 and 8 that keeps a `width`-pixel image at least
// twice max_width wide: the caller's area resampling then still averages 2x2
// pixels or more, which keeps the features close to those of the image
// decoded whole and resized (scaling to max_width itself, by the inverse DCT
// alone, gives sharper images and lost a sixth of the loops of the bundled
// sample).
int scale_denominator(JDIMENSION width, int max_width) {
  if (max_width <= 0) return 1;
  const auto wanted = 2 * static_cast<unsigned long>(max_width);
  int denominator = 1;
  while (denominator < 8 && (width + 2 * denominator - 1) / (2 * denominator) >= wanted)
    denominator *= 2;
  return denominator;
}

enum class Outcome { kDecoded, kDamaged, kCheckedElsewhere, kForOpenCV };

// Decodes into `image`; kCheckedElsewhere: a multi-scan JPEG, to check with
// jpeg_decoding_problem and decode again unhooked; kForOpenCV: CMYK or YCCK.
// `max_width` is of the image as stored (before orientation); `full_size`
// receives its size decoded whole.
Outcome decode(Decompressor& decompressor, const std::uint8_t* data, std::size_t size, bool grey,
               int max_width, bool checked, cv::Mat& image, cv::Size& full_size) {
  jpeg_decompress_struct& info = decompressor.info;
  if (setjmp(decompressor.errors.escape) != 0) return Outcome::kDamaged;
  jpeg_mem_src(&info, data, static_cast<unsigned long>(size));
  jpeg_read_header(&info, TRUE);
  if (info.num_components == 4) return Outcome::kForOpenCV;
  if (!checked && (!BINBOW_JPEG_ONE_PASS_CHECK || jpeg_has_multiple_scans(&info)))
    return Outcome::kCheckedElsewhere;
  info.out_color_space = grey ? JCS_GRAYSCALE : JCS_EXT_BGR;
  full_size = cv::Size(static_cast<int>(info.image_width), static_cast<int>(info.image_height));
  info.scale_num = 1;
  info.scale_denom = static_cast<unsigned>(scale_denominator(info.image_width, max_width));
  jpeg_start_decompress(&info);
#if BINBOW_JPEG_ONE_PASS_CHECK
  // A single scan: no block is decoded before the first scanline is read.
  if (!checked) check_while_decoding(decompressor);
#endif
  image.create(static_cast<int>(info.output_height), static_cast<int>(info.output_width),
               grey ? CV_8UC1 : CV_8UC3);
  constexpr JDIMENSION kRowsAtOnce = 4;  // libjpeg's rec_outbuf_height is at most 4
  while (info.output_scanline < info.output_height) {
    JSAMPROW rows[kRowsAtOnce];
    JDIMENSION count = 0;
    for (; count < kRowsAtOnce && info.output_scanline + count < info.output_height; ++count)
      rows[count] = image.ptr<JSAMPLE>(static_cast<int>(info.output_scanline + count));
    jpeg_read_scanlines(&info, rows, count);
  }
  jpeg_finish_decompress(&info);
  return Outcome::kDecoded;
}

}  // namespace

std::string jpeg_decoding_problem(const std::uint8_t* data, std::size_t size) {
  jpeg_decompress_struct info{};
  ErrorManager errors{};
  info.err = jpeg_std_error(&errors.base);
  errors.base.error_exit = fail;
  errors.base.emit_message = emit;
  jpeg_create_decompress(&info);
  const bool clean = check_all(info, errors, data, size);
  jpeg_destroy_decompress(&info);
  return clean ? std::string() : std::string(errors.message);
}

int jpeg_exif_orientation(const std::uint8_t* data, std::size_t size) {
  // Marker segments from the start of image to the start of scan.
  std::size_t at = 2;
  constexpr std::uint8_t kApp1 = 0xE1, kStartOfScan = 0xDA;
  while (at + 4 <= size && data[at] == 0xFF) {
    const std::uint8_t marker = data[at + 1];
    if (marker == 0xFF) {  // fill byte
      ++at;
      continue;
    }
    if (marker == kStartOfScan) break;
    const std::size_t length = (std::size_t{data[at + 2]} << 8) | data[at + 3];
    if (length < 2 || length > size - at - 2) break;
    const std::uint8_t* body = data + at + 4;
    const std::size_t body_size = length - 2;
    if (marker == kApp1 && body_size >= 6 && std::memcmp(body, "Exif\0\0", 6) == 0)
      return exif_orientation(body + 6, body_size - 6);
    at += 2 + length;
  }
  return 1;
}

DecodedJpeg decode_jpeg(const std::uint8_t* data, std::size_t size, bool grey, int max_width) {
  thread_local Decompressor decompressor;
  const int orientation = jpeg_exif_orientation(data, size);
  const bool turned = orientation >= 5;  // width and height swap
  // max_width applies to the oriented image, whose width is the stored height when turned.
  const int stored_max_width = turned ? 0 : max_width;
  DecodedJpeg decoded;
  Outcome outcome = decode(decompressor, data, size, grey, stored_max_width, false, decoded.image,
                           decoded.full_size);
  if (outcome == Outcome::kCheckedElsewhere || outcome == Outcome::kForOpenCV) {
    jpeg_abort_decompress(&decompressor.info);
    decoded.problem = jpeg_decoding_problem(data, size);
    if (!decoded.problem.empty() || outcome == Outcome::kForOpenCV) return decoded;
    outcome = decode(decompressor, data, size, grey, stored_max_width, true, decoded.image,
                     decoded.full_size);
  }
  if (outcome == Outcome::kDamaged) {
    decoded.problem = decompressor.errors.message;
    decoded.image.release();
  }
  // Ready for the next image, whatever happened to this one.
  jpeg_abort_decompress(&decompressor.info);
  if (!decoded.image.empty()) {
    decoded.image = orient(decoded.image, orientation);
    if (turned) decoded.full_size = cv::Size(decoded.full_size.height, decoded.full_size.width);
  }
  return decoded;
}

}  // namespace binbow::vision
