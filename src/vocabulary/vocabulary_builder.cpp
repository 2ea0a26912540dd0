// Vocabulary::build: hierarchical k-medians (DBoW2's HKmeansStep) processed
// level by level. Every node's rows are contiguous in one of two buffers; a
// node clusters its range of one buffer and scatters it, grouped by child,
// into the same range of the other, so no descriptor is copied per node and
// siblings never touch each other's memory. Each node draws its random numbers
// from a seed derived from its path in the tree, so the tree does not depend
// on which thread clusters which node.
#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <numeric>
#include <string>
#include <vector>

#include "binbow/error.h"
#include "binbow/vocabulary.h"
#include "core/parallel_for.h"
#include "vocabulary/kmedians.h"
#include "vocabulary/vocabulary_block.h"

namespace binbow {
namespace {

// A node that is clustered at the current level: rows [begin, end) of the
// level's source buffer.
struct NodeTask {
  std::size_t begin = 0, end = 0;
  std::uint64_t seed = 0;
  std::uint32_t node = 0;  // index in BuiltTree
  std::size_t size() const { return end - begin; }
};

// What clustering one task produced: its children, in cluster order.
struct TaskResult {
  std::size_t first_centre = 0;  // offset in the level's centre store, in clusters
  std::uint32_t children = 0;
};

// The tree in creation (breadth-first) order; children of a node are
// contiguous. Converted to DBoW2's depth-first order at the end.
struct BuiltTree {
  std::vector<std::uint32_t> parent, first_child, child_count;
  std::vector<std::uint8_t> descriptors;
};

std::size_t validate(const std::vector<DescriptorView>& images, const BuildOptions& options) {
  if (options.branching < 2 || options.branching > 255) {
    throw InvalidArgument("Vocabulary::build: branching must be in 2..255, got " +
                          std::to_string(options.branching));
  }
  if (options.levels < 1 || options.levels > 16) {
    throw InvalidArgument("Vocabulary::build: levels must be in 1..16, got " +
                          std::to_string(options.levels));
  }
  if (!(options.stop_word_fraction >= 0.0 && options.stop_word_fraction <= 1.0)) {
    throw InvalidArgument("Vocabulary::build: stop_word_fraction must be in [0, 1]");
  }
  if (!detail::valid_descriptor_name(options.descriptor)) {
    throw InvalidArgument("Vocabulary::build: descriptor name \"" + options.descriptor +
                          "\" is not " + detail::kDescriptorNameRule);
  }
  if (images.empty()) throw InvalidArgument("Vocabulary::build: no training images");
  std::size_t code_size = 0;
  std::size_t first_sized = 0;
  for (std::size_t i = 0; i < images.size(); ++i) {
    const DescriptorView& image = images[i];
    if (image.rows == 0) continue;
    if (image.code_size == 0 || image.data == nullptr) {
      throw InvalidArgument("Vocabulary::build: image " + std::to_string(i) +
                            " has descriptors without data or of size 0");
    }
    if (code_size == 0) {
      code_size = image.code_size;
      first_sized = i;
    } else if (image.code_size != code_size) {
      throw InvalidArgument("Vocabulary::build: mixed descriptor sizes: image " +
                            std::to_string(first_sized) + " has " + std::to_string(code_size) +
                            "-byte descriptors, image " + std::to_string(i) + " has " +
                            std::to_string(image.code_size));
    }
  }
  if (code_size == 0) throw InvalidArgument("Vocabulary::build: no training descriptors");
  return code_size;
}

class TreeBuilder {
 public:
  TreeBuilder(const std::vector<DescriptorView>& images, std::size_t code_size,
              const BuildOptions& options)
      : options_(options),
        code_size_(code_size),
        threads_(detail::resolve_thread_count(options.threads)) {
    for (const DescriptorView& image : images) total_ += image.rows;
    for (auto& buffer : buffers_) buffer.resize(total_ * code_size_);
    std::size_t offset = 0;
    for (const DescriptorView& image : images) {
      if (image.rows == 0) continue;
      std::memcpy(buffers_[0].data() + offset, image.data, image.rows * code_size_);
      offset += image.rows * code_size_;
    }
    assignment_.resize(total_);
    distance_.resize(total_);
    for (unsigned t = 0; t < threads_; ++t) workers_.emplace_back(code_size_, options.branching);
  }

