// Reads tests/compat/dbow2_golden.txt: numbers produced by DBoW2 itself (see
// the file's header). C++11 and DBoW2-API only, so that the installed-package
// consumer (tests/package/dbow2) compares against the same numbers.
#ifndef BINBOW_TESTS_COMPAT_DBOW2_GOLDEN_H
#define BINBOW_TESTS_COMPAT_DBOW2_GOLDEN_H

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <map>
#include <sstream>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include "binbow/compat/DBoW2.h"

namespace dbow2_golden {

// The consumer programs' tally of numbers that differ from DBoW2's; check()
// names each one on stderr.
inline int& mismatches() {
  static int count = 0;
  return count;
}
inline void check(bool ok, const std::string& what) {
  if (!ok) {
    std::fprintf(stderr, "mismatch: %s\n", what.c_str());
    ++mismatches();
  }
}

struct Query {
  std::string scoring;
  unsigned int image;
  int max_results;
  int max_id;
  std::vector<std::pair<DBoW2::EntryId, double> > results;
};

struct Golden {
  int k, L, weighting, scoring;
  unsigned int words;
  std::vector<std::vector<cv::Mat> > images;
  std::vector<std::vector<DBoW2::WordId> > feature_words;  // per image
  std::map<DBoW2::WordId, double> weights;
  // nodes[levelsup][image][feature]; undefined[...] is true where DBoW2 leaves it undefined
  std::vector<std::vector<std::vector<DBoW2::NodeId> > > nodes;
  std::vector<std::vector<std::vector<bool> > > undefined;
  std::map<std::pair<int, int>, DBoW2::FeatureVector> feature_vectors;  // (levelsup, image)
  std::map<DBoW2::WordId, std::vector<DBoW2::NodeId> > parents;         // levelsup 0..L+1
  // (weighting, scoring, image) -> BoW vector; names as DBoW2's enums
  std::map<std::pair<std::pair<std::string, std::string>, int>, DBoW2::BowVector> bows;
  std::map<std::pair<std::string, std::string>, std::vector<double> > scores;  // row-major
  double stop_min_weight;
  int stopped_words;
  int stop_image, stop_levelsup;
  DBoW2::BowVector stop_bow;
  DBoW2::FeatureVector stop_fv;
  std::vector<Query> queries;
};

inline DBoW2::WeightingType weighting_named(const std::string& name) {
  const char* names[] = {"TF_IDF", "TF", "IDF", "BINARY"};
  for (int i = 0; i < 4; ++i)
    if (name == names[i]) return static_cast<DBoW2::WeightingType>(i);
  throw std::runtime_error("unknown weighting " + name);
}

inline DBoW2::ScoringType scoring_named(const std::string& name) {
  const char* names[] = {"L1_NORM", "L2_NORM", "CHI_SQUARE", "KL", "BHATTACHARYYA", "DOT_PRODUCT"};
  for (int i = 0; i < 6; ++i)
    if (name == names[i]) return static_cast<DBoW2::ScoringType>(i);
  throw std::runtime_error("unknown scoring " + name);
}

inline DBoW2::BowVector read_bow(std::istringstream& in) {
  std::size_t size = 0;
  in >> size;
  DBoW2::BowVector v;
  for (std::size_t i = 0; i < size; ++i) {
    std::string item;
    in >> item;
    const std::size_t colon = item.find(':');
    v[static_cast<DBoW2::WordId>(std::strtoul(item.c_str(), NULL, 10))] =
        std::strtod(item.c_str() + colon + 1, NULL);
  }
  return v;
}

inline DBoW2::FeatureVector read_fv(std::istringstream& in) {
  std::size_t size = 0;
  in >> size;
  DBoW2::FeatureVector fv;
  for (std::size_t i = 0; i < size; ++i) {
    std::string item;
    in >> item;
    const std::size_t colon = item.find(':');
    std::vector<unsigned int>& features =
        fv[static_cast<DBoW2::NodeId>(std::strtoul(item.c_str(), NULL, 10))];
    std::istringstream list(item.substr(colon + 1));
    std::string number;
    while (std::getline(list, number, ','))
      features.push_back(static_cast<unsigned int>(std::strtoul(number.c_str(), NULL, 10)));
  }
  return fv;
}

inline Golden read(const std::string& path) {
  std::ifstream file(path.c_str());
  if (!file) throw std::runtime_error(path + ": cannot open the golden file");
  Golden g;
  g.k = g.L = g.weighting = g.scoring = -1;
  g.words = 0;
  std::string line;
  while (std::getline(file, line)) {
    if (line.empty() || line[0] == '#') continue;
    std::istringstream in(line);
    std::string key;
    in >> key;
    if (key == "vocabulary") {
      in >> g.k >> g.L >> g.weighting >> g.scoring >> g.words;
      g.nodes.resize(g.L + 1);
      g.undefined.resize(g.L + 1);
    } else if (key == "image") {
      std::size_t index = 0, count = 0;
      in >> index >> count;
      std::vector<cv::Mat> descriptors;
      for (std::size_t i = 0; i < count && std::getline(file, line); ++i) {
        cv::Mat d(1, 32, CV_8U);
        for (int b = 0; b < 32; ++b)
          d.at<unsigned char>(0, b) =
              static_cast<unsigned char>(std::strtoul(line.substr(2 * b, 2).c_str(), NULL, 16));
        descriptors.push_back(d);
      }
      g.images.push_back(descriptors);
    } else if (key == "words") {
      std::size_t image = 0;
      in >> image;
      std::vector<DBoW2::WordId> words;
      DBoW2::WordId w;
      while (in >> w) words.push_back(w);
      g.feature_words.push_back(words);
    } else if (key == "weights") {
      std::string item;
      while (in >> item)
        g.weights[static_cast<DBoW2::WordId>(std::strtoul(item.c_str(), NULL, 10))] =
            std::strtod(item.c_str() + item.find(':') + 1, NULL);
    } else if (key == "nodes") {
      int up = 0, image = 0;
      in >> up >> image;
      std::vector<DBoW2::NodeId> nodes;
      std::vector<bool> undefined;
      std::string item;
      while (in >> item) {
        nodes.push_back(static_cast<DBoW2::NodeId>(std::strtoul(item.c_str(), NULL, 10)));
        undefined.push_back(item[item.size() - 1] == '*');
      }
      g.nodes[up].push_back(nodes);
      g.undefined[up].push_back(undefined);
    } else if (key == "fv") {
      int up = 0, image = 0;
      in >> up >> image;
      g.feature_vectors[std::make_pair(up, image)] = read_fv(in);
    } else if (key == "parent") {
      DBoW2::WordId w = 0;
      in >> w;
      DBoW2::NodeId n;
      while (in >> n) g.parents[w].push_back(n);
    } else if (key == "bow") {
      std::string weighting, scoring;
      int image = 0;
      in >> weighting >> scoring >> image;
      g.bows[std::make_pair(std::make_pair(weighting, scoring), image)] = read_bow(in);
    } else if (key == "scores") {
      std::string weighting, scoring;
      in >> weighting >> scoring;
      std::vector<double>& scores = g.scores[std::make_pair(weighting, scoring)];
      double s;
      while (in >> s) scores.push_back(s);
    } else if (key == "stopwords") {
      in >> g.stop_min_weight >> g.stopped_words;
    } else if (key == "stopbow") {
      in >> g.stop_image;
      g.stop_bow = read_bow(in);
    } else if (key == "stopfv") {
      int image = 0;
      in >> g.stop_levelsup >> image;
      g.stop_fv = read_fv(in);
    } else if (key == "query") {
      Query q;
      std::size_t count = 0;
      in >> q.scoring >> q.image >> q.max_results >> q.max_id >> count;
      std::string item;
      while (in >> item)
        q.results.push_back(
            std::make_pair(static_cast<DBoW2::EntryId>(std::strtoul(item.c_str(), NULL, 10)),
                           std::strtod(item.c_str() + item.find(':') + 1, NULL)));
      if (q.results.size() != count) throw std::runtime_error(path + ": bad query line " + line);
      g.queries.push_back(q);
    } else {
      throw std::runtime_error(path + ": unknown line " + line);
    }
  }
  if (g.images.empty() || g.queries.empty() || g.bows.empty())
    throw std::runtime_error(path + ": incomplete golden file");
  return g;
}

// |a - b| within `relative` of the larger magnitude (absolute near zero).
inline bool close(double a, double b, double relative) {
  const double scale = std::max(std::max(std::abs(a), std::abs(b)), 1e-12);
  return std::abs(a - b) <= relative * scale;
}

}  // namespace dbow2_golden

#endif
