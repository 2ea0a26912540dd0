#include "binbow/loop/evaluation.h"

#include <sys/stat.h>
#include <unistd.h>
#include <algorithm>
#include <array>
#include <cctype>
#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <functional>
#include <memory>
#include <sstream>
#include <vector>

#include <matio.h>
#include <zlib.h>

#include "binbow/error.h"
#include "binbow/vision/image_source.h"
#include "core/file_io.h"
#include "vision/regular_file.h"

namespace binbow::loop {

using vision::read_grey_image;
using vision::read_regular_file;
using vision::require_regular_file;
namespace {

// (later, earlier) index pairs, as GroundTruth::from_later_earlier takes them.
using LaterEarlier = std::vector<std::pair<std::uint32_t, std::uint32_t>>;

// What a ground-truth file holds: its frame count and its pairs.
struct Loaded {
  std::size_t frames = 0;
  LaterEarlier pairs;
};

// No loop-closure sequence comes near this; bounds what a damaged header can make us allocate.
constexpr std::size_t kMaxFrames = kMaxGroundTruthFrames;
constexpr std::size_t kMaxTextBytes = std::size_t{1} << 31;

// The frames of a ground truth declaring `declared` frames, cut to the run's
// `frames` when known.
std::size_t cut_to_run(std::size_t declared, const GroundTruthOptions& options) {
  return options.frames > 0 ? std::min(declared, options.frames) : declared;
}

// Adds the pair (a, b) unless it is on the diagonal or outside `frames`.
void add_pair(std::size_t a, std::size_t b, std::size_t frames, LaterEarlier& pairs) {
  if (a == b || a >= frames || b >= frames) return;
  pairs.emplace_back(static_cast<std::uint32_t>(std::max(a, b)),
                     static_cast<std::uint32_t>(std::min(a, b)));
}
// Dense .mat matrices are read this many cells at a time.
constexpr std::size_t kMatBlockBytes = std::size_t{128} << 20;

std::string lower(std::string s) {
  for (char& c : s) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return s;
}

bool ends_with(const std::string& s, const std::string& suffix) {
  return s.size() >= suffix.size() &&
         s.compare(s.size() - suffix.size(), suffix.size(), suffix) == 0;
}

std::string read_text(const std::string& path) {
  return read_regular_file(path, kMaxTextBytes);
}

Loaded from_image(const std::string& path, const GroundTruthOptions& options) {
  const cv::Mat image = read_grey_image(path, options.max_image_pixels);
  if (image.rows != image.cols) {
    throw FileError(path, "ground-truth image is " + std::to_string(image.cols) + "x" +
                              std::to_string(image.rows) +
                              " pixels; it must be square (row = query, column = match)");
  }
  Loaded loaded;
  loaded.frames = cut_to_run(static_cast<std::size_t>(image.rows), options);
  // Row q lists the earlier images that share a place with q, merged from
  // row q left of the diagonal and column q above it: increasing, without
  // duplicates, so the pairs come out sorted and exactly as many as there are.
  const int n = static_cast<int>(loaded.frames);
  for (int q = 0; q < n; ++q) {
    const std::uint8_t* row = image.ptr<std::uint8_t>(q);
    for (int j = 0; j < q; ++j)
      if (row[j] != 0 || image.ptr<std::uint8_t>(j)[q] != 0)
        loaded.pairs.emplace_back(static_cast<std::uint32_t>(q), static_cast<std::uint32_t>(j));
  }
  return loaded;
}

// Cells of a dense block as "non-zero?", whatever the MATLAB class.
template <class T>
void collect_nonzero(const void* data, std::size_t rows, std::size_t first_column,
                     std::size_t columns, std::size_t frames, LaterEarlier& pairs) {
  const T* cells = static_cast<const T*>(data);
  for (std::size_t c = 0; c < columns; ++c)
    for (std::size_t r = 0; r < rows; ++r)
      if (cells[c * rows + r] != T(0)) add_pair(r, first_column + c, frames, pairs);
}

struct MatCloser {
  void operator()(mat_t* m) const { Mat_Close(m); }
};
struct VarFreer {
  void operator()(matvar_t* v) const { Mat_VarFree(v); }
};

// The level-5 data types that stand at the top of a .mat file, and the ones
// of a matrix's first sub-elements.
constexpr std::uint32_t kMiInt8 = 1, kMiInt32 = 5, kMiUint32 = 6, kMiMatrix = 14,
                        kMiCompressed = 15;
constexpr std::uint32_t kMxSparseClass = 5;
// Characters (4), sparse (5) and the numeric classes (6 double ... 15 uint64).
constexpr std::uint32_t kMxFirstPlainClass = 4, kMxLastPlainClass = 15;
// matio sizes its first allocations of a variable from these: the dimension
// list (rank 32 at most) and the name.
constexpr std::uint64_t kMaxMatDimensionBytes = 32 * 4;
constexpr std::uint64_t kMaxMatNameBytes = 4096;
// Inflating a compressed variable once to check it costs time, not memory:
// 1 GiB is a dense 11,585² double matrix. matio allocates a sparse matrix's
// index and value arrays whole, so those may expand at most 64x (real sparse
// ground truths expand 3-10x), or to 16 MiB.
constexpr std::uint64_t kMaxMatInflatedBytes = std::uint64_t{1} << 30;
constexpr std::uint64_t kMaxSparseExpansion = 64;
constexpr std::uint64_t kMinSparseInflatedLimit = std::uint64_t{16} << 20;

// Follows the chain of data elements inside one variable, from the tag of
// its matrix at position 0: every element must end inside the matrix.
// Positions count from the matrix's tag, in the file or in the inflated
// stream of a compressed variable.
class ElementChain {
 public:
  struct Element {
    std::uint32_t type = 0;
    std::uint64_t bytes = 0;
  };

