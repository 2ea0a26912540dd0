#include "vision/jpeg_check.h"

#include <csetjmp>
#include <cstdio>

#include <jpeglib.h>

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

// Reads every scanline of the 1/8-scale image into one row buffer owned by
// libjpeg's pool (freed by jpeg_destroy_decompress, even after a longjmp).
bool decode_all(jpeg_decompress_struct& info, ErrorManager& errors, const std::uint8_t* data,
                std::size_t size) {
  if (setjmp(errors.escape) != 0) return false;
  jpeg_mem_src(&info, data, static_cast<unsigned long>(size));
  jpeg_read_header(&info, TRUE);
  info.scale_num = 1;
  info.scale_denom = 8;
  info.dct_method = JDCT_IFAST;
  info.do_fancy_upsampling = FALSE;
  info.do_block_smoothing = FALSE;
  if (info.jpeg_color_space != JCS_CMYK && info.jpeg_color_space != JCS_YCCK)
    info.out_color_space = JCS_GRAYSCALE;
  jpeg_start_decompress(&info);
  JSAMPARRAY row = (*info.mem->alloc_sarray)(reinterpret_cast<j_common_ptr>(&info), JPOOL_IMAGE,
                                             info.output_width * info.output_components, 1);
  while (info.output_scanline < info.output_height) jpeg_read_scanlines(&info, row, 1);
  jpeg_finish_decompress(&info);
  return true;
}

}  // namespace

std::string jpeg_decoding_problem(const std::uint8_t* data, std::size_t size) {
  jpeg_decompress_struct info{};
  ErrorManager errors{};
  info.err = jpeg_std_error(&errors.base);
  errors.base.error_exit = fail;
  errors.base.emit_message = emit;
  jpeg_create_decompress(&info);
  const bool clean = decode_all(info, errors, data, size);
  jpeg_destroy_decompress(&info);
  return clean ? std::string() : std::string(errors.message);
}

}  // namespace binbow::vision
