#include "vision/jpeg_check.h"

#include <csetjmp>
#include <cstdio>
#include <cstdlib>

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

// The largest magnitude of a dequantised DCT coefficient of 8-bit samples:
// the DC term of a block of -128s is -1024, and no AC term is larger. The
// encoder rounds to the nearest multiple of the quantiser, hence one more
// quantiser of slack.
bool coefficient_possible(JCOEF coefficient, unsigned quantiser) {
  return static_cast<unsigned long>(std::labs(coefficient)) * quantiser <= 1024UL + quantiser;
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
    const JQUANT_TBL* table = component.quant_table;
    for (JDIMENSION y = 0; y < component.height_in_blocks; ++y) {
      const JBLOCKARRAY row = (*info.mem->access_virt_barray)(reinterpret_cast<j_common_ptr>(&info),
                                                              coefficients[c], y, 1, FALSE);
      for (JDIMENSION x = 0; x < component.width_in_blocks; ++x)
        for (int k = 0; k < DCTSIZE2; ++k)
          if (!coefficient_possible(row[0][x][k], table != nullptr ? table->quantval[k] : 1)) {
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

}  // namespace binbow::vision
