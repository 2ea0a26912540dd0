// Queries through the inverted index: every part of the index (segment or
// tail) is scored in turn into per-thread sums (query_kernels.h), and its
// entries offered to the best results (query_ranking.h); fast mode finds
// candidates first and rescores them exactly.
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <limits>
#include <memory>
#include <mutex>
#include <shared_mutex>
#include <type_traits>
#include <utility>
#include <vector>

#include "binbow/database.h"
#include "core/parallel_for.h"
#include "core/scoring.h"
#include "database/database_impl.h"
#include "database/query_kernels.h"
#include "database/query_ranking.h"
#include "database/query_word_set.h"

namespace binbow {

namespace {

using namespace detail::query;

using detail::QueryWordSet;

// What one thread of a query writes: its part sums, its best results and
// (fast mode) its best candidates.
struct WorkerScratch {
  std::vector<EntryScore> scores;
  std::vector<QueryResult> best;
  std::vector<std::uint32_t> hits;    // ForwardIndex::for_each_shared's buffer
  std::vector<float> candidate_sums;  // a segment's, over the rare words
  BestCandidates candidates;          // of the parts it searched
  std::vector<RowCursor> rows;        // find_rows' of a segment
};

// Owned by the thread that calls query(); the threads it starts for that
// query use one WorkerScratch each, so their buffers outlive them.
struct QueryScratch {
  std::vector<WorkerScratch> workers;
  std::vector<BowEntry> rare_words;
  std::vector<QueryResult> best;      // fast mode's results
  std::vector<QueryResult> rescored;  // fast mode's candidates' exact results
  std::vector<std::pair<std::uint64_t, std::uint32_t>> word_postings;  // (postings, position)
  std::vector<std::uint32_t> rows;                                     // of the query's words
  std::vector<std::uint32_t> counted_segments;                         // rare_words'
  QueryWordSet query_words;
  std::vector<double> query_weights;  // ForwardIndex::word_weight of each query word
};

thread_local QueryScratch scratch;

// The context of one query: what it searches, how it ranks, and the
// calling thread's buffers (a worker thread's own thread_local ones would
// die with it).
struct QueryContext {
  const IndexView& index;
  Span<BowEntry> words;  // sorted by word id
  EntryId last_entry;
  Scoring scoring;
  bool minimums;   // L1 terms summed as minimums (MinimumTerm)
  bool unchecked;  // a loaded file's postings are not checked yet
  double base;
  std::size_t keep;              // results wanted, at most the live entries
  std::size_t visible_segments;  // those with an entry ≤ last_entry: a prefix
  bool tail_visible;
  unsigned workers;
  QueryScratch& buffers;
  std::size_t fast_candidates;      // QueryOptions'
  std::uint64_t fast_min_postings;  // QueryOptions'
  bool fast_every_entry;            // fast_candidates covers every entry searched

