// Every kernel set the CPU supports (portable, popcnt, AVX2, AVX-512, NEON)
// against a bit-counting reference and against the portable set: distances
// (one pair, one query to many rows), nearest rows and the batched descent,
// with ties, odd child counts and every code size path, on random descriptors
// and on the bundled vocabularies' real ones. The choice of a set by
// BINBOW_HAMMING_KERNEL, and its errors.
#include <gtest/gtest.h>

#include <cstdlib>
#include <random>
#include <string>
#include <vector>

#include "binbow/descriptors.h"
#include "binbow/error.h"
#include "binbow/vocabulary.h"
#include "core/kernels.h"
#include "support/test_support.h"

namespace binbow {
namespace {

std::uint32_t naive_nearest(const std::uint8_t* query, const std::uint8_t* rows, std::size_t count,
                            std::size_t code_size) {
  std::uint32_t best = ~0u, best_index = 0;
  for (std::size_t c = 0; c < count; ++c) {
    const std::uint32_t d = test::bit_distance(query, rows + c * code_size, code_size);
    if (d < best) best = d, best_index = static_cast<std::uint32_t>(c);
  }
  return best_index;
}

// A flat tree in breadth-first order with `fanout(depth)` children per inner
// node; children are near copies of one another so that ties are frequent.
struct FlatTree {
  std::vector<std::uint8_t> descriptors;
  std::vector<std::uint32_t> links;
  std::vector<std::uint8_t> child_counts;
  std::size_t code_size = 0;

