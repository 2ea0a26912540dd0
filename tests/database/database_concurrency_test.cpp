// Readers query while writers add and remove: run under ThreadSanitizer
// (-DBINBOW_TSAN=ON) to check the reader-writer discipline.
#include <gtest/gtest.h>

#include <atomic>
#include <random>
#include <thread>
#include <vector>

#include "binbow/database.h"
#include "binbow/error.h"
#include "binbow/vocabulary.h"
#include "support/test_support.h"

namespace binbow {
namespace {

TEST(DatabaseConcurrency, QueriesWhileAddingAndRemoving) {
  std::mt19937_64 rng(5);
  std::vector<DescriptorMatrix> training;
  for (int i = 0; i < 8; ++i)
    training.push_back(test::clustered_descriptors(60, 32, 30, 0.08, rng));
  std::vector<DescriptorView> views;
  for (const auto& image : training) views.push_back(image.view());
  BuildOptions options;
  options.branching = 4;
  options.levels = 3;
  options.threads = 1;
  const Vocabulary vocabulary = Vocabulary::build(views, options);

  std::vector<BowVector> bows(200);
  for (auto& bow : bows)
    vocabulary.transform(test::clustered_descriptors(30, 32, 30, 0.08, rng).view(), bow);

  Database database(vocabulary);
  for (int i = 0; i < 50; ++i) database.add(bows[static_cast<std::size_t>(i)]);

  std::atomic<bool> writers_done{false};
  std::atomic<std::size_t> queries{0};
  std::vector<std::thread> readers;
  for (int r = 0; r < 3; ++r) {
    readers.emplace_back([&, r] {
      std::size_t q = static_cast<std::size_t>(r);
      while (!writers_done.load()) {
        const auto results = database.query(bows[q % bows.size()], 5, q % 3 ? kAllEntries : 100);
        for (std::size_t i = 1; i < results.size(); ++i)
          EXPECT_GE(results[i - 1].score, results[i].score);
        for (const auto& result : results) {
          // The entry may be removed concurrently: either answer is fine, no crash.
          if (database.contains(result.entry)) {
            try {
              (void)database.feature_vector(result.entry);
            } catch (const InvalidArgument&) {
            }
          }
        }
        (void)database.size();
        ++q;
        ++queries;
      }
    });
  }
  std::thread writer([&] {
    std::mt19937_64 writer_rng(9);
    for (int step = 0; step < 300; ++step) {
      const EntryId id = database.add(bows[writer_rng() % bows.size()]);
      if (step % 97 == 0) database.set_label(id, "frame");
      if (step % 2 == 0) database.remove(id - static_cast<EntryId>(writer_rng() % 2));
    }
  });
  std::thread saver([&] {
    for (int i = 0; i < 5; ++i) (void)database.serialize();
  });
  writer.join();
  saver.join();
  writers_done = true;
  for (auto& reader : readers) reader.join();
  EXPECT_GT(queries.load(), 0u);
  EXPECT_EQ(database.next_entry_id(), 350u);
  EXPECT_EQ(database.size(), 200u);
}

}  // namespace
}  // namespace binbow
