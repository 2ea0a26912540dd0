#include "vision/image_header.h"

#include <algorithm>
#include <cctype>
#include <cstdio>
#include <cstring>
#include <string>
#include <string_view>

#include "binbow/error.h"

namespace binbow::vision {
namespace {

// Bounds-checked little- and big-endian reads from the header bytes; every
// reader below returns nullopt when the bytes run out.
class Bytes {
 public:
  Bytes(const std::uint8_t* data, std::size_t size) : data_(data), size_(size) {}
  std::size_t size() const { return size_; }
  bool has(std::uint64_t at, std::uint64_t count) const {
    return at <= size_ && count <= size_ - at;
  }
  std::uint8_t operator[](std::size_t at) const { return data_[at]; }
  const char* chars() const { return reinterpret_cast<const char*>(data_); }
  bool matches(std::size_t at, std::string_view text) const {
    return has(at, text.size()) && std::memcmp(data_ + at, text.data(), text.size()) == 0;
  }
  std::uint64_t read(std::uint64_t at, unsigned count, bool little_endian) const {
    std::uint64_t value = 0;
    for (unsigned i = 0; i < count; ++i) {
      const std::uint64_t byte = data_[at + (little_endian ? count - 1 - i : i)];
      value = (value << 8) | byte;
    }
    return value;
  }
  std::uint64_t be(std::uint64_t at, unsigned count) const { return read(at, count, false); }
  std::uint64_t le(std::uint64_t at, unsigned count) const { return read(at, count, true); }

