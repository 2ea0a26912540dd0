#include "support/test_support.h"

#include <gtest/gtest.h>

#include <sys/wait.h>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <regex>
#include <stdexcept>

namespace binbow::test {

namespace fs = std::filesystem;

std::string shared_data(const std::string& relative) {
  const std::string path = std::string(BINBOW_SHARED_DATA_DIR) + "/" + relative;
  if (!fs::exists(path)) {
    ADD_FAILURE() << "missing test data: " << path
                  << "\n  The tests need the real data folder ../shared/data beside the checkout"
                  << " (or -DBINBOW_SHARED_DATA_DIR=...); see README.md, section Tests.";
    throw std::runtime_error("missing test data: " + path);
  }
  return path;
}

std::string samples_folder() {
  const std::string first = shared_data("rtabmap-samples/samples/1.jpg");
  return first.substr(0, first.rfind('/'));
}

std::string source_path(const std::string& relative) {
  return std::string(BINBOW_SOURCE_DIR) + "/" + relative;
}

std::string cli_path() {
  return BINBOW_CLI;
}

std::string cli_vision_module_path() {
  return BINBOW_CLI_VISION_MODULE;
}

TempDir::TempDir() {
  std::string pattern = (fs::temp_directory_path() / "binbow-test-XXXXXX").string();
  if (mkdtemp(pattern.data()) == nullptr) throw std::runtime_error("mkdtemp failed");
  path_ = pattern;
}

TempDir::~TempDir() {
  std::error_code ignored;
  fs::remove_all(path_, ignored);
}

std::string write_frame_list(const TempDir& dir, int count) {
  const std::string path = dir.file("frames.txt");
  std::ofstream list(path);
  for (int i = 1; i <= count; ++i) list << samples_folder() << "/" << i << ".jpg\n";
  return path;
}

Vocabulary hand_made_vocabulary(const std::string& descriptor, std::size_t code_size) {
  VocabularyTree tree;
  tree.code_size = code_size;
  tree.branching = 3;
  tree.levels = 2;
  tree.parent = {0, 0, 0, 0, 1, 1, 1, 2, 2};
  tree.descriptor = descriptor;
  std::mt19937_64 rng(4);
  tree.descriptors.resize(tree.parent.size() * code_size);
  for (std::uint8_t& byte : tree.descriptors) byte = static_cast<std::uint8_t>(rng());
  tree.weights = {0, 0, 0, 0.75f, 1.5f, 2.25f, 3.0f, 0.1f, 0.2f};
  return Vocabulary::from_tree(tree);
}

std::uint32_t bit_distance(const std::uint8_t* a, const std::uint8_t* b, std::size_t code_size) {
  std::uint32_t d = 0;
  for (std::size_t i = 0; i < code_size; ++i)
    for (int bit = 0; bit < 8; ++bit) d += ((a[i] ^ b[i]) >> bit) & 1u;
  return d;
}

DescriptorMatrix random_descriptors(std::size_t rows, std::size_t code_size, std::mt19937_64& rng) {
  DescriptorMatrix m(rows, code_size);
  for (std::size_t i = 0; i < rows * code_size; ++i) m.data()[i] = static_cast<std::uint8_t>(rng());
  return m;
}

DescriptorMatrix clustered_descriptors(std::size_t rows, std::size_t code_size, std::size_t centers,
                                       double noise, std::mt19937_64& rng) {
  const DescriptorMatrix c = random_descriptors(centers, code_size, rng);
  DescriptorMatrix m(rows, code_size);
  std::bernoulli_distribution flip(noise);
  for (std::size_t r = 0; r < rows; ++r) {
    const std::uint8_t* center = c.row(rng() % centers);
    for (std::size_t b = 0; b < code_size; ++b) {
      std::uint8_t v = center[b];
      for (int bit = 0; bit < 8; ++bit)
        if (flip(rng)) v ^= static_cast<std::uint8_t>(1u << bit);
      m.row(r)[b] = v;
    }
  }
  return m;
}

std::vector<std::uint8_t> read_file(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

void write_file(const std::string& path, const std::vector<std::uint8_t>& bytes) {
  std::ofstream out(path, std::ios::binary | std::ios::trunc);
  out.write(reinterpret_cast<const char*>(bytes.data()),
            static_cast<std::streamsize>(bytes.size()));
}

int run_command(const std::string& command, std::string* output) {
  FILE* pipe = popen((command + " 2>&1").c_str(), "r");
  if (pipe == nullptr) return -1;
  std::string text;
  char buffer[4096];
  std::size_t n;
  while ((n = fread(buffer, 1, sizeof buffer, pipe)) > 0) text.append(buffer, n);
  const int status = pclose(pipe);
  if (output != nullptr) *output = text;
  return WIFEXITED(status) ? WEXITSTATUS(status) : -1;
}

namespace {
std::string find_chromium() {
  for (const char* name : {"chromium", "chromium-browser", "google-chrome"}) {
    std::string out;
    if (run_command(std::string("command -v ") + name, &out) == 0) {
      while (!out.empty() && (out.back() == '\n' || out.back() == '\r')) out.pop_back();
      return out;
    }
  }
  return "";
}
}  // namespace

int run_cli(const std::string& arguments, std::string* output) {
  return run_command("'" + cli_path() + "' " + arguments, output);
}

double printed_number(const std::string& output, const std::string& key) {
  std::smatch m;
  if (!std::regex_search(output, m, std::regex("(^|\n)" + key + ": ([0-9.eE+-]+)"))) return -1;
  return std::stod(m[2]);
}

bool render_in_chromium(const std::string& page, const std::string& png,
                        const std::string& scratch_dir) {
  const std::string chromium = find_chromium();
  if (chromium.empty()) {
    ADD_FAILURE() << "headless Chromium is needed to check that the report renders: install it "
                     "(Debian: apt-get install -y chromium, or scripts/install-deps.sh)";
    return false;
  }
  std::string out;
  const int status = run_command(
      "timeout 120 " + chromium +
          " --headless --no-sandbox --disable-gpu --disable-quic --no-first-run"
          " --disable-background-networking --disable-component-update --disable-sync"
          " --user-data-dir=" +
          scratch_dir + "/chromium-profile --window-size=1280,2000 --screenshot=" + png +
          " file://" + page,
      &out);
  if (status != 0 || !fs::exists(png)) {
    ADD_FAILURE() << "Chromium could not render " << page << ":\n" << out;
    return false;
  }
  return true;
}

}  // namespace binbow::test
