#include <algorithm>
#include <array>
#include <cerrno>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <memory>
#include <string>
#include <vector>

#include <matio.h>
#include <zlib.h>

#include "binbow/error.h"
#include "loop/evaluation/ground_truth_readers.h"
#include "loop/evaluation/mat_zlib_stream.h"
#include "vision/media_module.h"

namespace binbow::loop::detail {
namespace {

constexpr std::size_t kMaxFrames = kMaxGroundTruthFrames;
// Dense .mat matrices are read this many cells at a time.
constexpr std::size_t kMatBlockBytes = std::size_t{128} << 20;

// Cells of a dense block as "non-zero?", whatever the MATLAB class.
// Column by column, rows increasing: the order RunCollector keeps compact.
template <class T>
void collect_nonzero(const void* data, std::size_t rows, std::size_t first_column,
                     std::size_t columns, RunCollector& runs) {
  const T* cells = static_cast<const T*>(data);
  for (std::size_t c = 0; c < columns; ++c)
    for (std::size_t r = 0; r < rows; ++r)
      if (cells[c * rows + r] != T(0)) runs.add(first_column + c, r);
}

struct MatCloser {
  void operator()(mat_t* m) const { vision::media_module().mat_close(m); }
};
struct VarFreer {
  void operator()(matvar_t* v) const { vision::media_module().mat_var_free(v); }
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
  // Where data element i's bytes start (after its tag, or inside a small one's).
  std::uint64_t data_position(std::size_t i) const { return data_at_[i]; }

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
      if (data_elements() < data_.size()) {
        data_[data_elements()] = {first & 0xffff, bytes};
        data_at_[data_elements()] = next_tag_ + (small ? 4 : 8);
      }
      next_tag_ += small ? 8 : 8 + (bytes + 7) / 8 * 8;
    }
    ++elements_;
  }

 private:
  const std::string& path_;
  std::uint64_t offset_;
  std::uint64_t next_tag_ = 0, end_ = 1;
  std::size_t elements_ = 0;
  std::array<Element, 4> data_{};
  std::array<std::uint64_t, 4> data_at_{};
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

// Where a variable lies in the file, as the element walk found it: what the
// single-pass reader of a compressed dense matrix needs.
struct VariableLayout {
  std::uint64_t offset = 0;  // of its tag in the file
  std::uint64_t bytes = 0;   // after the tag
  bool compressed = false;
  bool swapped = false;  // big-endian numbers
  // The real part, first data element: its level-5 type, bytes, and position
  // in the variable's (inflated) stream.
  ElementChain::Element real{};
  std::uint64_t real_at = 0;
};

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
  void check_compressed(std::ifstream& in, std::uint64_t offset, std::uint64_t bytes,
                        VariableLayout& layout) const {
    in.seekg(static_cast<std::streamoff>(offset + 8));
    MatZlibStream stream(in, path, offset, bytes, 64 << 10, 64 << 10);
    unsigned char head[512];
    std::size_t head_size = 0;
    ElementChain chain(path, offset);
    unsigned char tag[8];
    std::size_t tag_size = 0;
    while (!stream.ended()) {
      stream.next();
      const unsigned char* output = stream.piece();
      const std::size_t produced = stream.piece_size();
      const std::uint64_t inflated = stream.piece_start();
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
      std::memcpy(head + head_size, output, kept);
      head_size += kept;
      if (stream.inflated() > kMaxMatInflatedBytes)
        fail(offset, "a compressed variable expanding beyond " +
                         std::to_string(kMaxMatInflatedBytes) + " bytes");
    }
    if (stream.trailing_bytes())
      fail(offset, "a compressed variable with bytes after its zlib stream");
    const std::uint64_t inflated = stream.inflated();
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
    if (chain.data_elements() > 0) {
      layout.real = chain.data_element(0);
      layout.real_at = chain.data_position(0);
    }
  }
};

