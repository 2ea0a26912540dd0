// DBoW2 compatibility layer: results of database queries, as DBoW2 declares them.
//
// C++11, standard library only (see DBoW2.h).
#ifndef BINBOW_COMPAT_DBOW2_QUERY_RESULTS_H
#define BINBOW_COMPAT_DBOW2_QUERY_RESULTS_H

#include <iosfwd>
#include <string>
#include <vector>

namespace DBoW2 {

/// Id of an image in a database: 0, 1, 2, ... in the order of addition.
typedef unsigned int EntryId;

/// One query result.
class Result {
 public:
  EntryId Id;
  /// The similarity under the database's scoring type.
  double Score;
  /// Words shared by the query and the entry (DBoW2 fills it only for
  /// CHI_SQUARE and BHATTACHARYYA; binbow fills it for every scoring type).
  int nWords;
  /// Copies of Score for BHATTACHARYYA and CHI_SQUARE queries respectively
  /// (0 otherwise), as DBoW2 fills them.
  double bhatScore, chiScore;
  /// DBoW2's debugging sums of CHI_SQUARE queries; binbow leaves them 0.
  double sumCommonVi;
  double sumCommonWi;
  double expectedChiScore;

  Result()
      : Id(0),
        Score(0),
        nWords(0),
        bhatScore(0),
        chiScore(0),
        sumCommonVi(0),
        sumCommonWi(0),
        expectedChiScore(0) {}
  Result(EntryId _id, double _score)
      : Id(_id),
        Score(_score),
        nWords(0),
        bhatScore(0),
        chiScore(0),
        sumCommonVi(0),
        sumCommonWi(0),
        expectedChiScore(0) {}

  /// Comparisons by score, and equality with an entry id, as DBoW2's.
  bool operator<(const Result& r) const { return Score < r.Score; }
  bool operator>(const Result& r) const { return Score > r.Score; }
  bool operator==(EntryId id) const { return Id == id; }
  bool operator<(double s) const { return Score < s; }
  bool operator>(double s) const { return Score > s; }
  static bool gt(const Result& a, const Result& b) { return a.Score > b.Score; }
  static bool ge(const Result& a, const Result& b) { return a.Score > b.Score; }
  static bool geq(const Result& a, const Result& b) { return a.Score >= b.Score; }
  static bool geqv(const Result& a, double s) { return a.Score >= s; }
  static bool ltId(const Result& a, const Result& b) { return a.Id < b.Id; }

  /// Prints "<EntryId: id, Score: score>".
  friend std::ostream& operator<<(std::ostream& os, const Result& ret);
};

std::ostream& operator<<(std::ostream& os, const Result& ret);

/// The results of one query, best first.
class QueryResults : public std::vector<Result> {
 public:
  /// Multiplies every score by `factor`.
  void scaleScores(double factor) {
    for (iterator it = begin(); it != end(); ++it) it->Score *= factor;
  }
  /// Prints "N results:" then one result per line, as DBoW2 does.
  friend std::ostream& operator<<(std::ostream& os, const QueryResults& ret);
  /// Writes "id score" lines to a text file. Throws std::runtime_error naming
  /// the file if it cannot be written.
  void saveM(const std::string& filename) const;
};

std::ostream& operator<<(std::ostream& os, const QueryResults& ret);

}  // namespace DBoW2

#endif
