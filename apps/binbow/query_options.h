// --fast and its tuning, for the commands that query a Database: they fill a
// QueryOptions, whose defaults the help shows, and refuse what
// Database::query refuses before any work.
#pragma once

#include <CLI/CLI.hpp>

#include "binbow/database.h"
#include "validators.h"

namespace binbow::cli {

// `options` (default-constructed by the caller) gets mode kFast from --fast
// and the fast_* fields from the options of the same names, which need --fast.
inline void add_fast_query_options(CLI::App* command, QueryOptions& options) {
  CLI::Option* fast = command->add_flag_callback(
      "--fast", [&options] { options.mode = QueryMode::kFast; },
      "Fast mode for large databases: candidates from each query's rarest words, every score "
      "exact (an entry can be missed, never misranked; keeps a copy of each entry's words)");
  command
      ->add_option("--fast-candidates", options.fast_candidates,
                   "Entries each query scores exactly, at least: more finds more of the exact "
                   "best, slower")
      ->check(checked_number<long long>([](long long n) { return n >= 1; }, "at least 1"))
      ->needs(fast)
      ->capture_default_str();
  command
      ->add_option_function<double>(
          "--fast-candidate-share",
          [&options](double share) { options.fast_candidate_share = share; },
          "The candidates as a share of the entries searched, where that is more than "
          "--fast-candidates (default: a share that grows with the N entries searched, "
          "N/125 * (N/10^6)^0.3 candidates)")
      ->check(checked_number<double>([](double x) { return x >= 0.0 && x <= 1.0; }, "in [0, 1]"))
      ->needs(fast);
  command
      ->add_option("--fast-min-postings", options.fast_min_postings,
                   "Postings of its rarest words each query reads at least to find its "
                   "candidates, where that is more than an eighth of its postings")
      ->check(checked_number<long long>([](long long n) { return n >= 0; }, "at least 0"))
      ->needs(fast)
      ->capture_default_str();
}

}  // namespace binbow::cli