 private:
  const std::uint8_t* data_;
  std::size_t size_;
};

using Result = std::optional<ImageDimensions>;

Result dimensions(std::uint64_t width, std::uint64_t height, const char* format,
                  bool ratio_bounded = false) {
  return ImageDimensions{width, height, format, ratio_bounded};
}

Result png(const Bytes& b) {
  // Signature (8 bytes), IHDR length (4), "IHDR" (4), width (4), height (4).
  if (!b.matches(12, "IHDR") || !b.has(16, 8)) return std::nullopt;
  return dimensions(b.be(16, 4), b.be(20, 4), "png", true);
}

// Walks the marker segments up to the first start-of-frame.
Result jpeg(const Bytes& b) {
  std::size_t at = 2;  // after SOI
  while (b.has(at, 4)) {
    if (b[at] != 0xFF) return std::nullopt;
    const std::uint8_t marker = b[at + 1];
    if (marker == 0xFF) {  // fill byte
      ++at;
      continue;
    }
    if (marker == 0xD8 || marker == 0x01 || (marker >= 0xD0 && marker <= 0xD7)) {
      at += 2;  // markers without a length
      continue;
    }
    if (marker == 0xDA || marker == 0xD9) return std::nullopt;  // scan before any frame
    const std::size_t length = b.be(at + 2, 2);
    const bool start_of_frame =
        marker >= 0xC0 && marker <= 0xCF && marker != 0xC4 && marker != 0xC8 && marker != 0xCC;
    if (start_of_frame) {
      // length (2), precision (1), height (2), width (2)
      if (!b.has(at, 9)) return std::nullopt;
      return dimensions(b.be(at + 7, 2), b.be(at + 5, 2), "jpeg", true);
    }
    if (length < 2) return std::nullopt;
    at += 2 + length;
  }
  return std::nullopt;
}

// ImageWidth (256), ImageLength (257), RowsPerStrip (278), TileWidth (322)
// and TileLength (323) of the first image file directory.
Result tiff(const Bytes& b) {
  const bool little = b[0] == 'I';
  const bool big_tiff = b.read(2, 2, little) == 43;
  const unsigned offset_size = big_tiff ? 8 : 4;
  const unsigned count_size = big_tiff ? 8 : 2;
  const unsigned entry_size = big_tiff ? 20 : 12;
  const std::uint64_t directory_at = big_tiff ? 8 : 4;
  if (!b.has(directory_at, offset_size)) return std::nullopt;
  const std::uint64_t directory = b.read(directory_at, offset_size, little);
  if (!b.has(directory, count_size)) return std::nullopt;
  const std::uint64_t entries = b.read(directory, count_size, little);
  std::uint64_t width = 0, height = 0, rows_per_strip = 0, tile_width = 0, tile_height = 0;
  bool has_width = false, has_height = false, tiled = false;
  for (std::uint64_t i = 0; i < entries; ++i) {
    const std::uint64_t at = directory + count_size + i * entry_size;
    if (!b.has(at, entry_size)) return std::nullopt;
    const std::uint64_t tag = b.read(at, 2, little);
    if (tag != 256 && tag != 257 && tag != 278 && tag != 322 && tag != 323) continue;
    const std::uint64_t type = b.read(at + 2, 2, little);
    const std::uint64_t value_at = at + 4 + (big_tiff ? 8 : 4);
    std::uint64_t value = 0;
    if (type == 3) {  // SHORT
      value = b.read(value_at, 2, little);
    } else if (type == 4) {  // LONG
      value = b.read(value_at, 4, little);
    } else if (type == 16 && big_tiff) {  // LONG8
      value = b.read(value_at, 8, little);
    } else {
      return std::nullopt;
    }
    // A repeated tag (found by fuzzing: a second ImageWidth of 1) counts at
    // its largest, whichever one the decoder keeps.
    switch (tag) {
      case 256:
        width = std::max(width, value), has_width = true;
        break;
      case 257:
        height = std::max(height, value), has_height = true;
        break;
      case 278:
        rows_per_strip = std::max(rows_per_strip, value);
        break;
      default:
        std::uint64_t& tile = tag == 322 ? tile_width : tile_height;
        tile = std::max(tile, value), tiled = true;
    }
  }
  if (!has_width || !has_height) return std::nullopt;
  Result result = dimensions(width, height, "tiff");
  // As OpenCV 4.6 sizes its buffer: a missing (0) width or height is the
  // image's, and so is an unbounded (2^32 - 1) strip.
  result->block_width = tiled && tile_width != 0 ? tile_width : width;
  const std::uint64_t block_height = tiled ? tile_height : rows_per_strip;
  result->block_height =
      block_height == 0 || (!tiled && block_height == 0xFFFFFFFFu) ? height : block_height;
  return result;
}

Result bmp(const Bytes& b) {
  if (!b.has(14, 4)) return std::nullopt;
  const std::uint64_t header_size = b.le(14, 4);
  if (header_size == 12) {  // OS/2 BITMAPCOREHEADER: 16-bit sizes
    if (!b.has(18, 4)) return std::nullopt;
    return dimensions(b.le(18, 2), b.le(20, 2), "bmp");
  }
  if (header_size < 16 || !b.has(18, 8)) return std::nullopt;
  // Signed 32-bit; a negative height means top-down rows.
  const auto magnitude = [](std::uint64_t v) -> std::uint64_t {
    const auto s = static_cast<std::int32_t>(static_cast<std::uint32_t>(v));
    return s < 0 ? std::uint64_t{0} - static_cast<std::int64_t>(s) : static_cast<std::uint64_t>(s);
  };
  return dimensions(magnitude(b.le(18, 4)), magnitude(b.le(22, 4)), "bmp");
}

Result webp(const Bytes& b) {
  if (b.matches(12, "VP8 ")) {
    // Frame tag (3 bytes), start code 9D 01 2A, 14-bit width and height.
    if (!b.has(20, 10) || b[23] != 0x9D || b[24] != 0x01 || b[25] != 0x2A) return std::nullopt;
    return dimensions(b.le(26, 2) & 0x3FFF, b.le(28, 2) & 0x3FFF, "webp");
  }
  if (b.matches(12, "VP8L")) {
    if (!b.has(20, 5) || b[20] != 0x2F) return std::nullopt;
    const std::uint64_t bits = b.le(21, 4);
    return dimensions((bits & 0x3FFF) + 1, ((bits >> 14) & 0x3FFF) + 1, "webp");
  }
  if (b.matches(12, "VP8X")) {
    if (!b.has(20, 10)) return std::nullopt;
    return dimensions(b.le(24, 3) + 1, b.le(27, 3) + 1, "webp");
  }
  return std::nullopt;
}

// Netpbm (P1-P6: width and height after the magic, '#' comments between),
// PAM (P7: WIDTH and HEIGHT lines) and PFM (PF, Pf).
Result netpbm(const Bytes& b) {
  const std::size_t limit = std::min<std::size_t>(b.size(), 4096);
  std::size_t at = 2;
  // The next whitespace-separated token of the header, comments skipped.
  const auto token = [&]() -> std::string_view {
    for (;;) {
      while (at < limit && std::isspace(b[at])) ++at;
      if (at < limit && b[at] == '#') {
        while (at < limit && b[at] != '\n') ++at;
        continue;
      }
      break;
    }
    const std::size_t start = at;
    while (at < limit && !std::isspace(b[at])) ++at;
    return {b.chars() + start, at - start};
  };
  const auto number = [](std::string_view t) -> std::optional<std::uint64_t> {
    if (t.empty() || t.size() > 10) return std::nullopt;
    std::uint64_t value = 0;
    for (char c : t) {
      if (!std::isdigit(static_cast<unsigned char>(c))) return std::nullopt;
      value = value * 10 + static_cast<std::uint64_t>(c - '0');
    }
    return value;
  };
  if (b[1] == '7') {
    std::optional<std::uint64_t> width, height;
    for (std::string_view t = token(); !t.empty() && t != "ENDHDR"; t = token()) {
      if (t == "WIDTH") width = number(token());
      if (t == "HEIGHT") height = number(token());
    }
    if (!width || !height) return std::nullopt;
    return dimensions(*width, *height, "pam");
  }
  const auto width = number(token());
  const auto height = number(token());
  if (!width || !height) return std::nullopt;
  return dimensions(*width, *height, b[1] == 'F' || b[1] == 'f' ? "pfm" : "pnm");
}

// "-Y rows +X columns" (or another orientation) after the header's blank line.
Result radiance(const Bytes& b) {
  const std::size_t limit = std::min<std::size_t>(b.size(), 65536);
  std::string_view text(b.chars(), limit);
  const std::size_t blank = text.find("\n\n");
  if (blank == std::string_view::npos) return std::nullopt;
  text.remove_prefix(blank + 2);
  text = text.substr(0, text.find('\n'));
  char first_sign = 0, first_axis = 0, second_sign = 0, second_axis = 0;
  unsigned long long first = 0, second = 0;
  const std::string line(text);
  if (std::sscanf(line.c_str(), "%c%c %llu %c%c %llu", &first_sign, &first_axis, &first,
                  &second_sign, &second_axis, &second) != 6 ||
      first_axis == second_axis || (first_axis != 'X' && first_axis != 'Y') ||
      (second_axis != 'X' && second_axis != 'Y')) {
    return std::nullopt;
  }
  return first_axis == 'Y' ? dimensions(second, first, "hdr") : dimensions(first, second, "hdr");
}

// The first header's dataWindow attribute (box2i: xMin yMin xMax yMax).
Result openexr(const Bytes& b) {
  std::size_t at = 8;  // magic, version and flags
  while (b.has(at, 1) && b[at] != 0) {
    const char* begin = b.chars();
    const auto* name_end = static_cast<const char*>(std::memchr(begin + at, 0, b.size() - at));
    if (name_end == nullptr) return std::nullopt;
    const std::string_view name(begin + at, static_cast<std::size_t>(name_end - (begin + at)));
    at += name.size() + 1;
    const auto* type_end = static_cast<const char*>(std::memchr(begin + at, 0, b.size() - at));
    if (type_end == nullptr) return std::nullopt;
    at = static_cast<std::size_t>(type_end - begin) + 1;
    if (!b.has(at, 4)) return std::nullopt;
    const std::uint64_t size = b.le(at, 4);
    at += 4;
    if (!b.has(at, size)) return std::nullopt;
    if (name == "dataWindow" && size == 16) {
      const auto coordinate = [&](std::size_t offset) {
        return static_cast<std::int64_t>(static_cast<std::int32_t>(b.le(at + offset, 4)));
      };
      const std::int64_t width = coordinate(8) - coordinate(0) + 1;
      const std::int64_t height = coordinate(12) - coordinate(4) + 1;
      return dimensions(static_cast<std::uint64_t>(std::max<std::int64_t>(width, 0)),
                        static_cast<std::uint64_t>(std::max<std::int64_t>(height, 0)), "exr");
    }
    at += size;
  }
  return std::nullopt;
}

// A JPEG 2000 codestream's SIZ marker segment: the size of the reference grid
// less its offset; more than 4 components (each allocated whole) is refused.
Result jpeg2000_codestream(const Bytes& b, std::uint64_t at) {
  // FF4F (SOC), FF51 (SIZ), Lsiz, Rsiz, Xsiz, Ysiz, XOsiz, YOsiz, ..., Csiz.
  if (!b.has(at, 42) || b.be(at, 4) != 0xFF4FFF51) return std::nullopt;
  const std::uint64_t width = b.be(at + 8, 4), height = b.be(at + 12, 4);
  const std::uint64_t x_offset = b.be(at + 16, 4), y_offset = b.be(at + 20, 4);
  const std::uint64_t components = b.be(at + 40, 2);
  if (x_offset >= width || y_offset >= height || components > 4) return std::nullopt;
  return dimensions(width - x_offset, height - y_offset, "jpeg2000");
}

// A .jp2 file: boxes up to the contiguous codestream box (jp2c).
Result jpeg2000_file(const Bytes& b) {
  std::uint64_t at = 0;
  while (b.has(at, 8)) {
    std::uint64_t length = b.be(at, 4), header = 8;
    if (length == 1) {
      if (!b.has(at, 16)) return std::nullopt;
      length = b.be(at + 8, 8);
      header = 16;
    }
    if (b.matches(at + 4, "jp2c")) return jpeg2000_codestream(b, at + header);
    // 0: the last box, and it is not the codestream.
    if (length < header || !b.has(at, length)) return std::nullopt;
    at += length;
  }
  return std::nullopt;
}

}  // namespace

std::optional<ImageDimensions> declared_dimensions(const std::uint8_t* data, std::size_t size) {
  const Bytes b(data, size);
  if (b.matches(0, "\x89PNG\r\n\x1A\n")) return png(b);
  if (b.has(0, 3) && b[0] == 0xFF && b[1] == 0xD8 && b[2] == 0xFF) return jpeg(b);
  if (b.matches(0, std::string_view("II*\0", 4)) || b.matches(0, std::string_view("MM\0*", 4)) ||
      b.matches(0, std::string_view("II+\0", 4)) || b.matches(0, std::string_view("MM\0+", 4))) {
    return tiff(b);
  }
  if (b.matches(0, "BM")) return bmp(b);
  if (b.matches(0, "RIFF") && b.matches(8, "WEBP")) return webp(b);
  if (b.has(0, 3) && b[0] == 'P' && ((b[1] >= '1' && b[1] <= '7') || b[1] == 'F' || b[1] == 'f') &&
      std::isspace(b[2])) {
    return netpbm(b);
  }
  if (b.has(0, 4) && b.be(0, 4) == 0x59A66A95) {  // Sun raster
    if (!b.has(4, 8)) return std::nullopt;
    return dimensions(b.be(4, 4), b.be(8, 4), "sunras");
  }
  if (b.matches(0, "#?RADIANCE") || b.matches(0, "#?RGBE")) return radiance(b);
  if (b.has(0, 4) && b.be(0, 4) == 0x762F3101) return openexr(b);
  if (b.matches(0, std::string_view("\0\0\0\x0CjP  \r\n\x87\n", 12))) return jpeg2000_file(b);
  if (b.has(0, 4) && b.be(0, 4) == 0xFF4FFF51) return jpeg2000_codestream(b, 0);
  return std::nullopt;
}

std::string describe_size(std::uint64_t width, std::uint64_t height) {
  return std::to_string(width) + "x" + std::to_string(height);
}

void check_pixel_count(const std::string& path, const char* what, std::uint64_t width,
                       std::uint64_t height, std::uint64_t max_pixels) {
  if (width == 0 || height == 0) {
    throw FileError(
        path, std::string(what) + " declares 0 pixels (" + describe_size(width, height) + ")");
  }
  if (width > max_pixels / height) {
    throw FileError(path, std::string(what) + " declares " + describe_size(width, height) +
                              " pixels, more than the limit of " + std::to_string(max_pixels));
  }
}

ImageDimensions check_image_header(const std::string& path, const std::string& bytes,
                                   std::uint64_t max_pixels) {
  if (bytes.empty()) throw FileError(path, "empty file (0 bytes), not an image");
  const auto declared =
      declared_dimensions(reinterpret_cast<const std::uint8_t*>(bytes.data()), bytes.size());
  if (!declared) {
    throw FileError(path,
                    "not an image whose size can be read before decoding "
                    "(unknown format, or a damaged header)");
  }
  check_pixel_count(path, "image header", declared->width, declared->height, max_pixels);
  return *declared;
}

void check_image_allocation(const std::string& path, const ImageDimensions& declared,
                            std::size_t file_size, std::uint64_t max_pixels) {
  // Found by fuzzing: a 172-byte TIFF of 12090x6 pixels in strips of 65530
  // rows made OpenCV allocate 3 GB for one strip.
  if (declared.block_width != 0)
    check_pixel_count(path, "TIFF header's strip or tile", declared.block_width,
                      declared.block_height, max_pixels);
  if (declared.ratio_bounded &&
      declared.width * declared.height > max_pixels_for_file_size(file_size)) {
    throw FileError(path,
                    "image header declares " + describe_size(declared.width, declared.height) +
                        " pixels, more than " + std::to_string(file_size) + " bytes can hold");
  }
}

}  // namespace binbow::vision