  VocabularyTree build() {
    tree_.parent.push_back(0);
    tree_.first_child.push_back(0);
    tree_.child_count.push_back(0);
    tree_.descriptors.assign(code_size_, 0);
    std::vector<NodeTask> tasks{{0, total_, detail::child_seed(options_.seed, 0), 0}};
    last_report_ = std::chrono::steady_clock::now();
    for (std::uint32_t depth = 0; !tasks.empty(); ++depth) {
      tasks = cluster_level(tasks, depth);
    }
    report(true);
    return depth_first_tree();
  }

 private:
  std::vector<NodeTask> cluster_level(const std::vector<NodeTask>& tasks, std::uint32_t depth) {
    const std::uint8_t* source = buffers_[depth % 2].data();
    std::uint8_t* target = buffers_[(depth + 1) % 2].data();
    const bool last_level = depth + 1 >= options_.levels;
    const std::size_t k = options_.branching;

    // Children of task t: at most min(k, size) clusters, stored from
    // first_centre; per cluster its row count and whether its rows differ.
    std::vector<TaskResult> results(tasks.size());
    std::size_t centre_slots = 0;
    for (std::size_t t = 0; t < tasks.size(); ++t) {
      results[t].first_centre = centre_slots;
      centre_slots += std::min(k, tasks[t].size());
    }
    std::vector<std::uint8_t> centres(centre_slots * code_size_);
    std::vector<std::size_t> sizes(centre_slots);
    std::vector<std::uint8_t> spread(centre_slots);

    auto run_task = [&](std::size_t t, detail::KMedians& kmedians, unsigned threads) {
      const NodeTask& task = tasks[t];
      std::uint32_t* assignment = assignment_.data() + task.begin;
      std::uint32_t* distance = distance_.data() + task.begin;
      kmedians.cluster(source + task.begin * code_size_, task.size(), task.seed,
                       options_.max_iterations, threads, assignment, distance);
      TaskResult& result = results[t];
      result.children = kmedians.cluster_count();
      const std::size_t slot = result.first_centre;
      std::memcpy(centres.data() + slot * code_size_, kmedians.centres(),
                  result.children * code_size_);
      std::size_t* child_sizes = sizes.data() + slot;
      std::uint8_t* child_spread = spread.data() + slot;
      std::size_t leaf_rows = 0;
      if (last_level) {
        leaf_rows = task.size();
      } else {
        // Counting sort of the rows by cluster into the other buffer.
        std::vector<std::size_t>& offsets = scratch_offsets(kmedians);
        offsets.assign(result.children + 1, 0);
        for (std::size_t i = 0; i < task.size(); ++i) {
          ++offsets[assignment[i] + 1];
          child_spread[assignment[i]] |= distance[i] != 0 ? 1 : 0;
        }
        for (std::uint32_t c = 0; c < result.children; ++c) {
          child_sizes[c] = offsets[c + 1];
          if (child_sizes[c] <= 1 || !child_spread[c]) leaf_rows += child_sizes[c];
          offsets[c + 1] += offsets[c];
        }
        const std::uint8_t* rows = source + task.begin * code_size_;
        std::uint8_t* out = target + task.begin * code_size_;
        for (std::size_t i = 0; i < task.size(); ++i) {
          std::memcpy(out + offsets[assignment[i]]++ * code_size_, rows + i * code_size_,
                      code_size_);
        }
      }
      clustered_ += leaf_rows;
      nodes_ += result.children;
    };

    // Big nodes first, one at a time, each split over every thread; then the
    // others in parallel, largest first, one per thread.
    std::size_t level_rows = 0;
    for (const NodeTask& task : tasks) level_rows += task.size();
    std::vector<std::size_t> order(tasks.size());
    std::iota(order.begin(), order.end(), std::size_t{0});
    std::stable_sort(order.begin(), order.end(), [&](std::size_t a, std::size_t b) {
      return tasks[a].size() > tasks[b].size();
    });
    std::size_t big = 0;
    while (threads_ > 1 && big < order.size() &&
           tasks[order[big]].size() * 2 * threads_ > level_rows) {
      run_task(order[big], workers_[0], threads_);
      report(false);
      ++big;
    }
    detail::parallel_for(threads_, order.size() - big, [&](std::size_t i, unsigned worker) {
      run_task(order[big + i], workers_[worker], 1);
      if (worker == 0) report(false);
    });

    // Record the children in task order (breadth-first numbering) and queue
    // those that are split further.
    std::vector<NodeTask> next;
    for (std::size_t t = 0; t < tasks.size(); ++t) {
      const NodeTask& task = tasks[t];
      const TaskResult& result = results[t];
      const auto first = static_cast<std::uint32_t>(tree_.parent.size());
      tree_.first_child[task.node] = first;
      tree_.child_count[task.node] = result.children;
      std::size_t begin = task.begin;
      for (std::uint32_t c = 0; c < result.children; ++c) {
        const std::size_t slot = result.first_centre + c;
        tree_.parent.push_back(task.node);
        tree_.first_child.push_back(0);
        tree_.child_count.push_back(0);
        tree_.descriptors.insert(tree_.descriptors.end(), centres.data() + slot * code_size_,
                                 centres.data() + (slot + 1) * code_size_);
        // DBoW2 splits every child with more than one row; a child whose rows
        // are all equal would only grow a chain of single children, so it
        // stays a leaf.
        if (!last_level && sizes[slot] > 1 && spread[slot]) {
          next.push_back({begin, begin + sizes[slot], detail::child_seed(task.seed, c), first + c});
        }
        if (!last_level) begin += sizes[slot];
      }
    }
    return next;
  }

