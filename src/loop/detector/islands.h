// Islands and temporal consistency of the loop detector (paper Sections V-B
// and V-C), kept apart from LoopDetector so that each stage is testable alone.
#pragma once

#include <vector>

#include "binbow/types.h"

namespace binbow::loop::detail {

// A database entry that passed the α threshold, with its (normalised) score.
struct Candidate {
  EntryId entry = 0;
  double score = 0;
};

// A run of candidates with nearby entry ids: a place seen over consecutive images.
struct Island {
  EntryId first = 0;
  EntryId last = 0;
  double score = 0;        // H: sum of the candidates' scores
  EntryId best_entry = 0;  // the candidate with the highest score (lowest id on ties)
  double best_score = 0;

  int length() const { return static_cast<int>(last - first) + 1; }
};

// Sorts `candidates` by entry id and groups them: consecutive candidates j < j'
// belong to one island when j' − j < max_gap. Islands shorter than min_length
// (last − first + 1) are dropped. Islands come out in increasing entry order.
void compute_islands(std::vector<Candidate>& candidates, int max_gap, int min_length,
                     std::vector<Island>& islands);

// The island with the highest score; the earliest one on ties. Null if none.
const Island* best_island(const std::vector<Island>& islands);

// Counts how many successive queries matched islands that agree: the chain
// continues when the new query is at most max_distance_between_queries after
// the previous one and its island overlaps the previous island or lies at
// most max_distance_between_islands entries from it; otherwise it restarts.
class TemporalWindow {
 public:
  TemporalWindow(int max_distance_between_islands, int max_distance_between_queries)
      : max_island_distance_(max_distance_between_islands),
        max_query_distance_(max_distance_between_queries) {}

  // Records the best island of `query`; returns the length of the chain of
  // consistent queries, this one included (≥ 1).
  int update(const Island& island, EntryId query);
  int consistent() const { return consistent_; }
  void clear() { consistent_ = 0; }

  // What update() reads of the past (the last island's extent, not its
  // scores): saved and restored with the detector's state.
  struct State {
    int consistent = 0;
    EntryId last_first = 0, last_last = 0;
    EntryId last_query = 0;
  };
  State state() const { return {consistent_, last_island_.first, last_island_.last, last_query_}; }
  void restore(const State& state) {
    consistent_ = state.consistent;
    last_island_ = Island{};
    last_island_.first = state.last_first;
    last_island_.last = state.last_last;
    last_query_ = state.last_query;
  }

 private:
  int max_island_distance_;
  int max_query_distance_;
  int consistent_ = 0;
  Island last_island_;
  EntryId last_query_ = 0;
};

}  // namespace binbow::loop::detail
