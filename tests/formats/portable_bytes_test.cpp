// Files binbow writes hold the same bytes on every processor: a vocabulary
// built from fixed descriptors (k-medians, weights), saved in every format,
// and databases over it, against the CRC-32C of the bytes written on x86-64.
// scripts/test-aarch64.sh runs this under qemu-aarch64 too. A deliberate
// change of a format changes these numbers (a failure prints the new ones).
// With BINBOW_PORTABLE_BYTES_DIR set, the files are also kept in that folder,
// for cmp against another processor's.
#include <gtest/gtest.h>

#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <map>
#include <random>
#include <string>
#include <vector>

#include "binbow/database.h"
#include "binbow/formats.h"
#include "binbow/vocabulary.h"
#include "core/crc32c.h"
#include "support/test_support.h"

namespace binbow {
namespace {

std::vector<DescriptorMatrix> training_images(std::size_t code_size) {
  std::mt19937_64 rng(41);
  std::vector<DescriptorMatrix> images;
  for (int i = 0; i < 12; ++i)
    images.push_back(test::clustered_descriptors(300, code_size, 40, 0.1, rng));
  return images;
}

TEST(PortableBytes, WrittenFilesEqualTheBytesWrittenOnX86_64) {
  const test::TempDir dir;
  const char* keep = std::getenv("BINBOW_PORTABLE_BYTES_DIR");
  const std::string folder = keep != nullptr && *keep ? keep : dir.path();
  std::filesystem::create_directories(folder);

  const std::vector<DescriptorMatrix> images = training_images(32);
  std::vector<DescriptorView> views;
  for (const DescriptorMatrix& m : images) views.push_back(m.view());
  BuildOptions options;
  options.branching = 5;
  options.levels = 3;
  options.seed = 7;
  options.threads = 2;
  options.descriptor = "orb";
  const Vocabulary vocabulary = Vocabulary::build(views, options);

  const std::vector<std::string> vocabulary_files{
      "vocabulary.bbw", "vocabulary.yml",   "vocabulary.yml.gz", "vocabulary.txt",
      "vocabulary.bin", "vocabulary.dbow3", "vocabulary.fbow",   "vocabulary.vins.bin"};
  for (const std::string& name : vocabulary_files) save_vocabulary(vocabulary, folder + "/" + name);
  Database database(vocabulary);
  for (std::size_t i = 0; i < images.size(); ++i)
    database.add(images[i].view(), "image " + std::to_string(i));
  database.save(folder + "/database.bbdb");
  database.save(folder + "/database-without-vocabulary.bbdb", false);

  const std::map<std::string, std::uint32_t> expected{
      {"vocabulary.bbw", 0xa4f6b2e9},    {"vocabulary.yml", 0xa672bd14},
      {"vocabulary.yml.gz", 0x2bf74795}, {"vocabulary.txt", 0x1acf6ad0},
      {"vocabulary.bin", 0x8e46cd68},    {"vocabulary.dbow3", 0xe3046ec1},
      {"vocabulary.fbow", 0x9d395bbf},   {"vocabulary.vins.bin", 0xcf20ac40},
      {"database.bbdb", 0x9b0443cd},     {"database-without-vocabulary.bbdb", 0xfa3010ad},
  };
  std::string actual;
  for (const auto& [name, crc] : expected) {
    const std::vector<std::uint8_t> bytes = test::read_file(folder + "/" + name);
    const std::uint32_t got = detail::crc32c(bytes.data(), bytes.size());
    char line[96];
    std::snprintf(line, sizeof line, "      {\"%s\", 0x%08x},\n", name.c_str(), got);
    actual += line;
    EXPECT_EQ(got, crc) << name;
  }
  if (HasFailure()) ADD_FAILURE() << "the files' CRC-32C here:\n" << actual;
}

}  // namespace
}  // namespace binbow