  // Per-worker scratch for the counting sort, kept to avoid an allocation per node.
  std::vector<std::size_t>& scratch_offsets(const detail::KMedians& kmedians) {
    return offsets_[static_cast<std::size_t>(&kmedians - workers_.data())];
  }

  void report(bool final) {
    if (!options_.progress) return;
    const auto now = std::chrono::steady_clock::now();
    if (!final && now - last_report_ < std::chrono::milliseconds(100)) return;
    last_report_ = now;
    BuildProgress progress;
    progress.clustered_descriptors = clustered_;
    progress.total_descriptors = total_;
    progress.nodes = nodes_ + 1;
    options_.progress(progress);
  }

  // DBoW2's numbering: a node's children get consecutive ids, then each child's
  // subtree is numbered in turn.
  VocabularyTree depth_first_tree() const {
    const std::size_t count = tree_.parent.size();
    std::vector<std::uint32_t> new_id(count, 0);
    std::uint32_t next_id = 1;
    number_children(0, new_id, next_id);

    VocabularyTree tree;
    tree.code_size = code_size_;
    tree.branching = options_.branching;
    tree.levels = options_.levels;
    tree.weighting = options_.weighting;
    tree.scoring = options_.scoring;
    tree.descriptor = options_.descriptor;
    tree.parent.resize(count);
    tree.descriptors.resize(count * code_size_);
    tree.weights.assign(count, 1.0f);
    for (std::size_t node = 0; node < count; ++node) {
      const std::uint32_t id = new_id[node];
      tree.parent[id] = new_id[tree_.parent[node]];
      std::memcpy(tree.descriptors.data() + id * code_size_,
                  tree_.descriptors.data() + node * code_size_, code_size_);
    }
    return tree;
  }

  void number_children(std::uint32_t node, std::vector<std::uint32_t>& new_id,
                       std::uint32_t& next_id) const {
    const std::uint32_t first = tree_.first_child[node];
    const std::uint32_t children = tree_.child_count[node];
    for (std::uint32_t c = 0; c < children; ++c) new_id[first + c] = next_id++;
    for (std::uint32_t c = 0; c < children; ++c) number_children(first + c, new_id, next_id);
  }