  ElementChain(const std::string& path, std::uint64_t offset) : path_(path), offset_(offset) {}

  // matio reads at most four elements after the name (a complex sparse
  // matrix's), so the walk stops there.
  bool done() const { return next_tag_ >= end_ || data_elements() >= data_.size(); }
  std::uint64_t next_tag() const { return next_tag_; }
  // Elements after the array flags, dimensions and name.
  std::size_t data_elements() const { return elements_ > 4 ? elements_ - 4 : 0; }
  const Element& data_element(std::size_t i) const { return data_[i]; }

  // The tag's two words, in the file's byte order already read.
  void on_tag(std::uint32_t first, std::uint32_t second) {
    const bool small = (first >> 16) != 0;  // a small data element: bytes in the tag
    const std::uint64_t bytes = small ? first >> 16 : second;
    if (elements_ == 0) {
      end_ = 8 + bytes;
      next_tag_ = 8;
    } else {
      if ((small && bytes > 4) || 8 + bytes > end_ - next_tag_)
        throw FileError(path_, "variable at byte " + std::to_string(offset_) + ": element " +
                                   std::to_string(elements_) + " declares " +
                                   std::to_string(bytes) + " bytes, more than its matrix holds");
      next_tag_ += small ? 8 : 8 + (bytes + 7) / 8 * 8;
      if (data_elements() < data_.size()) data_[data_elements()] = {first & 0xffff, bytes};
    }
    ++elements_;
  }

 private:
  const std::string& path_;
  std::uint64_t offset_;
  std::uint64_t next_tag_ = 0, end_ = 1;
  std::size_t elements_ = 0;
  std::array<Element, 4> data_{};
};

// The bytes of one number of a level-5 numeric data type; 0 for the others.
std::uint64_t mat_number_bytes(std::uint32_t type) {
  switch (type) {
    case 1:
    case 2:
      return 1;  // miINT8, miUINT8
    case 3:
    case 4:
      return 2;  // miINT16, miUINT16
    case 5:
    case 6:
    case 7:
      return 4;  // miINT32, miUINT32, miSINGLE
    case 9:
    case 12:
    case 13:
      return 8;  // miDOUBLE, miINT64, miUINT64
    default:
      return 0;
  }
}

struct Level5Reader {
  const std::string& path;
  bool swapped;

  std::uint32_t word(const unsigned char* bytes) const {
    std::uint32_t v = 0;
    for (int i = 0; i < 4; ++i) v |= std::uint32_t(bytes[swapped ? 3 - i : i]) << (8 * i);
    return v;
  }

  [[noreturn]] void fail(std::uint64_t offset, const std::string& what) const {
    throw FileError(path, "variable at byte " + std::to_string(offset) + ": " + what);
  }

  // Checks the head of a matrix (its array flags, dimensions and name), whose
  // sizes matio allocates before anything else, against `size`, the bytes of
  // the matrix after its tag; `head` holds its first bytes. Returns the class.
  std::uint32_t check_matrix_head(std::uint64_t offset, const unsigned char* head,
                                  std::size_t head_size, std::uint64_t size) const {
    if (head_size < 24 || size < 24) fail(offset, "a matrix too short for its array flags");
    if (word(head) != kMiUint32 || word(head + 4) != 8)
      fail(offset, "a matrix whose array flags are damaged");
    const std::uint32_t matrix_class = word(head + 8) & 0xff;
    // Cell arrays, structures and objects nest further matrices, each with a
    // head of its own that matio sizes allocations from: no ground truth
    // needs them.
    if (matrix_class < kMxFirstPlainClass || matrix_class > kMxLastPlainClass)
      fail(offset, "a cell array, structure, object or other nested variable (class " +
                       std::to_string(matrix_class) + "); save the ground truth alone");
    if (word(head + 16) != kMiInt32) fail(offset, "a matrix whose dimensions are damaged");
    const std::uint64_t dimension_bytes = word(head + 20);
    if (dimension_bytes < 8 || dimension_bytes % 4 != 0 ||
        dimension_bytes > kMaxMatDimensionBytes || 24 + dimension_bytes > size)
      fail(offset, "a matrix declaring " + std::to_string(dimension_bytes) +
                       " bytes of dimensions (8 to 128 expected)");
    if (24 + dimension_bytes > head_size) fail(offset, "a matrix cut inside its dimensions");
    // matio allocates, and this reader visits, every cell of a dense matrix
    // (numbers, characters, cells of a cell array) and every column of a
    // sparse one: each takes at least a byte, or 4, of the file.
    std::uint64_t cells = 1;
    for (std::uint64_t at = 24; at < 24 + dimension_bytes; at += 4) {
      const std::uint64_t extent = word(head + at);
      cells = extent != 0 && cells > size / extent ? size + 1 : cells * extent;
    }
    const std::uint64_t columns = dimension_bytes >= 8 ? word(head + 28) : 0;
    if (matrix_class != kMxSparseClass && cells > size)
      fail(offset,
           "a matrix declaring more cells than its " + std::to_string(size) + " bytes hold");
    if (matrix_class == kMxSparseClass && (columns + 1) * 4 > size)
      fail(offset, "a sparse matrix declaring more columns than its " + std::to_string(size) +
                       " bytes hold");
    const std::uint64_t name_at = 24 + (dimension_bytes + 7) / 8 * 8;
    if (name_at + 8 > head_size || name_at + 8 > size) fail(offset, "a matrix with no name");
    const std::uint32_t name_tag = word(head + name_at);
    if ((name_tag >> 16) == 0) {  // not a small data element: a length of its own
      const std::uint64_t name_bytes = word(head + name_at + 4);
      if (name_tag != kMiInt8 || name_bytes > kMaxMatNameBytes || name_at + 8 + name_bytes > size)
        fail(offset, "a matrix whose name declares " + std::to_string(name_bytes) + " bytes");
    }
    return matrix_class;
  }

