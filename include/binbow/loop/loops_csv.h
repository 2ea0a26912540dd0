// loops.csv: the detections file written by `binbow detect-loops` and read
// by `binbow evaluate`.
#pragma once

#include <cstddef>
#include <string>
#include <vector>

namespace binbow::loop {

// One detected loop: a row of loops.csv.
struct Detection {
  std::size_t query = 0;  // 0-based index in input order
  std::size_t match = 0;
  std::string query_file;
  std::string match_file;
  double score = 0;
  std::size_t inliers = 0;
};

// loops.csv: header `query_index,match_index,query_file,match_file,score,inliers`
// and one row per detection (RFC 4180 quoting of file names; scores finite).
// Written atomically; reading throws FileError naming the file and line, and
// takes about 100 bytes per row plus the file names longer than 15
// characters (at most ~10 times the file's size; files up to 2 GiB).
//
// read_detections_csv also reads other tools' loops: any CSV whose header
// names a `query` (or `query_index`) and a `match` (or `match_index`) column,
// 0-based frame indices, in any order and beside any other columns
// (`query_file`, `match_file`, `score` and `inliers` are taken when present;
// names are case-insensitive, spaces around fields ignored). Every row has the
// header's number of fields, and its match is earlier than its query.
void write_detections_csv(const std::string& path, const std::vector<Detection>& detections);
// The text write_detections_csv writes, header included.
std::string format_detections_csv(const std::vector<Detection>& detections);
std::vector<Detection> read_detections_csv(const std::string& path);

}  // namespace binbow::loop