  detail::TreeView view() const {
    return {descriptors.data(), links.data(), child_counts.data(), code_size};
  }
};

FlatTree make_tree(std::mt19937_64& rng, std::size_t code_size, std::uint32_t max_children,
                   std::uint32_t levels) {
  FlatTree t;
  t.code_size = code_size;
  t.descriptors.resize(code_size);
  t.links.push_back(0);
  t.child_counts.push_back(0);
  std::vector<std::uint32_t> frontier{0};
  std::uint32_t words = 0;
  for (std::uint32_t depth = 0; depth < levels; ++depth) {
    std::vector<std::uint32_t> next;
    for (std::uint32_t node : frontier) {
      const auto count = static_cast<std::uint32_t>(1 + rng() % max_children);
      if (depth > 0 && rng() % 8 == 0) continue;  // an early leaf
      t.links[node] = static_cast<std::uint32_t>(t.links.size());
      t.child_counts[node] = static_cast<std::uint8_t>(count);
      for (std::uint32_t c = 0; c < count; ++c) {
        const std::size_t at = t.descriptors.size();
        t.descriptors.resize(at + code_size);
        for (std::size_t b = 0; b < code_size; ++b)
          t.descriptors[at + b] = static_cast<std::uint8_t>(rng());
        if (c > 0 && rng() % 3 == 0)  // duplicate a sibling: a tie
          std::copy_n(t.descriptors.begin() + static_cast<std::ptrdiff_t>(at - code_size),
                      code_size, t.descriptors.begin() + static_cast<std::ptrdiff_t>(at));
        next.push_back(static_cast<std::uint32_t>(t.links.size()));
        t.links.push_back(0);
        t.child_counts.push_back(0);
      }
    }
    frontier = std::move(next);
  }
  for (std::size_t n = 0; n < t.links.size(); ++n)
    if (t.child_counts[n] == 0) t.links[n] = words++ | detail::kLeafBit;
  return t;
}

void naive_descend(const FlatTree& t, const std::uint8_t* query, std::uint32_t level_depth,
                   std::uint32_t* word, std::uint32_t* level_node) {
  std::uint32_t node = 0, depth = 0;
  *level_node = 0;
  while (t.child_counts[node] != 0) {
    const std::uint32_t first = t.links[node];
    node = first + naive_nearest(query, t.descriptors.data() + std::size_t{first} * t.code_size,
                                 t.child_counts[node], t.code_size);
    if (++depth <= level_depth) *level_node = node;
  }
  *word = t.links[node] & ~detail::kLeafBit;
}

std::vector<std::uint8_t> random_bytes(std::mt19937_64& rng, std::size_t n) {
  std::vector<std::uint8_t> v(n);
  for (auto& b : v) b = static_cast<std::uint8_t>(rng());
  return v;
}

TEST(Kernels, TheDispatchedSetIsOneOfTheSupported) {
  const auto all = detail::supported_kernels();
  ASSERT_FALSE(all.empty());
  bool found = false;
  for (const detail::Kernels* k : all) found = found || k == &detail::kernels();
  EXPECT_TRUE(found) << detail::kernels().name;
}

// The set BINBOW_HAMMING_KERNEL asks for, or the fastest when it is unset:
// the test suites run once per supported set with the variable set.
std::string expected_kernel_name() {
  const char* requested = std::getenv("BINBOW_HAMMING_KERNEL");
  if (requested != nullptr && *requested != '\0') return requested;
  return supported_hamming_kernels().back();
}

TEST(Kernels, ThePublicNamesAreTheDispatchedAndSupportedSets) {
  EXPECT_STREQ(hamming_kernel_name(), detail::kernels().name);
  const auto all = detail::supported_kernels();
  const std::vector<std::string> names = supported_hamming_kernels();
  ASSERT_EQ(names.size(), all.size());
  for (std::size_t i = 0; i < all.size(); ++i) EXPECT_EQ(names[i], all[i]->name);
  EXPECT_EQ(names.front(), "generic");
  EXPECT_EQ(hamming_kernel_name(), expected_kernel_name());
  for (const std::string& name : names)
    EXPECT_TRUE(name == "generic" || name == "popcnt" || name == "avx2" || name == "avx512" ||
                name == "neon")
        << name;
}

TEST(Kernels, CpuFeaturesDecideTheKernelSet) {
  const std::vector<CpuFeature> features = cpu_features();
  std::vector<std::string> names;
  for (const detail::Kernels* k : detail::supported_kernels()) names.emplace_back(k->name);
#if defined(__x86_64__)
  ASSERT_EQ(features.size(), 4u);
  EXPECT_STREQ(features[0].name, "popcnt");
  EXPECT_STREQ(features[1].name, "avx2");
  EXPECT_STREQ(features[2].name, "avx512f");
  EXPECT_STREQ(features[3].name, "avx512vpopcntdq");
  std::vector<std::string> expected{"generic"};
  if (features[0].present) {
    expected.emplace_back("popcnt");
    if (features[1].present) expected.emplace_back("avx2");
    if (features[2].present && features[3].present) expected.emplace_back("avx512");
  }
  EXPECT_EQ(names, expected);
#elif defined(__aarch64__)
  EXPECT_TRUE(features.empty());
  EXPECT_EQ(names, (std::vector<std::string>{"generic", "neon"}));
#else
  EXPECT_TRUE(features.empty());
#endif
}

TEST(KernelChoice, EachSupportedSetCanBeForcedByName) {
  for (const detail::Kernels* k : detail::supported_kernels())
    EXPECT_EQ(&detail::select_kernels(k->name), k) << k->name;
  EXPECT_EQ(&detail::select_kernels(nullptr), detail::supported_kernels().back());
  EXPECT_EQ(&detail::select_kernels(""), detail::supported_kernels().back());
}

TEST(KernelChoice, AnUnsupportedOrUnknownSetIsAnErrorThatSaysWhatToDo) {
  const std::vector<std::string> supported = supported_hamming_kernels();
  std::string list;
  for (const std::string& name : supported) list += (list.empty() ? "" : ", ") + name;
  for (const char* name : {"generic", "popcnt", "avx2", "avx512", "neon", "AVX2", "sse"}) {
    if (std::find(supported.begin(), supported.end(), name) != supported.end()) continue;
    try {
      detail::select_kernels(name);
      ADD_FAILURE() << name << " was accepted";
    } catch (const InvalidArgument& e) {
      const std::string message = e.what();
      EXPECT_NE(message.find("BINBOW_HAMMING_KERNEL=" + std::string(name) + ": "),
                std::string::npos)
          << message;
      EXPECT_NE(message.find("this CPU supports " + list +
                             ": set BINBOW_HAMMING_KERNEL to one "
                             "of them, or unset it to use the fastest"),
                std::string::npos)
          << message;
      const bool known = std::string(name) != "AVX2" && std::string(name) != "sse";
      EXPECT_NE(message.find(known ? "this CPU cannot run that Hamming kernel"
                                   : "no such Hamming kernel"),
                std::string::npos)
          << message;
    }
  }
}

TEST(Kernels, DistancesAndNearestRowsEqualBitCounting) {
  std::mt19937_64 rng(3);
  for (const detail::Kernels* kernels : detail::supported_kernels()) {
    for (std::size_t code_size : {5, 20, 32, 61, 64, 96}) {
      const std::size_t count = 1 + rng() % 40;
      auto rows = random_bytes(rng, count * code_size);
      if (count > 2) std::copy_n(rows.begin(), code_size, rows.begin() + 2 * code_size);
      const auto queries = random_bytes(rng, 30 * code_size);
      std::vector<std::uint32_t> index(30), distance(30);
      kernels->nearest(queries.data(), 30, rows.data(), count, code_size, index.data(),
                       distance.data());
      for (std::size_t q = 0; q < 30; ++q) {
        const std::uint8_t* query = queries.data() + q * code_size;
        const std::uint32_t expected = naive_nearest(query, rows.data(), count, code_size);
        EXPECT_EQ(index[q], expected) << kernels->name << " code size " << code_size;
        EXPECT_EQ(distance[q],
                  test::bit_distance(query, rows.data() + expected * code_size, code_size));
        EXPECT_EQ(kernels->hamming(query, rows.data(), code_size),
                  test::bit_distance(query, rows.data(), code_size));
      }
    }
  }
}

TEST(Kernels, DistancesToContiguousAndIndexedRowsEqualBitCounting) {
  std::mt19937_64 rng(4);
  for (const detail::Kernels* kernels : detail::supported_kernels()) {
    for (std::size_t code_size : {5, 20, 32, 61, 64, 96}) {
      const std::size_t count = 1 + rng() % 40;
      const auto rows = random_bytes(rng, count * code_size);
      const auto query = random_bytes(rng, code_size);
      std::vector<std::uint32_t> contiguous(count), indexed(count), indices(count);
      for (auto& index : indices) index = static_cast<std::uint32_t>(rng() % count);
      kernels->distances(query.data(), rows.data(), nullptr, count, code_size, contiguous.data());
      kernels->distances(query.data(), rows.data(), indices.data(), count, code_size,
                         indexed.data());
      for (std::size_t i = 0; i < count; ++i) {
        EXPECT_EQ(contiguous[i],
                  test::bit_distance(query.data(), rows.data() + i * code_size, code_size))
            << kernels->name << " code size " << code_size;
        EXPECT_EQ(indexed[i],
                  test::bit_distance(query.data(), rows.data() + indices[i] * code_size, code_size))
            << kernels->name << " code size " << code_size;
      }
    }
  }
}

TEST(Kernels, DescentEqualsNaiveDescentForEveryFanoutAndCodeSize) {
  std::mt19937_64 rng(5);
  for (const detail::Kernels* kernels : detail::supported_kernels()) {
    for (std::size_t code_size : {32, 64, 24, 61}) {
      for (std::uint32_t max_children : {1u, 2u, 3u, 9u, 10u, 17u, 255u}) {
        const std::uint32_t levels = max_children > 20 ? 2 : 4;
        const FlatTree tree = make_tree(rng, code_size, max_children, levels);
        // More queries than one batch, and a query equal to a node (distance 0).
        const std::size_t n = 150;
        auto queries = random_bytes(rng, n * code_size);
        std::copy_n(tree.descriptors.begin() + static_cast<std::ptrdiff_t>(code_size), code_size,
                    queries.begin());
        for (std::uint32_t level_depth : {0u, 1u, 2u, 9u}) {
          std::vector<std::uint32_t> words(n), nodes(n);
          kernels->descend(tree.view(), queries.data(), n, words.data(), nodes.data(), level_depth);
          for (std::size_t q = 0; q < n; ++q) {
            std::uint32_t word = 0, node = 0;
            naive_descend(tree, queries.data() + q * code_size, level_depth, &word, &node);
            ASSERT_EQ(words[q], word) << kernels->name << " code size " << code_size << " k "
                                      << max_children << " query " << q;
            ASSERT_EQ(nodes[q], node) << kernels->name << " level depth " << level_depth;
          }
        }
      }
    }
  }
}

// The flat tree of a real vocabulary, as the descent kernel reads it.
FlatTree tree_of(const Vocabulary& v) {
  FlatTree t;
  t.code_size = v.code_size();
  for (NodeId n = 0; n < v.node_count(); ++n) {
    const std::uint8_t* d = v.node_descriptor(n);
    t.descriptors.insert(t.descriptors.end(), d, d + v.code_size());
    t.links.push_back(v.is_leaf(n) ? v.node_word(n) | detail::kLeafBit : v.first_child(n));
    t.child_counts.push_back(static_cast<std::uint8_t>(v.child_count(n)));
  }
  return t;
}

// Real descriptors: the bundled vocabularies' nodes (medians of ORB and BRIEF
// descriptors of photographs), each with a few bits flipped so that queries
// fall between words. Every kernel set gives the portable set's distances,
// nearest rows, words and direct-index nodes, bit for bit.
TEST(Kernels, EverySetEqualsThePortableOneOnRealDescriptors) {
  for (const char* file : {"data/vocab/orb_default.bbw", "data/vocab/brief_default.bbw"}) {
    const Vocabulary v = Vocabulary::load(test::source_path(file));
    const FlatTree tree = tree_of(v);
    const std::size_t code_size = v.code_size();
    std::mt19937_64 rng(6);
    const std::size_t n = 2000;
    std::vector<std::uint8_t> queries(n * code_size);
    for (std::size_t q = 0; q < n; ++q) {
      const std::size_t node = 1 + rng() % (v.node_count() - 1);
      std::copy_n(v.node_descriptor(static_cast<NodeId>(node)), code_size,
                  queries.begin() + static_cast<std::ptrdiff_t>(q * code_size));
      const std::size_t flips = rng() % 24;
      for (std::size_t f = 0; f < flips; ++f) {
        const std::size_t bit = rng() % (code_size * 8);
        queries[q * code_size + bit / 8] ^= static_cast<std::uint8_t>(1u << (bit % 8));
      }
    }
    const detail::Kernels& generic = detail::generic_kernels();
    std::vector<std::uint32_t> words(n), nodes(n), distances(v.node_count()), index(n), best(n);
    generic.descend(tree.view(), queries.data(), n, words.data(), nodes.data(), 3);
    generic.distances(queries.data(), tree.descriptors.data(), nullptr, v.node_count(), code_size,
                      distances.data());
    generic.nearest(queries.data(), n, tree.descriptors.data(), 500, code_size, index.data(),
                    best.data());
    for (const detail::Kernels* kernels : detail::supported_kernels()) {
      std::vector<std::uint32_t> k_words(n), k_nodes(n), k_distances(v.node_count()), k_index(n),
          k_best(n);
      kernels->descend(tree.view(), queries.data(), n, k_words.data(), k_nodes.data(), 3);
      kernels->distances(queries.data(), tree.descriptors.data(), nullptr, v.node_count(),
                         code_size, k_distances.data());
      kernels->nearest(queries.data(), n, tree.descriptors.data(), 500, code_size, k_index.data(),
                       k_best.data());
      EXPECT_EQ(k_words, words) << kernels->name << " " << file;
      EXPECT_EQ(k_nodes, nodes) << kernels->name << " " << file;
      EXPECT_EQ(k_distances, distances) << kernels->name << " " << file;
      EXPECT_EQ(k_index, index) << kernels->name << " " << file;
      EXPECT_EQ(k_best, best) << kernels->name << " " << file;
      for (std::size_t q = 0; q < n; ++q)
        ASSERT_EQ(
            kernels->hamming(queries.data() + q * code_size, tree.descriptors.data(), code_size),
            generic.hamming(queries.data() + q * code_size, tree.descriptors.data(), code_size))
            << kernels->name << " " << file;
    }
    // The vocabulary's own descent runs the set in use (the suites run once
    // per set with BINBOW_HAMMING_KERNEL, scores and files included).
    std::vector<WordId> dispatched(n);
    v.quantize(DescriptorView{queries.data(), n, code_size}, dispatched.data());
    EXPECT_EQ(dispatched, words) << hamming_kernel_name();
  }
}

}  // namespace
}  // namespace binbow