  bool is_complex(const unsigned char* head) const { return (word(head + 8) & 0x0800) != 0; }

  // The elements a sparse matrix needs after its array flags, dimensions and
  // name. matio allocates its row indices, column starts and values from
  // their own tags; it reads a missing one from whatever follows the matrix
  // (found by fuzzing: a 232-byte file whose missing column starts became a
  // 4 GiB allocation), and it steps over an element by the numbers it read,
  // not by the bytes its tag declares, so a type or size that disagrees
  // sends it reading the next tag from inside the data (found next: row
  // indices typed as bytes, then 1.7 GB of values).
  void check_sparse_elements(std::uint64_t offset, bool complex, const ElementChain& chain) const {
    const std::size_t needed = complex ? 4 : 3;
    if (chain.data_elements() < needed)
      fail(offset, "a sparse matrix holding " + std::to_string(chain.data_elements()) + " of the " +
                       std::to_string(needed) +
                       " elements it needs (row indices, column starts, values)");
    for (std::size_t i = 0; i < needed; ++i) {
      const auto& element = chain.data_element(i);
      const std::uint64_t number_bytes = mat_number_bytes(element.type);
      const bool index = i < 2;
      if (number_bytes == 0 || (index && number_bytes != 4) || element.bytes % number_bytes != 0)
        fail(offset, std::string("a sparse matrix whose ") +
                         (i == 0   ? "row indices"
                          : i == 1 ? "column starts"
                                   : "values") +
                         " have type " + std::to_string(element.type) + " and " +
                         std::to_string(element.bytes) + " bytes" +
                         (index ? " (32-bit integers expected)" : ""));
    }
  }

