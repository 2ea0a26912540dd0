#include "loop/detector/islands.h"

#include <algorithm>

namespace binbow::loop::detail {

void compute_islands(std::vector<Candidate>& candidates, int max_gap, int min_length,
                     std::vector<Island>& islands) {
  islands.clear();
  if (candidates.empty()) return;
  std::sort(candidates.begin(), candidates.end(),
            [](const Candidate& a, const Candidate& b) { return a.entry < b.entry; });
  Island current{candidates[0].entry, candidates[0].entry, candidates[0].score, candidates[0].entry,
                 candidates[0].score};
  const auto close_island = [&] {
    if (current.length() >= min_length) islands.push_back(current);
  };
  for (std::size_t i = 1; i < candidates.size(); ++i) {
    const Candidate& c = candidates[i];
    if (static_cast<long long>(c.entry) - static_cast<long long>(current.last) < max_gap) {
      current.last = c.entry;
      current.score += c.score;
      if (c.score > current.best_score) {
        current.best_score = c.score;
        current.best_entry = c.entry;
      }
    } else {
      close_island();
      current = Island{c.entry, c.entry, c.score, c.entry, c.score};
    }
  }
  close_island();
}

const Island* best_island(const std::vector<Island>& islands) {
  const Island* best = nullptr;
  for (const Island& island : islands)
    if (best == nullptr || island.score > best->score) best = &island;
  return best;
}

int TemporalWindow::update(const Island& island, EntryId query) {
  const long long query_gap = static_cast<long long>(query) - static_cast<long long>(last_query_);
  if (consistent_ == 0 || query_gap > max_query_distance_) {
    consistent_ = 1;
  } else {
    const long long a1 = last_island_.first, a2 = last_island_.last;
    const long long b1 = island.first, b2 = island.last;
    const bool overlap = (b1 <= a1 && a1 <= b2) || (a1 <= b1 && b1 <= a2);
    const long long gap = std::max(a1 - b2, b1 - a2);
    consistent_ = (overlap || gap <= max_island_distance_) ? consistent_ + 1 : 1;
  }
  last_island_ = island;
  last_query_ = query;
  return consistent_;
}

}  // namespace binbow::loop::detail