// matio reads a truncated compressed variable as zeros without complaint, and
// sizes its allocations from the headers of a variable, so the level-5
// element chain is walked first: every element is a matrix or a compressed
// matrix that fits in the file, with a plausible head, and every compressed
// one inflates to what it declares.
std::vector<VariableLayout> check_level5_elements(const std::string& path) {
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
  if (version == 0x0200) return {};  // 7.3: HDF5 inside, which matio checks
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
  std::vector<VariableLayout> layouts;
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
    VariableLayout& layout = layouts.emplace_back();
    layout.offset = offset;
    layout.bytes = bytes;
    layout.compressed = type == kMiCompressed;
    layout.swapped = swapped;
    if (type == kMiCompressed) {
      reader.check_compressed(in, offset, bytes, layout);
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
  return layouts;
}

// Reads the cells of a compressed dense matrix in one pass over its zlib
// stream (matio inflates a compressed variable from its start for every
// block it is asked for, so a large matrix read block by block costs passes
// growing with its size). Cells are column by column, rows increasing;
// non-zero cells within rows_read × columns_read go to `runs`.
void read_compressed_dense(const std::string& path, const VariableLayout& layout, std::size_t rows,
                           std::size_t columns, std::size_t rows_read, std::size_t columns_read,
                           RunCollector& runs) {
  const auto fail = [&](const std::string& what) {
    throw FileError(path, "variable at byte " + std::to_string(layout.offset) + ": " + what);
  };
  const std::uint64_t number_bytes = mat_number_bytes(layout.real.type);
  if (number_bytes == 0 || layout.real.bytes != std::uint64_t{rows} * columns * number_bytes)
    fail("a dense matrix whose " + std::to_string(layout.real.bytes) + " bytes of type " +
         std::to_string(layout.real.type) + " do not hold its " + std::to_string(rows) + "x" +
         std::to_string(columns) + " cells");
  // A cell is zero when all its bytes are, but for the sign bit of a
  // floating-point number (-0.0 is zero; NaN is not).
  const bool floating = layout.real.type == 7 || layout.real.type == 9;
  const std::size_t sign_byte = layout.swapped ? 0 : number_bytes - 1;
  const auto nonzero = [&](const unsigned char* cell) {
    for (std::size_t i = 0; i < number_bytes; ++i) {
      const unsigned char byte =
          floating && i == sign_byte ? static_cast<unsigned char>(cell[i] & 0x7f) : cell[i];
      if (byte != 0) return true;
    }
    return false;
  };
  std::ifstream in(path, std::ios::binary);
  in.seekg(static_cast<std::streamoff>(layout.offset + 8));
  MatZlibStream stream(in, path, layout.offset, layout.bytes, 256 << 10, 1 << 20);
  const std::uint64_t data_begin = layout.real_at;
  // Only the columns read: the stream is left once they are.
  const std::uint64_t data_end = data_begin + std::uint64_t{columns_read} * rows * number_bytes;
  unsigned char partial[8];
  std::size_t partial_size = 0;
  std::size_t row = 0, column = 0;
  constexpr std::size_t kNoStretch = SIZE_MAX;
  std::size_t stretch = kNoStretch;  // the first row of non-zero cells going on
  while (!stream.ended() && stream.inflated() < data_end) {
    stream.next();
    const std::uint64_t inflated = stream.piece_start();
    // The part of this piece inside the cells.
    const std::uint64_t from = std::max(inflated, data_begin);
    const std::uint64_t to = std::min(stream.inflated(), data_end);
    for (std::uint64_t at = from; at < to;) {
      const unsigned char* bytes = stream.piece() + (at - inflated);
      const unsigned char* cell_bytes = bytes;
      if (partial_size > 0 || to - at < number_bytes - partial_size) {
        const auto take =
            static_cast<std::size_t>(std::min<std::uint64_t>(number_bytes - partial_size, to - at));
        std::memcpy(partial + partial_size, bytes, take);
        partial_size += take;
        at += take;
        if (partial_size < number_bytes) break;
        cell_bytes = partial;
        partial_size = 0;
      } else {
        at += number_bytes;
      }
      // A stretch of non-zero cells in a column is added at once.
      if (row < rows_read && nonzero(cell_bytes)) {
        if (stretch == kNoStretch) stretch = row;
      } else if (stretch != kNoStretch) {
        runs.add_line(column, stretch, row);
        stretch = kNoStretch;
      }
      if (++row == rows) {
        if (stretch != kNoStretch) runs.add_line(column, stretch, std::min(rows, rows_read));
        stretch = kNoStretch;
        row = 0;
        ++column;
      }
    }
  }
  if (stream.inflated() < data_end) fail("a compressed matrix whose cells end early");
}

}  // namespace

LoadedGroundTruth read_ground_truth_mat(const std::string& path,
                                        const GroundTruthOptions& options) {
  const std::vector<VariableLayout> layouts = check_level5_elements(path);
  // matio comes with the image/video module: it links HDF5.
  const media::Api& matio = vision::media_module();
  std::unique_ptr<mat_t, MatCloser> file(matio.mat_open(path.c_str(), MAT_ACC_RDONLY));
  if (!file) throw FileError(path, "not a readable MATLAB .mat file");
  std::unique_ptr<matvar_t, VarFreer> var;
  // matio reads the variables in file order, as the element walk listed them.
  std::size_t index = 0;
  for (;; ++index) {
    var.reset(matio.mat_var_read_next_info(file.get()));
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
  LoadedGroundTruth loaded;
  loaded.frames = cut_to_run(std::max(rows, columns), options);
  RunCollector runs(loaded.frames);
  // Cells beyond the run's frames are not read at all.
  const std::size_t rows_read = std::min(rows, loaded.frames);
  const std::size_t columns_read = std::min(columns, loaded.frames);
  if (var->class_type == MAT_C_SPARSE) {
    if (matio.mat_var_read_data_all(file.get(), var.get()) != 0 || var->data == nullptr)
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
        runs.add(c, static_cast<std::size_t>(sparse->ir[k]));
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
    if (index < layouts.size() && layouts[index].compressed) {
      read_compressed_dense(path, layouts[index], rows, columns, rows_read, columns_read, runs);
      loaded.runs = runs.take();
      return loaded;
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
      if (matio.mat_var_read_data(file.get(), var.get(), buffer.data(), start, stride, edge) != 0)
        throw FileError(path, "cannot read variable '" + name + "' (truncated or damaged)");
      switch (var->class_type) {
        case MAT_C_DOUBLE:
          collect_nonzero<double>(buffer.data(), rows_read, first, count, runs);
          break;
        case MAT_C_SINGLE:
          collect_nonzero<float>(buffer.data(), rows_read, first, count, runs);
          break;
        case MAT_C_INT64:
        case MAT_C_UINT64:
          collect_nonzero<std::uint64_t>(buffer.data(), rows_read, first, count, runs);
          break;
        case MAT_C_INT32:
        case MAT_C_UINT32:
          collect_nonzero<std::uint32_t>(buffer.data(), rows_read, first, count, runs);
          break;
        case MAT_C_INT16:
        case MAT_C_UINT16:
          collect_nonzero<std::uint16_t>(buffer.data(), rows_read, first, count, runs);
          break;
        default:
          collect_nonzero<std::uint8_t>(buffer.data(), rows_read, first, count, runs);
          break;
      }
    }
  }
  loaded.runs = runs.take();
  return loaded;
}

}  // namespace binbow::loop::detail