  std::size_t parts() const noexcept { return visible_segments + (tail_visible ? 1 : 0); }
  EntryId part_first(std::size_t part) const noexcept {
    return part < visible_segments ? index.segments[part]->first_entry : index.tail_first_entry;
  }
  std::size_t part_span(std::size_t part) const noexcept {
    const std::size_t end = std::size_t{last_entry} + 1;
    const std::size_t part_end =
        part < visible_segments ? index.segments[part]->end_entry : index.entry_count;
    return std::min(part_end, end) - part_first(part);
  }
  PartScores scores(unsigned worker) const {
    std::vector<EntryScore>& sums = buffers.workers[worker].scores;
    if (sums.size() < detail::kSegmentSpan) sums.resize(detail::kSegmentSpan);
    return PartScores{sums.data()};
  }
  // One BestResults per worker, keeping `keep_results` in `storage`.
  std::vector<BestResults> per_worker(std::size_t keep_results,
                                      std::vector<QueryResult> WorkerScratch::*storage) const {
    std::vector<BestResults> results;
    results.reserve(workers);
    for (unsigned w = 0; w < workers; ++w)
      results.emplace_back(scoring, minimums, base, keep_results, buffers.workers[w].*storage);
    return results;
  }
};

// Sums the terms of the query's words for the entries of a part and offers the part's
// live entries to `best`. Every term is computed and summed exactly as
// Vocabulary::score does (or, for MinimumTerm, as its exact equal), in the
// same order (increasing word id), so that with all the query's words the
// scores agree to the last bit: each entry lives in one segment or in the
// tail, whose pass visits the words in order.
template <class Term>
void score_part(const QueryContext& c, std::size_t part, unsigned worker, BestResults& best) {
  const PartScores scores = c.scores(worker);
  if (part < c.visible_segments)
    accumulate_segment<Term>(
        *c.index.segments[part], c.index.row_order, c.words, c.last_entry,
        {c.index.word_weights, c.index.divisors + c.index.segments[part]->first_entry}, scores,
        c.buffers.workers[worker].rows);
  else
    accumulate_tail<Term>(c.index, c.words, c.last_entry, scores);
  best.take_part(c.part_first(part), c.part_span(part), scores, c.index.alive, c.unchecked);
}

// The workers' results, merged: the order is total (ties by entry id), so
// the best ones do not depend on how the parts were shared.
std::vector<QueryResult> merged(std::vector<BestResults>& results) {
  for (std::size_t w = 1; w < results.size(); ++w) results[0].take_results(results[w]);
  return results[0].sorted();
}

template <class Term>
std::vector<QueryResult> exact_query(const QueryContext& c) {
  std::vector<BestResults> best = c.per_worker(c.keep, &WorkerScratch::best);
  detail::parallel_for(c.workers, c.parts(), [&](std::size_t part, unsigned worker) {
    score_part<Term>(c, part, worker, best[worker]);
  });
  return merged(best);
}

// Fast mode: the share of the query's postings read to find candidates, at
// least QueryOptions::fast_min_postings of them, and how many candidates
// are scored exactly (QueryOptions::fast_candidates, or fast_candidate_share
// of the entries). The defaults were chosen on a tuning set of real images
// (docs/benchmarks.md): four other noisy copies of each held-out photograph
// (296 queries, other seeds than the 148 the benchmark reports). At 200,000
// images, with at least 2^20 postings, 1000 candidates kept the exact top 10
// for all of them (with 2^18, 97.0%: a query of few postings read too few to
// tell near-copies apart; 800 candidates 99.3%, 600 98.0%; a share of 1/12
// or 1/16 of the postings 98.6%). At 1,000,000 each photograph has five
// times the near-copies: 1000 candidates kept 81.4%, 6000 98.3%, 8000
// 99.7%; at 500,000 2500 kept 98.99%, 3000 99.7%, 3249 all: the candidates
// needed grow as about N^1.3, and so does the default share
// (QueryOptions::candidates_for). Stopping the
// rescoring early (once 128 or 256 candidates in a row have not entered the
// top 10) kept 87.5% / 94.6% at 200,000: the exact best are spread over the
// whole candidate order, so every candidate is rescored.
constexpr double kFastPostingShare = 1.0 / 8;
// Of those, candidates whose sum is below kFastCandidateFloor times the sum
// of the max_results-th best are not rescored: near-copies of the query's
// best have sums close to theirs. On the tuning set at 1,000,000 images
// (8000 candidates), 0.5 and 0.6 kept the exact top 10 as often as no floor
// (99.7%), 0.65 and 0.7 98.99%; at 200,000 (1600 candidates) 0.7 rescored
// 1061 per query instead of 1346 and kept every top 10, 0.8 609 and 99.3%.
constexpr float kFastCandidateFloor = 0.6f;
// Small indexes are read whole (the candidates are then the exact best), and
// so is any index where skipping the other words would save fewer postings
// than kRescorePostings per word of the candidates (a query's size): a
// candidate's word costs about 3 postings (~6 µs per candidate of 1000 words,
// 2.2 ns per posting at 200,000 images), so between ~1M and ~3M postings per
// query fast mode can be slower than exact; 10,000 ORB-1000 images of the
// benchmark (600k postings per query) are read whole.
constexpr std::uint64_t kRescorePostings = 1;

// +1 where a larger sum of terms means a better score, -1 where a smaller.
float better_sign(Scoring scoring, bool minimums) {
  if (scoring == Scoring::kL1) return minimums ? 1.0f : -1.0f;
  return scoring == Scoring::kKL ? -1.0f : 1.0f;
}

// A count row's weight in an entry is word_weight * count / divisor, with
// the entry's divisor (the norm of its weighted counts). Candidates take the
// query's divisor for every entry's: the entries that compete for the best
// results are near-copies of the query, with about its divisor, and every
// candidate's score is computed exactly afterwards. On the tuning set at
// 200,000 images this kept the same top 10 as the entries' own divisors,
// 2-6% faster, as no divisor is read per entry. The query's divisor is
// word_weight / value of a word it counts once: the largest of those ratios
// (a word counted c times gives divisor / c). 1 for a query whose values
// give no usable divisor (not made by transform, or over word ids, where
// every word weight is 0): its candidates are still ranked by the weighted
// counts of the words they share. `word_weights`: of each query word, as
// ForwardIndex::word_weight gives them.
float inverse_query_divisor(Span<BowEntry> words, const std::vector<double>& word_weights) {
  double divisor = 0;
  for (std::size_t q = 0; q < words.size(); ++q)
    if (words[q].value >= std::numeric_limits<float>::min())
      divisor = std::max(divisor, word_weights[q] / words[q].value);
  const auto inverse = static_cast<float>(1.0 / divisor);
  return inverse >= std::numeric_limits<float>::min() && std::isfinite(inverse) ? inverse : 1.0f;
}

// Sums the rare words' terms of a segment's entries in floats, a stripe at
// a time, and offers its live entries with a positive sum to the worker's
// candidates. Rows are checked: a fast query waits for a loaded file's
// check.
template <class Term>
void find_candidates(const QueryContext& c, std::size_t part, Span<BowEntry> words, float sign,
                     float inverse_divisor, WorkerScratch& worker) {
  const detail::Segment& segment = *c.index.segments[part];
  std::vector<float>& sums = worker.candidate_sums;
  if (sums.size() < detail::kSegmentSpan) sums.resize(detail::kSegmentSpan);
  float* const out = sums.data();
  const std::uint32_t entry_bound = segment.end_entry - segment.first_entry - 1;
  std::fill(out, out + entry_bound + 1, 0.0f);
  const EntryId first_entry = segment.first_entry;
  const std::size_t span = c.part_span(part);
  BestCandidates& best = worker.candidates;
  std::vector<RowCursor>& rows = worker.rows;
  find_rows(segment, c.index.row_order, words, c.index.word_weights, rows);
  read_in_stripes(
      rows, entry_bound, detail::kRowStart,
      [&](RowCursor& row, std::uint32_t until) {
        const Term term{words[row.q].value};
        const float count_weight = row.word_weight * inverse_divisor;
        read_any_row(
            row, until,
            [&](std::uint32_t entry, float weight) {
              out[entry] += sign * static_cast<float>(term(weight));
            },
            [&](std::uint32_t entry, std::uint32_t count) {
              out[entry] +=
                  sign * static_cast<float>(term(count_weight * static_cast<float>(count)));
            });
      },
      [&](std::uint32_t first, std::uint32_t end) {
        for (std::size_t r = first; r < std::min<std::size_t>(end, span); ++r) {
          const float key = out[r];
          if (best.may_keep(key) && c.index.alive[first_entry + r] != 0)
            best.offer({key, static_cast<EntryId>(first_entry + r)});
        }
      });
}

// The tail's entries' sums over the rare words (exact terms, as a pass over
// the tail gives them: it is small), offered as find_candidates offers a
// segment's, so that its entries are rescored only where they compete.
template <class Term>
void find_tail_candidates(const QueryContext& c, Span<BowEntry> words, float sign,
                          unsigned worker) {
  const PartScores scores = c.scores(worker);
  accumulate_tail<Term>(c.index, words, c.last_entry, scores);
  BestCandidates& best = c.buffers.workers[worker].candidates;
  const EntryId first = c.index.tail_first_entry;
  const std::size_t span = c.part_span(c.visible_segments);
  for (std::size_t r = 0; r < span; ++r) {
    EntryScore& score = scores.entries[r];
    if (score.shared == 0) continue;
    const float key = sign * static_cast<float>(score.sum);
    if (best.may_keep(key) && c.index.alive[first + r] != 0)
      best.offer({key, static_cast<EntryId>(first + r)});
    score = {};
  }
}

// The query's words that find candidates, in word order: those that can add
// most to a score for the postings they cost (the query's value over the
// word's postings in the visible segments: rare words, and among them the
// heavy ones), up to kFastPostingShare of the query's postings or
// c.fast_min_postings (at least one word); all of them when fast mode would not
// pay off.
Span<BowEntry> rare_words(const QueryContext& c) {
  auto& postings = c.buffers.word_postings;
  const std::size_t n = c.words.size();
  postings.clear();
  for (std::size_t q = 0; q < n; ++q) postings.emplace_back(0, static_cast<std::uint32_t>(q));
  // A segment at a time, its rows' offsets and headers fetched ahead: each
  // is a cache miss, about as many as the query's rare postings otherwise.
  // The largest segments that hold a quarter of the postings are counted,
  // and their counts scaled to all: they tell rare words from common ones
  // as well as every segment does (the same agreement on the tuning set at
  // 200,000 images), and each segment counted costs a look-up per query
  // word (counting 15/16 of the postings cost 0.3-0.4 ms more per query).
  std::vector<std::uint32_t>& rows = c.buffers.rows;
  rows.clear();
  for (const BowEntry& e : c.words) rows.push_back(c.index.row_order.row(e.word));
  std::vector<std::uint32_t>& counted = c.buffers.counted_segments;
  counted.clear();
  std::uint64_t visible_postings = 0;
  for (std::uint32_t s = 0; s < c.visible_segments; ++s) {
    counted.push_back(s);
    visible_postings += c.index.segments[s]->postings();
  }
  std::sort(counted.begin(), counted.end(), [&](std::uint32_t a, std::uint32_t b) {
    const std::size_t pa = c.index.segments[a]->postings();
    const std::size_t pb = c.index.segments[b]->postings();
    return pa != pb ? pa > pb : a < b;
  });
  std::uint64_t counted_postings = 0;
  std::size_t counting = 0;
  while (counting < counted.size() && counted_postings < visible_postings / 4)
    counted_postings += c.index.segments[counted[counting++]]->postings();
  for (std::size_t k = 0; k < counting; ++k) {
    const detail::Segment& segment = *c.index.segments[counted[k]];
    const std::uint32_t* offsets = segment.offsets.data();
    for (std::size_t q = 0; q < n; ++q) {
      if (q + 2 * kPrefetchAhead < n) __builtin_prefetch(offsets + rows[q + 2 * kPrefetchAhead]);
      if (q + kPrefetchAhead < n)
        __builtin_prefetch(segment.bytes.data() + offsets[rows[q + kPrefetchAhead]]);
      postings[q].first += segment.row_postings(rows[q]);
    }
  }
  if (counted_postings < visible_postings) {
    const double scale = static_cast<double>(visible_postings) /
                         static_cast<double>(std::max<std::uint64_t>(1, counted_postings));
    for (auto& [count, q] : postings)
      count = static_cast<std::uint64_t>(static_cast<double>(count) * scale);
  }
  std::uint64_t total = 0;
  for (const auto& [count, q] : postings) total += count;
  // value_a / (postings_a + 1) > value_b / (postings_b + 1), without division;
  // ties by position, so the choice is deterministic.
  std::sort(postings.begin(), postings.end(), [&](const auto& a, const auto& b) {
    const double ka =
        static_cast<double>(c.words[a.second].value) * static_cast<double>(b.first + 1);
    const double kb =
        static_cast<double>(c.words[b.second].value) * static_cast<double>(a.first + 1);
    if (ka != kb) return ka > kb;
    return a.second < b.second;
  });
  const auto budget = std::max<std::uint64_t>(
      static_cast<std::uint64_t>(static_cast<double>(total) * kFastPostingShare),
      c.fast_min_postings);
  std::size_t taken = 0;
  std::uint64_t read = 0;
  for (; taken < postings.size(); ++taken) {
    if (read + postings[taken].first > budget && taken > 0) break;
    read += postings[taken].first;
  }
  // (total - read) / words < candidates * kRescorePostings, without overflow.
  if ((total - read) / c.words.size() / kRescorePostings < c.fast_candidates) return c.words;
  std::sort(postings.begin(), postings.begin() + static_cast<std::ptrdiff_t>(taken),
            [](const auto& a, const auto& b) { return a.second < b.second; });
  auto& rare = c.buffers.rare_words;
  rare.clear();
  for (std::size_t i = 0; i < taken; ++i) rare.push_back(c.words[postings[i].second]);
  return {rare.data(), rare.size()};
}

// The exact scores of candidates from their BoW vectors: the same terms,
// summed in the same order (increasing word id), as a pass over the index
// gives them.
template <class Term>
void rescore_candidates(const QueryContext& c, const Candidate* first, const Candidate* last,
                        QueryResult* out, WorkerScratch& worker, const BestResults& best) {
  const QueryWordSet& query = c.buffers.query_words;
  const detail::ForwardIndex& forward = *c.index.forward;
  for (const Candidate* candidate = first; candidate != last; ++candidate) {
    // Where the next-but-one's codes are, then the next one's codes.
    if (last - candidate > 2) forward.prefetch_location(candidate[2].entry);
    if (candidate + 1 != last) forward.prefetch(candidate[1].entry);
    double sum = 0;
    std::uint32_t shared = 0;
    forward.for_each_shared(candidate->entry, query, c.buffers.query_weights.data(), worker.hits,
                            [&](std::uint32_t q, float weight) {
                              sum += Term{c.words[q].value}(weight);
                              ++shared;
                            });
    *out++ = best.result(candidate->entry, sum, shared);
  }
}

template <class Term>
std::vector<QueryResult> fast_query(const QueryContext& c) {
  const Span<BowEntry> rare = rare_words(c);
  if (rare.size() == c.words.size()) return exact_query<Term>(c);  // a small index, read whole
  // Candidates from every part's rare words.
  const std::size_t keep = std::max(c.fast_candidates, c.keep);
  const float sign = better_sign(c.scoring, c.minimums);
  // The query words' vocabulary weights: the candidates' divisor, then
  // their rescoring.
  std::vector<double>& weights = c.buffers.query_weights;
  weights.clear();
  for (const BowEntry& e : c.words) weights.push_back(c.index.forward->word_weight(e.word));
  const float inverse_divisor = inverse_query_divisor(c.words, weights);
  for (unsigned w = 0; w < c.workers; ++w) c.buffers.workers[w].candidates.reset(keep);
  detail::parallel_for(c.workers, c.parts(), [&](std::size_t part, unsigned worker) {
    if (part == c.visible_segments)
      find_tail_candidates<Term>(c, rare, sign, worker);
    else
      find_candidates<Term>(c, part, rare, sign, inverse_divisor, c.buffers.workers[worker]);
  });
  std::vector<Candidate>& chosen = c.buffers.workers[0].candidates.best();
  for (unsigned w = 1; w < c.workers; ++w) {
    const std::vector<Candidate>& more = c.buffers.workers[w].candidates.best();
    chosen.insert(chosen.end(), more.begin(), more.end());
  }
  if (chosen.size() > keep) {
    std::nth_element(chosen.begin(), chosen.begin() + static_cast<std::ptrdiff_t>(keep),
                     chosen.end(), BetterCandidate{});
    chosen.resize(keep);
  }
  // Candidates far behind the best are not rescored (see kFastCandidateFloor),
  // unless every entry searched was asked for.
  if (chosen.size() > c.keep && !c.fast_every_entry) {
    const auto last_wanted = chosen.begin() + static_cast<std::ptrdiff_t>(c.keep - 1);
    std::nth_element(chosen.begin(), last_wanted, chosen.end(), BetterCandidate{});
    const float floor = kFastCandidateFloor * last_wanted->key;
    chosen.erase(std::remove_if(chosen.begin() + static_cast<std::ptrdiff_t>(c.keep), chosen.end(),
                                [floor](const Candidate& k) { return k.key < floor; }),
                 chosen.end());
  }
  // Rescored in entry order: their BoW vectors are then read in the order
  // they were stored.
  std::sort(chosen.begin(), chosen.end(),
            [](const Candidate& a, const Candidate& b) { return a.entry < b.entry; });
  c.buffers.query_words.assign(c.words);
  // Each candidate's exact score; then every result is offered in entry
  // order, so that the results do not depend on the threads.
  BestResults best(c.scoring, c.minimums, c.base, c.keep, c.buffers.best);
  std::vector<QueryResult>& rescored = c.buffers.rescored;
  rescored.resize(chosen.size());
  constexpr std::size_t kChunk = 64;
  detail::parallel_for(
      c.workers, (chosen.size() + kChunk - 1) / kChunk, [&](std::size_t chunk, unsigned worker) {
        const std::size_t first = chunk * kChunk;
        const std::size_t last = std::min(chosen.size(), first + kChunk);
        rescore_candidates<Term>(c, chosen.data() + first, chosen.data() + last,
                                 rescored.data() + first, c.buffers.workers[worker], best);
      });
  for (const QueryResult& result : rescored) best.offer(result);
  return best.sorted();
}

template <class Term>
std::vector<QueryResult> run_query(const QueryContext& c, QueryMode mode) {
  return mode == QueryMode::kFast ? fast_query<Term>(c) : exact_query<Term>(c);
}

std::vector<QueryResult> run_query(const QueryContext& c, QueryMode mode) {
  switch (c.scoring) {
    case Scoring::kL1:
      if (c.minimums) return run_query<MinimumTerm>(c, mode);
      return run_query<ScoringTerm<Scoring::kL1>>(c, mode);
    case Scoring::kL2:
      return run_query<ScoringTerm<Scoring::kL2>>(c, mode);
    case Scoring::kChiSquare:
      return run_query<ScoringTerm<Scoring::kChiSquare>>(c, mode);
    case Scoring::kKL:
      return run_query<ScoringTerm<Scoring::kKL>>(c, mode);
    case Scoring::kBhattacharyya:
      return run_query<ScoringTerm<Scoring::kBhattacharyya>>(c, mode);
    case Scoring::kDotProduct:
      return run_query<ScoringTerm<Scoring::kDotProduct>>(c, mode);
  }
  return {};
}

}  // namespace

std::atomic<std::size_t>& detail::postings_per_query_thread() {
  static std::atomic<std::size_t> postings{std::size_t{1} << 22};
  return postings;
}

std::vector<QueryResult> Database::query(const BowVector& bow, std::size_t max_results,
                                         EntryId max_entry_id) const {
  return query(bow, max_results, max_entry_id, QueryOptions{});
}

// By default N / kGrowingShareDivisor * (N / kGrowingShareEntries)^kGrowingShareExponent
// candidates for N entries (see QueryOptions::fast_candidate_share).
constexpr double kGrowingShareDivisor = 125;
constexpr double kGrowingShareEntries = 1e6;
constexpr double kGrowingShareExponent = 0.3;

std::size_t QueryOptions::candidates_for(std::size_t entries) const {
  const auto n = static_cast<double>(entries);
  const double candidates =
      fast_candidate_share
          ? *fast_candidate_share * n
          : n / kGrowingShareDivisor * std::pow(n / kGrowingShareEntries, kGrowingShareExponent);
  // At most every entry; none for a NaN share (check() refuses it).
  const double bounded = candidates > 0 ? std::min(std::ceil(candidates), n) : 0.0;
  return std::max(fast_candidates, static_cast<std::size_t>(bounded));
}

void QueryOptions::check() const {
  if (mode != QueryMode::kExact && mode != QueryMode::kFast)
    throw InvalidArgument("Database::query: unknown query mode " +
                          std::to_string(static_cast<int>(mode)));
  if (fast_candidates == 0)
    throw InvalidArgument("Database::query: fast_candidates must be at least 1");
  if (fast_candidate_share && !(*fast_candidate_share >= 0.0 && *fast_candidate_share <= 1.0))
    throw InvalidArgument("Database::query: fast_candidate_share must be in [0, 1], not " +
                          std::to_string(*fast_candidate_share));
}

std::vector<QueryResult> Database::query(const BowVector& bow, std::size_t max_results,
                                         EntryId max_entry_id, const QueryOptions& options) const {
  options.check();
  if (!impl_->over_word_ids) detail::check_bow_words(bow, impl_->vocabulary, "Database::query");
  detail::check_bow_values(bow, "Database::query");
  if (bow.empty() || max_results == 0) return {};
  const Scoring scoring = impl_->scoring;
  const double base = detail::score_base(scoring, bow);

  std::shared_lock lock(impl_->mutex);
  impl_->throw_if_damaged();
  // Over word ids, words beyond the capacity are in no entry yet: the index
  // is searched for the others (base() above still counts them, for KL).
  Span<BowEntry> searched(bow.begin(), bow.size());
  if (impl_->over_word_ids && bow[bow.size() - 1].word >= impl_->word_capacity) {
    const auto end =
        std::lower_bound(bow.begin(), bow.end(), impl_->word_capacity,
                         [](const BowEntry& e, std::size_t capacity) { return e.word < capacity; });
    searched = Span<BowEntry>(bow.begin(), static_cast<std::size_t>(end - bow.begin()));
    if (searched.empty()) return {};
  }
  const std::size_t entry_count = impl_->alive.size();
  if (impl_->live_entries == 0) return {};
  const EntryId last_entry = std::min<EntryId>(max_entry_id, static_cast<EntryId>(entry_count - 1));
  const IndexView index{impl_->segments,
                        impl_->tail_lists.data(),
                        impl_->arena,
                        impl_->tail_list_shift,
                        impl_->high_bits,
                        impl_->row_order,
                        impl_->tail_postings,
                        impl_->tail_first_entry,
                        impl_->alive.data(),
                        entry_count,
                        &impl_->forward,
                        impl_->over_word_ids ? nullptr : detail::word_weights(impl_->vocabulary),
                        impl_->divisors.data()};
  if (options.mode == QueryMode::kFast) impl_->build_forward_index();
  std::size_t visible = 0;
  std::size_t postings = impl_->tail_postings;
  for (const auto& segment : impl_->segments) {
    if (segment->first_entry > last_entry) break;
    ++visible;
    postings += segment->postings();
  }
  const bool tail_visible = impl_->tail_postings > 0 && impl_->tail_first_entry <= last_entry;
  const auto workers = static_cast<unsigned>(std::min<std::size_t>(
      {detail::resolve_thread_count(options.threads),
       std::max<std::size_t>(
           1, postings / std::max<std::size_t>(1, detail::postings_per_query_thread())),
       std::max<std::size_t>(1, visible + (tail_visible ? 1 : 0))}));
  QueryScratch& buffers = scratch;
  if (buffers.workers.size() < workers) buffers.workers.resize(workers);
  detail::ValueRange query_values;
  for (const BowEntry& e : searched) query_values.include(e.value);
  // While a loaded file's values are not known, L1 sums DBoW2's terms: the
  // same scores, to the last bit.
  detail::ValueRange index_values;
  const bool checked = impl_->index_values(index_values);
  const bool minimums = scoring == Scoring::kL1 && checked &&
                        detail::l1_terms_are_minimums(index_values, query_values);
  const std::size_t searched_entries =
      std::min<std::size_t>(impl_->live_entries, std::size_t{last_entry} + 1);
  const std::size_t candidates = options.candidates_for(searched_entries);
  const QueryContext context{index,
                             searched,
                             last_entry,
                             scoring,
                             minimums,
                             !checked,
                             base,
                             std::min(max_results, impl_->live_entries),
                             visible,
                             tail_visible,
                             workers,
                             buffers,
                             candidates,
                             options.fast_min_postings,
                             candidates >= searched_entries};
  std::vector<QueryResult> results = run_query(context, options.mode);
  lock.unlock();
  return results;
}

}  // namespace binbow