  const BuildOptions& options_;
  std::size_t code_size_;
  unsigned threads_;
  std::size_t total_ = 0;
  std::vector<std::uint8_t> buffers_[2];
  std::vector<std::uint32_t> assignment_, distance_;
  std::vector<detail::KMedians> workers_;
  std::vector<std::vector<std::size_t>> offsets_ = std::vector<std::vector<std::size_t>>(threads_);
  BuiltTree tree_;
  std::atomic<std::size_t> clustered_{0}, nodes_{0};
  std::chrono::steady_clock::time_point last_report_;
};

// N_i: the number of training images in which word i appears.
std::vector<std::uint32_t> image_counts(const Vocabulary& vocabulary,
                                        const std::vector<DescriptorView>& images,
                                        unsigned threads) {
  const std::size_t words = vocabulary.word_count();
  const std::size_t workers = std::min<std::size_t>(threads, images.size());
  std::vector<std::vector<std::uint32_t>> partial(workers, std::vector<std::uint32_t>(words, 0));
  detail::parallel_for(static_cast<unsigned>(workers), workers, [&](std::size_t w, unsigned) {
    std::vector<std::uint32_t>& counts = partial[w];
    std::vector<std::uint32_t> last_image(words, 0);  // image index + 1 that last counted it
    std::vector<WordId> image_words;
    for (std::size_t i = w; i < images.size(); i += workers) {
      if (images[i].rows == 0) continue;
      image_words.resize(images[i].rows);
      vocabulary.quantize(images[i], image_words.data());
      const auto stamp = static_cast<std::uint32_t>(i + 1);
      for (const WordId word : image_words) {
        if (last_image[word] == stamp) continue;
        last_image[word] = stamp;
        ++counts[word];
      }
    }
  });
  std::vector<std::uint32_t> counts(words, 0);
  for (const auto& part : partial) {
    for (std::size_t word = 0; word < words; ++word) counts[word] += part[word];
  }
  return counts;
}

}  // namespace

Vocabulary Vocabulary::build(const std::vector<DescriptorView>& images,
                             const BuildOptions& options) {
  const std::size_t code_size = validate(images, options);
  const bool idf = options.weighting == Weighting::kTfIdf || options.weighting == Weighting::kIdf;
  // Checked before clustering, which can take minutes: the outcome is known.
  if (idf && images.size() < 2) {
    throw InvalidArgument(std::string("Vocabulary::build: ") + to_string(options.weighting) +
                          " weighting needs at least two training images that differ: with one "
                          "image every word's IDF, log(N / N_i), is 0, so every BoW vector would "
                          "be empty; train on more images or use tf weighting");
  }
  VocabularyTree tree = TreeBuilder(images, code_size, options).build();

  const bool stop_words = options.stop_word_fraction < 1.0;
  if (!idf && !stop_words) return from_tree(tree);

  // Document frequencies come from quantising the training images with the
  // finished tree, as DBoW2's setNodeWeights does.
  const Vocabulary unweighted = from_tree(tree);
  const std::vector<std::uint32_t> counts =
      image_counts(unweighted, images, detail::resolve_thread_count(options.threads));
  VocabularyTree weighted = unweighted.to_tree();
  weighted.weighting = options.weighting;
  weighted.scoring = options.scoring;
  const std::vector<NodeId> word_nodes = unweighted.word_nodes();
  const double image_count = static_cast<double>(images.size());
  const double stop_limit = options.stop_word_fraction * image_count;
  std::fill(weighted.weights.begin(), weighted.weights.end(), 0.0f);
  for (std::size_t word = 0; word < word_nodes.size(); ++word) {
    double weight = 1.0;
    if (idf) weight = counts[word] == 0 ? 0.0 : std::log(image_count / counts[word]);
    if (stop_words && counts[word] > stop_limit) weight = 0.0;
    weighted.weights[word_nodes[word]] = static_cast<float>(weight);
  }
  // Such a vocabulary transforms every image to an empty BoW vector.
  if (std::all_of(weighted.weights.begin(), weighted.weights.end(),
                  [](float weight) { return weight == 0.0f; })) {
    const bool in_every_image = std::all_of(counts.begin(), counts.end(), [&](std::uint32_t n) {
      return n == 0 || n == images.size();
    });
    if (idf && in_every_image) {
      throw InvalidArgument(std::string("Vocabulary::build: ") + to_string(options.weighting) +
                            " weighting needs at least two training images that differ: every "
                            "word appears in all " +
                            std::to_string(images.size()) +
                            " training images, so every word's IDF, log(N / N_i), is 0 and "
                            "every BoW vector would be empty; train on more images or use tf "
                            "weighting");
    }
    char fraction[32];
    std::snprintf(fraction, sizeof fraction, "%g", options.stop_word_fraction);
    throw InvalidArgument(std::string("Vocabulary::build: every word is a stop word (in more "
                                      "than stop_word_fraction = ") +
                          fraction + " of the " + std::to_string(images.size()) +
                          " training images), so every BoW vector would be empty; raise "
                          "stop_word_fraction");
  }
  return from_tree(weighted);
}

}  // namespace binbow