  // Inflates a compressed variable once, keeping only its first bytes:
  // matio would read a damaged stream as zeros, or size arrays from it.
  void check_compressed(std::ifstream& in, std::uint64_t offset, std::uint64_t bytes) const {
    z_stream stream{};
    if (inflateInit(&stream) != Z_OK) fail(offset, "cannot start zlib");
    std::unique_ptr<z_stream, int (*)(z_streamp)> guard(&stream, inflateEnd);
    std::vector<unsigned char> input(64 << 10), output(64 << 10);
    unsigned char head[512];
    std::size_t head_size = 0;
    ElementChain chain(path, offset);
    unsigned char tag[8];
    std::size_t tag_size = 0;
    std::uint64_t inflated = 0, left = bytes;
    int status = Z_OK;
    in.seekg(static_cast<std::streamoff>(offset + 8));
    while (status != Z_STREAM_END) {
      if (stream.avail_in == 0) {
        if (left == 0) fail(offset, "a compressed variable that ends before its zlib stream");
        const auto chunk = static_cast<std::size_t>(std::min<std::uint64_t>(left, input.size()));
        if (!in.read(reinterpret_cast<char*>(input.data()), static_cast<std::streamsize>(chunk)))
          fail(offset, "a compressed variable cut short");
        left -= chunk;
        stream.next_in = input.data();
        stream.avail_in = static_cast<uInt>(chunk);
      }
      stream.next_out = output.data();
      stream.avail_out = static_cast<uInt>(output.size());
      status = inflate(&stream, Z_NO_FLUSH);
      if (status != Z_OK && status != Z_STREAM_END)
        fail(offset, "a compressed variable whose zlib stream is damaged");
      const std::size_t produced = output.size() - stream.avail_out;
      for (std::size_t i = 0; i < produced && !chain.done();) {
        const std::uint64_t wanted = chain.next_tag() + tag_size;  // the next tag byte
        if (wanted >= inflated + produced) break;
        if (wanted > inflated + i) {
          i = static_cast<std::size_t>(wanted - inflated);
          continue;
        }
        tag[tag_size++] = output[i++];
        if (tag_size == sizeof tag) {
          chain.on_tag(word(tag), word(tag + 4));
          tag_size = 0;
        }
      }
      const std::size_t kept = std::min(produced, sizeof head - head_size);
      std::memcpy(head + head_size, output.data(), kept);
      head_size += kept;
      inflated += produced;
      if (inflated > kMaxMatInflatedBytes)
        fail(offset, "a compressed variable expanding beyond " +
                         std::to_string(kMaxMatInflatedBytes) + " bytes");
    }
    if (left != 0 || stream.avail_in != 0)
      fail(offset, "a compressed variable with bytes after its zlib stream");
    if (head_size < 8 || word(head) != kMiMatrix)
      fail(offset, "a compressed variable that holds no matrix");
    const std::uint64_t size = word(head + 4);
    if (8 + size > inflated) fail(offset, "a compressed matrix longer than its zlib stream");
    const std::uint32_t matrix_class = check_matrix_head(offset, head + 8, head_size - 8, size);
    if (!chain.done()) fail(offset, "a compressed matrix whose last element is cut short");
    if (matrix_class == kMxSparseClass) check_sparse_elements(offset, is_complex(head + 8), chain);
    const std::uint64_t sparse_limit =
        std::max(kMinSparseInflatedLimit, kMaxSparseExpansion * bytes);
    if (matrix_class == kMxSparseClass && inflated > sparse_limit)
      fail(offset, "a compressed sparse matrix expanding " + std::to_string(inflated) +
                       " bytes, more than " + std::to_string(sparse_limit));
  }
};

// matio reads a truncated compressed variable as zeros without complaint, and
// sizes its allocations from the headers of a variable, so the level-5
// element chain is walked first: every element is a matrix or a compressed
// matrix that fits in the file, with a plausible head, and every compressed
// one inflates to what it declares.
void check_level5_elements(const std::string& path) {
  std::ifstream in(path, std::ios::binary | std::ios::ate);
  if (!in) throw FileError(path, std::string("cannot open: ") + std::strerror(errno));
  const std::uint64_t size = static_cast<std::uint64_t>(in.tellg());
  unsigned char header[128];
  in.seekg(0);
  if (size < 128 || !in.read(reinterpret_cast<char*>(header), 128))
    throw FileError(path, "too short for a MATLAB .mat file");
  const bool swapped = header[126] == 'M' && header[127] == 'I';
  if (!swapped && !(header[126] == 'I' && header[127] == 'M'))
    throw FileError(path, "not a MATLAB level-5 .mat file (bad endian indicator)");
  // The version field, not the header's text, decides how matio reads the
  // file (found by fuzzing: a level-5 file whose text said "MATLAB 7.3").
  const unsigned version =
      swapped ? header[124] << 8 | header[125] : header[125] << 8 | header[124];
  if (version == 0x0200) return;  // 7.3: HDF5 inside, which matio checks
  // matio reads any other version as a level-4 file from byte 0, allocating
  // a name as long as bytes 16-19 say (found by fuzzing: 744 MB).
  if (version != 0x0100) {
    char hex[8];
    std::snprintf(hex, sizeof hex, "0x%04x", version);
    throw FileError(path, std::string("unsupported .mat header version ") + hex +
                              "; binbow reads level-5 files (version 0x0100, MATLAB's "
                              "-v6 and -v7) and -v7.3 files (0x0200)");
  }
  const Level5Reader reader{path, swapped};
  std::uint64_t offset = 128;
  while (offset < size) {
    unsigned char tag[8];
    in.seekg(static_cast<std::streamoff>(offset));
    if (size - offset < 8 || !in.read(reinterpret_cast<char*>(tag), 8))
      throw FileError(path, "truncated: incomplete element tag at byte " + std::to_string(offset));
    const std::uint32_t type = reader.word(tag);
    const std::uint64_t bytes = reader.word(tag + 4);
    if (type != kMiMatrix && type != kMiCompressed)
      throw FileError(path, "element at byte " + std::to_string(offset) + " has type " +
                                std::to_string(type) + ", not a variable");
    const std::uint64_t end = offset + 8 + bytes;
    if (end > size)
      throw FileError(path, "truncated: element at byte " + std::to_string(offset) + " needs " +
                                std::to_string(bytes) + " bytes, file ends after " +
                                std::to_string(size - offset - 8));
    if (type == kMiCompressed) {
      reader.check_compressed(in, offset, bytes);
    } else {
      unsigned char head[512];
      const auto head_size = static_cast<std::size_t>(std::min<std::uint64_t>(bytes, sizeof head));
      if (!in.read(reinterpret_cast<char*>(head), static_cast<std::streamsize>(head_size)))
        throw FileError(path, "truncated variable at byte " + std::to_string(offset));
      const std::uint32_t matrix_class = reader.check_matrix_head(offset, head, head_size, bytes);
      ElementChain chain(path, offset);
      while (!chain.done()) {
        const std::uint64_t at = offset + chain.next_tag();
        in.seekg(static_cast<std::streamoff>(at));
        if (at + 8 > end || !in.read(reinterpret_cast<char*>(tag), 8))
          throw FileError(path, "variable at byte " + std::to_string(offset) +
                                    ": an element cut short at byte " + std::to_string(at));
        chain.on_tag(reader.word(tag), reader.word(tag + 4));
      }
      if (matrix_class == kMxSparseClass)
        reader.check_sparse_elements(offset, reader.is_complex(head), chain);
    }
    offset = type == kMiCompressed ? end : (end + 7) / 8 * 8;  // compressed ones are not padded
  }
}

Loaded from_mat(const std::string& path, const GroundTruthOptions& options) {
  check_level5_elements(path);
  std::unique_ptr<mat_t, MatCloser> file(Mat_Open(path.c_str(), MAT_ACC_RDONLY));
  if (!file) throw FileError(path, "not a readable MATLAB .mat file");
  std::unique_ptr<matvar_t, VarFreer> var;
  while (true) {
    var.reset(Mat_VarReadNextInfo(file.get()));
    if (!var) throw FileError(path, "no two-dimensional numeric or logical variable");
    if (var->rank == 2 && var->dims != nullptr && var->class_type != MAT_C_CHAR &&
        var->class_type != MAT_C_CELL && var->class_type != MAT_C_STRUCT &&
        var->class_type != MAT_C_OBJECT && var->class_type != MAT_C_FUNCTION &&
        var->class_type != MAT_C_OPAQUE && var->class_type != MAT_C_EMPTY && !var->isComplex)
      break;
  }
  const std::string name = var->name != nullptr ? var->name : "?";
  const std::size_t rows = var->dims[0], columns = var->dims[1];
  if (rows > kMaxFrames || columns > kMaxFrames)
    throw FileError(path, "variable '" + name + "' is " + std::to_string(rows) + "x" +
                              std::to_string(columns) + ", too large for a ground truth");
  Loaded loaded;
  loaded.frames = cut_to_run(std::max(rows, columns), options);
  LaterEarlier& pairs = loaded.pairs;
  // Cells beyond the run's frames are not read at all.
  const std::size_t rows_read = std::min(rows, loaded.frames);
  const std::size_t columns_read = std::min(columns, loaded.frames);
  if (var->class_type == MAT_C_SPARSE) {
    if (Mat_VarReadDataAll(file.get(), var.get()) != 0 || var->data == nullptr)
      throw FileError(path, "cannot read sparse variable '" + name + "'");
    const auto* sparse = static_cast<const mat_sparse_t*>(var->data);
    if (sparse->jc == nullptr || sparse->ir == nullptr ||
        sparse->njc != static_cast<decltype(sparse->njc)>(columns + 1))
      throw FileError(path, "damaged sparse variable '" + name + "'");
    for (std::size_t c = 0; c < columns_read; ++c) {
      const std::size_t begin = sparse->jc[c], end = sparse->jc[c + 1];
      if (begin > end || end > static_cast<std::size_t>(sparse->nir))
        throw FileError(path, "damaged sparse variable '" + name + "'");
      // A stored zero is not a loop, but logical sparse matrices store no values worth checking.
      for (std::size_t k = begin; k < end; ++k) {
        if (static_cast<std::size_t>(sparse->ir[k]) >= rows)
          throw FileError(path, "damaged sparse variable '" + name + "'");
        add_pair(static_cast<std::size_t>(sparse->ir[k]), c, loaded.frames, pairs);
      }
    }
  } else {
    std::size_t cell_bytes = 0;
    switch (var->class_type) {
      case MAT_C_DOUBLE:
      case MAT_C_INT64:
      case MAT_C_UINT64:
        cell_bytes = 8;
        break;
      case MAT_C_SINGLE:
      case MAT_C_INT32:
      case MAT_C_UINT32:
        cell_bytes = 4;
        break;
      case MAT_C_INT16:
      case MAT_C_UINT16:
        cell_bytes = 2;
        break;
      case MAT_C_INT8:
      case MAT_C_UINT8:
        cell_bytes = 1;
        break;
      default:
        throw FileError(path, "variable '" + name + "' has an unsupported class");
    }
    const std::size_t block_columns =
        std::max<std::size_t>(1, kMatBlockBytes / std::max<std::size_t>(1, rows_read * cell_bytes));
    std::vector<std::uint8_t> buffer;
    for (std::size_t first = 0; rows_read > 0 && first < columns_read; first += block_columns) {
      const std::size_t count = std::min(block_columns, columns_read - first);
      buffer.assign(rows_read * count * cell_bytes, 0);
      int start[2] = {0, static_cast<int>(first)};
      int stride[2] = {1, 1};
      int edge[2] = {static_cast<int>(rows_read), static_cast<int>(count)};
      if (Mat_VarReadData(file.get(), var.get(), buffer.data(), start, stride, edge) != 0)
        throw FileError(path, "cannot read variable '" + name + "' (truncated or damaged)");
      const std::size_t f = loaded.frames;
      switch (var->class_type) {
        case MAT_C_DOUBLE:
          collect_nonzero<double>(buffer.data(), rows_read, first, count, f, pairs);
          break;
        case MAT_C_SINGLE:
          collect_nonzero<float>(buffer.data(), rows_read, first, count, f, pairs);
          break;
        case MAT_C_INT64:
        case MAT_C_UINT64:
          collect_nonzero<std::uint64_t>(buffer.data(), rows_read, first, count, f, pairs);
          break;
        case MAT_C_INT32:
        case MAT_C_UINT32:
          collect_nonzero<std::uint32_t>(buffer.data(), rows_read, first, count, f, pairs);
          break;
        case MAT_C_INT16:
        case MAT_C_UINT16:
          collect_nonzero<std::uint16_t>(buffer.data(), rows_read, first, count, f, pairs);
          break;
        default:
          collect_nonzero<std::uint8_t>(buffer.data(), rows_read, first, count, f, pairs);
          break;
      }
    }
  }
  return loaded;
}

int detect_index_base(const std::string& text) {
  std::istringstream lines(text);
  std::string line;
  bool zero_seen = false;
  while (std::getline(lines, line)) {
    const std::size_t start = line.find_first_not_of(" \t\r");
    if (start == std::string::npos) continue;
    if (line[start] == '#') {
      const std::string l = lower(line);
      if (l.find("1-based") != std::string::npos) return 1;
      if (l.find("0-based") != std::string::npos) return 0;
      continue;
    }
    for (std::size_t i = start; i < line.size(); ++i) {
      const bool boundary_before = i == 0 || !std::isdigit(static_cast<unsigned char>(line[i - 1]));
      const bool boundary_after =
          i + 1 == line.size() || !std::isdigit(static_cast<unsigned char>(line[i + 1]));
      if (line[i] == '0' && boundary_before && boundary_after) zero_seen = true;
    }
  }
  return zero_seen ? 0 : -1;
}

Loaded from_pairs_text(const std::string& path, const GroundTruthOptions& options) {
  const std::string text = read_text(path);
  int base = options.pairs_index_base;
  if (base != 0 && base != 1) {
    base = detect_index_base(text);
    if (base < 0)
      throw FileError(path,
                      "cannot tell whether the pairs are 0-based or 1-based: "
                      "add a comment line saying \"0-based\" or \"1-based\", or give the base");
  }
  Loaded loaded;
  std::size_t frames = 0, line_number = 0;
  std::istringstream lines(text);
  std::string line;
  while (std::getline(lines, line)) {
    ++line_number;
    const std::size_t start = line.find_first_not_of(" \t\r");
    if (start == std::string::npos || line[start] == '#') continue;
    for (char& c : line)
      if (c == ',' || c == ';' || c == '\t' || c == '\r') c = ' ';
    std::istringstream fields(line);
    std::string a, b, extra;
    fields >> a >> b;
    const auto parse = [&](const std::string& s) -> std::size_t {
      if (s.empty() || s.size() > 12 || !std::all_of(s.begin(), s.end(), [](char c) {
            return std::isdigit(static_cast<unsigned char>(c)) != 0;
          }))
        throw FileError(path, "line " + std::to_string(line_number) +
                                  ": expected two non-negative indices \"query match\"");
      const std::size_t v = std::strtoull(s.c_str(), nullptr, 10);
      if (v < static_cast<std::size_t>(base) || v - base >= kMaxFrames)
        throw FileError(path, "line " + std::to_string(line_number) + ": index " + s +
                                  " out of range for " + std::to_string(base) + "-based pairs");
      return v - base;
    };
    const std::size_t query = parse(a), match = parse(b);
    if (fields >> extra)
      throw FileError(path, "line " + std::to_string(line_number) + ": more than two fields");
    // Without the run's frame count, the largest index says how many there are.
    add_pair(query, match, options.frames > 0 ? options.frames : kMaxFrames, loaded.pairs);
    frames = std::max({frames, query + 1, match + 1});
  }
  loaded.frames = options.frames > 0 ? options.frames : frames;
  return loaded;
}

std::string csv_field(const std::string& s) {
  if (s.find_first_of(",\"\r\n") == std::string::npos) return s;
  std::string quoted = "\"";
  for (char c : s) quoted += c == '"' ? std::string("\"\"") : std::string(1, c);
  return quoted + "\"";
}

// Splits one CSV record (RFC 4180) starting at `pos`; advances `pos` past it.
bool next_record(const std::string& text, std::size_t& pos, std::vector<std::string>& fields,
                 bool& malformed) {
  fields.clear();
  malformed = false;
  if (pos >= text.size()) return false;
  std::string field;
  bool quoted = false, in_quotes = false;
  while (pos < text.size()) {
    const char c = text[pos++];
    if (in_quotes) {
      if (c == '"') {
        if (pos < text.size() && text[pos] == '"') {
          field += '"';
          ++pos;
        } else {
          in_quotes = false;
        }
      } else {
        field += c;
      }
    } else if (c == '"') {
      if (!field.empty() || quoted) malformed = true;
      in_quotes = quoted = true;
    } else if (c == ',') {
      fields.push_back(std::move(field));
      field.clear();
      quoted = false;
    } else if (c == '\n') {
      break;
    } else if (c != '\r') {
      if (quoted) malformed = true;
      field += c;
    }
  }
  if (in_quotes) malformed = true;
  fields.push_back(std::move(field));
  return true;
}

}  // namespace

GroundTruth::GroundTruth(std::size_t frames,
                         const std::vector<std::pair<std::size_t, std::size_t>>& pairs) {
  if (frames > kMaxFrames) throw InvalidArgument("ground truth too large");
  LaterEarlier later_earlier;
  later_earlier.reserve(pairs.size());
  for (const auto& [a, b] : pairs) {
    if (a >= frames || b >= frames)
      throw InvalidArgument("ground-truth pair (" + std::to_string(a) + ", " + std::to_string(b) +
                            ") outside " + std::to_string(frames) + " frames");
    add_pair(a, b, frames, later_earlier);
  }
  *this = from_later_earlier(frames, std::move(later_earlier));
}

GroundTruth GroundTruth::from_later_earlier(std::size_t frames, LaterEarlier pairs) {
  if (!std::is_sorted(pairs.begin(), pairs.end())) std::sort(pairs.begin(), pairs.end());
  pairs.erase(std::unique(pairs.begin(), pairs.end()), pairs.end());
  GroundTruth truth;
  truth.frames_ = frames;
  truth.later_.reserve(pairs.size());
  truth.earlier_.reserve(pairs.size());
  for (const auto& [later, earlier] : pairs) {
    if (truth.later_.empty() || truth.later_.back() != later) ++truth.queries_with_loops_;
    truth.later_.push_back(later);
    truth.earlier_.push_back(earlier);
  }
  return truth;
}

GroundTruth GroundTruth::load(const std::string& path, const GroundTruthOptions& options) {
  const std::string name = lower(path);
  try {
    require_regular_file(path);
    Loaded loaded;
    bool image = false;
    for (const char* ext : {".bmp", ".png", ".pgm", ".pbm", ".tif", ".tiff", ".jpg", ".jpeg"})
      image = image || ends_with(name, ext);
    if (image) {
      loaded = from_image(path, options);
    } else if (ends_with(name, ".mat")) {
      loaded = from_mat(path, options);
    } else {
      loaded = from_pairs_text(path, options);
    }
    return from_later_earlier(loaded.frames, std::move(loaded.pairs));
  } catch (const InvalidArgument& e) {
    throw FileError(path, e.what());
  }
}

bool GroundTruth::is_loop(std::size_t query, std::size_t match) const {
  const std::size_t later = std::max(query, match), earlier = std::min(query, match);
  if (later >= frames_ || later == earlier) return false;
  const Span<std::uint32_t> m = earlier_matches(later);
  return std::binary_search(m.begin(), m.end(), static_cast<std::uint32_t>(earlier));
}

bool GroundTruth::has_loop(std::size_t query) const {
  return !earlier_matches(query).empty();
}

std::vector<std::size_t> GroundTruth::loop_queries() const {
  std::vector<std::size_t> queries;
  queries.reserve(queries_with_loops_);
  for (const std::uint32_t later : later_)
    if (queries.empty() || queries.back() != later) queries.push_back(later);
  return queries;
}

Span<std::uint32_t> GroundTruth::earlier_matches(std::size_t query) const {
  if (query >= frames_) return {};
  const auto [first, last] =
      std::equal_range(later_.begin(), later_.end(), static_cast<std::uint32_t>(query));
  const auto offset = static_cast<std::size_t>(first - later_.begin());
  return {earlier_.data() + offset, static_cast<std::size_t>(last - first)};
}

std::string format_detections_csv(const std::vector<Detection>& detections) {
  std::ostringstream out;
  out << "query_index,match_index,query_file,match_file,score,inliers\n";
  char score[64];
  for (const Detection& d : detections) {
    std::snprintf(score, sizeof score, "%.9g", d.score);
    out << d.query << ',' << d.match << ',' << csv_field(d.query_file) << ','
        << csv_field(d.match_file) << ',' << score << ',' << d.inliers << '\n';
  }
  return out.str();
}

void write_detections_csv(const std::string& path, const std::vector<Detection>& detections) {
  const std::string text = format_detections_csv(detections);
  detail::write_file_atomically(path, text.data(), text.size());
}

std::vector<Detection> read_detections_csv(const std::string& path) {
  const std::string text = read_text(path);
  std::size_t pos = 0, line = 0;
  std::vector<std::string> fields;
  bool malformed = false;
  if (!next_record(text, pos, fields, malformed) ||
      fields != std::vector<std::string>{"query_index", "match_index", "query_file", "match_file",
                                         "score", "inliers"})
    throw FileError(path,
                    "line 1: expected the header "
                    "query_index,match_index,query_file,match_file,score,inliers");
  ++line;
  std::vector<Detection> detections;
  // One row per line at most: reserving once avoids the doubling's spare half.
  detections.reserve(static_cast<std::size_t>(std::count(
                         text.begin() + static_cast<std::ptrdiff_t>(pos), text.end(), '\n')) +
                     1);
  while (next_record(text, pos, fields, malformed)) {
    ++line;
    if (fields.size() == 1 && fields[0].empty()) continue;
    const std::string where = "line " + std::to_string(line) + ": ";
    if (malformed || fields.size() != 6)
      throw FileError(path, where + "expected 6 comma-separated fields");
    const auto index = [&](const std::string& s) -> std::size_t {
      if (s.empty() || s.size() > 12 || !std::all_of(s.begin(), s.end(), [](char c) {
            return std::isdigit(static_cast<unsigned char>(c)) != 0;
          }))
        throw FileError(path, where + "\"" + s + "\" is not a non-negative index");
      return std::strtoull(s.c_str(), nullptr, 10);
    };
    Detection d;
    d.query = index(fields[0]);
    d.match = index(fields[1]);
    d.query_file = fields[2];
    d.match_file = fields[3];
    char* end = nullptr;
    d.score = std::strtod(fields[4].c_str(), &end);
    if (fields[4].empty() || end != fields[4].c_str() + fields[4].size() || !std::isfinite(d.score))
      throw FileError(path, where + "score \"" + fields[4] + "\" is not a finite number");
    d.inliers = index(fields[5]);
    detections.push_back(std::move(d));
  }
  detections.shrink_to_fit();
  return detections;
}

namespace {

void check_inside(const Detection& d, const GroundTruth& truth) {
  if (d.query >= truth.frames() || d.match >= truth.frames())
    throw InvalidArgument("detection (" + std::to_string(d.query) + ", " + std::to_string(d.match) +
                          ") outside the ground truth's " + std::to_string(truth.frames()) +
                          " frames");
}

// A true positive that also finds its query: the loop is with an earlier image.
bool finds_query(const Detection& d, const GroundTruth& truth) {
  return d.match < d.query && truth.is_loop(d.query, d.match);
}

void set_ratios(PrecisionRecall& r) {
  r.precision = r.detections == 0 ? 1.0 : double(r.true_positives) / double(r.detections);
  r.recall =
      r.queries_with_loops == 0 ? 0.0 : double(r.queries_found) / double(r.queries_with_loops);
}

}  // namespace

PrecisionRecall evaluate_detections(const std::vector<Detection>& detections,
                                    const GroundTruth& truth) {
  PrecisionRecall r;
  r.queries_with_loops = truth.queries_with_loops();
  std::vector<std::size_t> found;  // queries with a true positive, repeated
  for (const Detection& d : detections) {
    check_inside(d, truth);
    ++r.detections;
    if (truth.is_loop(d.query, d.match)) {
      ++r.true_positives;
      if (d.match < d.query) found.push_back(d.query);
    } else {
      ++r.false_positives;
    }
  }
  std::sort(found.begin(), found.end());
  r.queries_found =
      static_cast<std::size_t>(std::unique(found.begin(), found.end()) - found.begin());
  set_ratios(r);
  return r;
}

double recall_at_full_precision(const std::vector<PrCurvePoint>& curve) {
  double best = 0;
  for (const PrCurvePoint& p : curve)
    if (p.result.detections > 0 && p.result.false_positives == 0)
      best = std::max(best, p.result.recall);
  return best;
}

std::vector<PrCurvePoint> pr_curve_by_score(const std::vector<Detection>& detections,
                                            const GroundTruth& truth) {
  for (const Detection& d : detections) {
    check_inside(d, truth);
    if (std::isnan(d.score)) throw InvalidArgument("detection with a NaN score");
  }
  // Detections by decreasing score: lowering the threshold t adds them in this order.
  std::vector<const Detection*> order;
  order.reserve(detections.size());
  for (const Detection& d : detections) order.push_back(&d);
  std::sort(order.begin(), order.end(),
            [](const Detection* a, const Detection* b) { return a->score > b->score; });
  // A query is found at t once its best-scoring detection that finds it is kept.
  std::vector<std::pair<std::size_t, double>> finding;  // (query, score)
  for (const Detection& d : detections)
    if (finds_query(d, truth)) finding.emplace_back(d.query, d.score);
  std::sort(finding.begin(), finding.end(), [](const auto& a, const auto& b) {
    return a.first != b.first ? a.first < b.first : a.second > b.second;
  });
  std::vector<double> found_at;  // per found query, the highest t that finds it; decreasing
  for (std::size_t i = 0; i < finding.size(); ++i)
    if (i == 0 || finding[i].first != finding[i - 1].first) found_at.push_back(finding[i].second);
  std::sort(found_at.begin(), found_at.end(), std::greater<>());

  std::vector<PrCurvePoint> curve;
  PrecisionRecall r;
  r.queries_with_loops = truth.queries_with_loops();
  std::size_t next_found = 0;
  for (std::size_t i = 0; i < order.size();) {
    const double t = order[i]->score;
    for (; i < order.size() && order[i]->score == t; ++i) {
      ++r.detections;
      ++(truth.is_loop(order[i]->query, order[i]->match) ? r.true_positives : r.false_positives);
    }
    while (next_found < found_at.size() && found_at[next_found] >= t) ++next_found;
    r.queries_found = next_found;
    set_ratios(r);
    curve.push_back({t, r});
  }
  std::reverse(curve.begin(), curve.end());
  return curve;
}

}  // namespace binbow::loop
