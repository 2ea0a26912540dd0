// Helpers shared by the test executables: where real data lives, temporary
// directories, random descriptors.
#pragma once

#include <cstdint>
#include <random>
#include <string>
#include <vector>

// Whether AddressSanitizer instruments this build (GCC defines
// __SANITIZE_ADDRESS__; clang answers __has_feature).
#if defined(__SANITIZE_ADDRESS__)
#define BINBOW_TEST_ASAN 1
#elif defined(__has_feature)
#if __has_feature(address_sanitizer)
#define BINBOW_TEST_ASAN 1
#endif
#endif

#include "binbow/descriptors.h"
#include "binbow/vocabulary.h"

namespace binbow::test {

// Path of a file under ../shared/data (see its README). Fails the current test
// with a clear message, and throws to stop it, when the file is missing.
std::string shared_data(const std::string& relative);
// The folder of rtabmap-samples' 84 corridor frames (a real sequence).
std::string samples_folder();
// Path of a file in the repository (e.g. "data/...").
std::string source_path(const std::string& relative);
// Path of the binbow CLI built beside the tests.
std::string cli_path();
// Path of the module with the CLI's commands that need OpenCV.
std::string cli_vision_module_path();

// A fresh empty directory, removed when the object dies.
class TempDir {
 public:
  TempDir();
  ~TempDir();
  TempDir(const TempDir&) = delete;
  TempDir& operator=(const TempDir&) = delete;
  const std::string& path() const { return path_; }
  std::string file(const std::string& name) const { return path_ + "/" + name; }

 private:
  std::string path_;
};

// A frame list (one path a line) of the first `count` corridor frames of
// samples_folder(), written in `dir`; returns its path.
std::string write_frame_list(const TempDir& dir, int count);

// A hand-made two-level tree of 9 nodes (3 x 3 leaves, fixed random words of
// `code_size` bytes, fixed weights) trained on `descriptor`: a vocabulary
// that depends on no builder.
Vocabulary hand_made_vocabulary(const std::string& descriptor = "", std::size_t code_size = 32);

// A 4-way, 3-level vocabulary built on ten images of clustered descriptors
// from `seed`: small, real structure, the same for the same seed.
Vocabulary clustered_vocabulary(std::uint64_t seed = 1);

// Hamming distance counted bit by bit: the reference for the kernels.
std::uint32_t bit_distance(const std::uint8_t* a, const std::uint8_t* b, std::size_t code_size);

// `rows` uniformly random descriptors of `code_size` bytes.
DescriptorMatrix random_descriptors(std::size_t rows, std::size_t code_size, std::mt19937_64& rng);
// Descriptors clustered around `centers` random centres, each bit flipped
// with probability `noise`: data with real structure for k-medians.
DescriptorMatrix clustered_descriptors(std::size_t rows, std::size_t code_size, std::size_t centers,
                                       double noise, std::mt19937_64& rng);

// Reads a whole file; empty vector if missing.
std::vector<std::uint8_t> read_file(const std::string& path);
void write_file(const std::string& path, const std::vector<std::uint8_t>& bytes);

// Runs a shell command, returns its exit status; stdout+stderr go to `output`.
int run_command(const std::string& command, std::string* output);
// Runs the binbow CLI with `arguments` (already quoted as the shell needs).
int run_cli(const std::string& arguments, std::string* output);
// The number on the first "key: number" line of a command's output, or -1.
double printed_number(const std::string& output, const std::string& key);

// Renders an HTML page in headless Chromium into `png` (profile in
// `scratch_dir`). Adds a test failure saying how to install Chromium when it
// is missing, or what Chromium printed when rendering fails; returns success.
bool render_in_chromium(const std::string& page, const std::string& png,
                        const std::string& scratch_dir);

}  // namespace binbow::test
