// DBoW2's map-based vectors and query results: methods and printing.
#include <cmath>
#include <fstream>
#include <ostream>
#include <stdexcept>

#include "binbow/compat/BowVector.h"
#include "binbow/compat/FeatureVector.h"
#include "binbow/compat/QueryResults.h"

namespace DBoW2 {

namespace {
std::ofstream open_for_writing(const std::string& filename) {
  std::ofstream file(filename.c_str());
  if (!file) throw std::runtime_error(filename + ": cannot open the file for writing");
  return file;
}

void finish_writing(std::ofstream& file, const std::string& filename) {
  file.close();
  if (!file) throw std::runtime_error(filename + ": write failed");
}
}  // namespace

void BowVector::addWeight(WordId id, WordValue v) {
  iterator it = lower_bound(id);
  if (it != end() && it->first == id)
    it->second += v;
  else
    insert(it, value_type(id, v));
}

void BowVector::addIfNotExist(WordId id, WordValue v) {
  iterator it = lower_bound(id);
  if (it == end() || it->first != id) insert(it, value_type(id, v));
}

void BowVector::normalize(LNorm norm_type) {
  double norm = 0;
  if (norm_type == L1) {
    for (const auto& entry : *this) norm += std::fabs(entry.second);
  } else {
    for (const auto& entry : *this) norm += entry.second * entry.second;
    norm = std::sqrt(norm);
  }
  if (norm > 0)
    for (auto& entry : *this) entry.second /= norm;
}

std::ostream& operator<<(std::ostream& out, const BowVector& v) {
  const char* separator = "";
  for (const auto& entry : v) {
    out << separator << "<" << entry.first << ", " << entry.second << ">";
    separator = ", ";
  }
  return out;
}

void BowVector::saveM(const std::string& filename, std::size_t W) const {
  std::ofstream file = open_for_writing(filename);
  std::size_t next = 0;
  for (const auto& entry : *this) {
    for (; next < entry.first; ++next) file << "0 ";
    file << entry.second << " ";
    next = static_cast<std::size_t>(entry.first) + 1;
  }
  for (; next < W; ++next) file << "0 ";
  finish_writing(file, filename);
}

void FeatureVector::addFeature(NodeId id, unsigned int i_feature) {
  iterator it = lower_bound(id);
  if (it == end() || it->first != id) it = insert(it, value_type(id, std::vector<unsigned int>()));
  it->second.push_back(i_feature);
}

std::ostream& operator<<(std::ostream& out, const FeatureVector& v) {
  const char* separator = "";
  for (const auto& node : v) {
    out << separator << "<" << node.first << ": [";
    for (std::size_t i = 0; i < node.second.size(); ++i) out << (i ? ", " : "") << node.second[i];
    out << "]>";
    separator = ", ";
  }
  return out;
}

std::ostream& operator<<(std::ostream& os, const Result& ret) {
  return os << "<EntryId: " << ret.Id << ", Score: " << ret.Score << ">";
}

std::ostream& operator<<(std::ostream& os, const QueryResults& ret) {
  if (ret.size() == 1)
    os << "1 result:" << std::endl;
  else
    os << ret.size() << " results:" << std::endl;
  for (std::size_t i = 0; i < ret.size(); ++i) {
    os << ret[i];
    if (i + 1 != ret.size()) os << std::endl;
  }
  return os;
}

void QueryResults::saveM(const std::string& filename) const {
  std::ofstream file = open_for_writing(filename);
  for (const Result& result : *this) file << result.Id << " " << result.Score << std::endl;
  finish_writing(file, filename);
}

}  // namespace DBoW2
