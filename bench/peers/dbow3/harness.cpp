// binbow against DBoW3, side by side in one process on the same trained
// vocabulary (binbow's .bbw, and the same tree written as .dbow3 and as
// ORB-SLAM text by `binbow convert`, read by DBoW3's own loader) and the same
// real ORB descriptors. Calls interleaved, the first library alternating;
// thread CPU time (process CPU time for loads, which may use threads).
//
//   harness --bbw V.bbw --dbow3 V.dbow3 [--text V.txt] [--reps N]
//           [--tables load,transform,database] [--entries N] [--queries N]
//
// Prints one Markdown table per part, each figure as min–max over the
// repetitions (median), and checks that both libraries agree: the same BoW
// vectors for every image, the same top 10 for every query. Exit 3 when they
// do not (a ratio of different answers means nothing).
//
// load       Vocabulary::load(.bbw, checksums verified) / DBoW3 load(.dbow3);
//            load_vocabulary(ORB-SLAM text) / DBoW3 load(.txt).
// transform  38 images of 1000 ORB descriptors (rtabmap-samples at twice
//            their size): BoW vector; BoW + feature vector 4 levels up.
// database   entries: ORB-1000 of the 84 rtabmap-samples frames and the 4
//            DBoW2 demo images at 8 scales, plain and mirrored, pooled scale
//            by scale (every image at one scale, then at the next) and read
//            as overlapping windows of 1000 rows (neighbouring
//            entries share most descriptors, as neighbouring keyframes do);
//            queries: the same images at 3 other scales. Each repetition
//            fills fresh databases of both (direct index 4 levels up) with the
//            BoW and feature vectors given, 0 → 1,000 → N, querying the top 10
//            at 1,000 and N, then fresh ones 0 → 1,000 from descriptors
//            (transform included). Memory per entry: malloc's heap growth
//            during each library's adds.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <functional>
#include <iostream>
#include <memory>
#include <set>
#include <sstream>
#include <string>
#include <vector>

#include <DBoW3/DBoW3.h>

#include "binbow/database.h"
#include "binbow/formats.h"
#include "binbow/vocabulary.h"
#include "peer_bench.h"

namespace {

using peers::spread;

struct Options {
  std::string bbw, dbow3, text;
  int reps = 3;
  std::set<std::string> tables{"load", "transform", "database"};
  std::size_t entries = 10000;
  std::size_t queries = 200;
};

[[noreturn]] void usage(const std::string& message) {
  std::fprintf(stderr,
               "harness: %s\nusage: harness --bbw V.bbw --dbow3 V.dbow3 [--text V.txt] [--reps N]\n"
               "       [--tables load,transform,database] [--entries N] [--queries N]\n",
               message.c_str());
  std::exit(2);
}

Options parse(int argc, char** argv) {
  Options o;
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    auto next = [&]() -> std::string {
      if (i + 1 >= argc) usage(a + " needs a value");
      return argv[++i];
    };
    if (a == "--bbw") {
      o.bbw = next();
    } else if (a == "--dbow3") {
      o.dbow3 = next();
    } else if (a == "--text") {
      o.text = next();
    } else if (a == "--reps") {
      o.reps = std::stoi(next());
    } else if (a == "--entries") {
      o.entries = std::stoul(next());
    } else if (a == "--queries") {
      o.queries = std::stoul(next());
    } else if (a == "--tables") {
      o.tables.clear();
      std::stringstream list(next());
      for (std::string t; std::getline(list, t, ',');) o.tables.insert(t);
    } else {
      usage("unknown argument " + a);
    }
  }
  if (o.bbw.empty() || o.dbow3.empty()) usage("--bbw and --dbow3 are required");
  if (o.tables.count("load") && o.text.empty()) usage("the load table needs --text");
  if (o.reps < 1 || o.entries < 1000) usage("--reps must be >= 1 and --entries >= 1000");
  return o;
}

// A table row: each library's figure per repetition and the ratio DBoW3 /
// binbow of each repetition's figures.
struct Row {
  std::string label;
  const char* format;  // of one library's figure
  std::vector<double> binbow, dbow3;
  void print() const {
    std::vector<double> ratio;
    for (std::size_t i = 0; i < binbow.size(); ++i) ratio.push_back(dbow3[i] / binbow[i]);
    std::printf("| %s | %s | %s | **%s** |\n", label.c_str(), spread(binbow, format).c_str(),
                spread(dbow3, format).c_str(), spread(ratio, "%.1fx").c_str());
  }
};

void table_head(const char* title) {
  std::printf("\n%s\n\n| | binbow | DBoW3 | DBoW3 / binbow |\n| --- | ---: | ---: | ---: |\n",
              title);
}

// Runs a and b in the order the repetition asks for; returns their times.
std::pair<double, double> interleaved(bool a_first, const std::function<double()>& a,
                                      const std::function<double()>& b) {
  double ta, tb;
  if (a_first) {
    ta = a();
    tb = b();
  } else {
    tb = b();
    ta = a();
  }
  return {ta, tb};
}

bool same_bow(const binbow::BowVector& a, const DBoW3::BowVector& b) {
  if (a.size() != b.size()) return false;
  auto it = b.begin();
  for (const binbow::BowEntry& e : a) {
    if (e.word != it->first) return false;
    if (std::fabs(e.value - it->second) > 1e-5 * std::fabs(it->second)) return false;
    ++it;
  }
  return true;
}

void load_table(const Options& o) {
  Row own{"own binary format (`.bbw` verified / `.dbow3`), ms CPU", "%.1f", {}, {}};
  Row text{"ORB-SLAM text, the same file, ms CPU", "%.0f", {}, {}};
  for (int rep = 0; rep < o.reps; ++rep) {
    const bool binbow_first = rep % 2 == 0;
    auto [b, d] = interleaved(
        binbow_first,
        [&] {
          const double t0 = peers::process_cpu_us();
          const binbow::Vocabulary v = binbow::Vocabulary::load(o.bbw);
          return (peers::process_cpu_us() - t0) * 1e-3;
        },
        [&] {
          const double t0 = peers::process_cpu_us();
          DBoW3::Vocabulary v;
          v.load(o.dbow3);
          return (peers::process_cpu_us() - t0) * 1e-3;
        });
    own.binbow.push_back(b);
    own.dbow3.push_back(d);
    std::tie(b, d) = interleaved(
        binbow_first,
        [&] {
          const double t0 = peers::process_cpu_us();
          const binbow::Vocabulary v =
              binbow::load_vocabulary(o.text, binbow::VocabularyFormat::kOrbSlamText);
          return (peers::process_cpu_us() - t0) * 1e-3;
        },
        [&] {
          // DBoW3's text reader draws a dot per 100 lines on std::cerr: not shown.
          std::streambuf* const cerr_buffer = std::cerr.rdbuf(nullptr);
          const double t0 = peers::process_cpu_us();
          DBoW3::Vocabulary v;
          v.load(o.text);
          const double t = (peers::process_cpu_us() - t0) * 1e-3;
          std::cerr.rdbuf(cerr_buffer);
          return t;
        });
    text.binbow.push_back(b);
    text.dbow3.push_back(d);
  }
  table_head("**Load the vocabulary** (process CPU time, each load once per repetition):");
  own.print();
  text.print();
}

void transform_table(const binbow::Vocabulary& bb, const DBoW3::Vocabulary& db, const Options& o) {
  const std::vector<cv::Mat> images = peers::rtabmap_images_of_1000();
  std::size_t mismatches = 0;
  for (const cv::Mat& m : images) {
    binbow::BowVector bv;
    bb.transform(peers::view(m), bv);
    DBoW3::BowVector dv;
    db.transform(m, dv);
    if (!same_bow(bv, dv)) ++mismatches;
  }
  std::printf("\ncheck transform: %zu images of 1000, %zu with different BoW vectors\n",
              images.size(), mismatches);
  if (mismatches != 0) std::exit(3);

  // DBoW3 takes a cv::Mat for the BoW vector alone, one cv::Mat per row for
  // the feature vector: the rows are split before timing.
  std::vector<std::vector<cv::Mat>> rows;
  for (const cv::Mat& m : images) rows.push_back(peers::rows_of(m));
  Row bow{"BoW vector, µs", "%.0f", {}, {}};
  Row fv{"+ feature vector at levels up 4, µs", "%.0f", {}, {}};
  binbow::BowVector bv;
  binbow::FeatureVector bf;
  DBoW3::BowVector dv;
  DBoW3::FeatureVector df;
  for (int rep = 0; rep < o.reps; ++rep) {
    std::vector<double> tb, td, tbf, tdf;
    for (std::size_t i = 0; i < images.size(); ++i) {
      const cv::Mat& m = images[i];
      const bool binbow_first = (rep + i) % 2 == 0;
      auto [b, d] = interleaved(
          binbow_first,
          [&] {
            const double t0 = peers::thread_cpu_us();
            bb.transform(peers::view(m), bv);
            return peers::thread_cpu_us() - t0;
          },
          [&] {
            const double t0 = peers::thread_cpu_us();
            db.transform(m, dv);
            return peers::thread_cpu_us() - t0;
          });
      tb.push_back(b);
      td.push_back(d);
      std::tie(b, d) = interleaved(
          binbow_first,
          [&] {
            const double t0 = peers::thread_cpu_us();
            bb.transform(peers::view(m), bv, bf, 4);
            return peers::thread_cpu_us() - t0;
          },
          [&] {
            const double t0 = peers::thread_cpu_us();
            db.transform(rows[i], dv, df, 4);
            return peers::thread_cpu_us() - t0;
          });
      tbf.push_back(b);
      tdf.push_back(d);
    }
    bow.binbow.push_back(peers::median(tb));
    bow.dbow3.push_back(peers::median(td));
    fv.binbow.push_back(peers::median(tbf));
    fv.dbow3.push_back(peers::median(tdf));
  }
  table_head(
      "**Transform 1000 descriptors** (thread CPU time, median of the images per repetition):");
  bow.print();
  fv.print();
}

// The database part's descriptors: entries as overlapping windows of a pool,
// queries as images of their own.
struct DatabaseData {
  std::vector<cv::Mat> entries, queries;
};

DatabaseData database_data(std::size_t entries, std::size_t queries) {
  const std::vector<std::string> files =
      peers::images_in({"rtabmap-samples/samples", "dbow2-demo-images"});
  cv::Mat pool;
  for (const double scale : {0.6, 0.7, 0.8, 0.9, 1.0, 1.1, 1.25, 1.4})
    for (const bool mirrored : {false, true})
      for (const std::string& f : files)
        pool.push_back(peers::orb_descriptors(f, 1000, scale, mirrored));
  DatabaseData out;
  const double step = double(pool.rows - 1000) / double(entries - 1);
  for (std::size_t i = 0; i < entries; ++i) {
    const int first = static_cast<int>(i * step);
    out.entries.push_back(pool.rowRange(first, first + 1000));
  }
  for (const double scale : {0.65, 0.95, 1.3})
    for (const std::string& f : files) {
      if (out.queries.size() == queries) break;
      out.queries.push_back(peers::orb_descriptors(f, 1000, scale));
    }
  std::printf(
      "\ndatabase data: %zu images → %d descriptors in %zu entries of 1000 (a step of "
      "%.0f rows); %zu queries\n",
      files.size() * 16, pool.rows, out.entries.size(), step, out.queries.size());
  return out;
}

void database_table(const binbow::Vocabulary& bb, const DBoW3::Vocabulary& db, const Options& o) {
  const DatabaseData data = database_data(o.entries, o.queries);
  const std::size_t n = data.entries.size();
  // The queries' vectors, each library's own, checked equal. The entries'
  // are made just before each add (untimed): stored, DBoW3's alone would
  // take ~10 GB at 100,000 entries.
  std::size_t mismatches = 0;
  std::vector<binbow::BowVector> bq(data.queries.size());
  std::vector<DBoW3::BowVector> dq(data.queries.size());
  for (std::size_t i = 0; i < data.queries.size(); ++i) {
    bb.transform(peers::view(data.queries[i]), bq[i]);
    db.transform(data.queries[i], dq[i]);
    if (!same_bow(bq[i], dq[i])) ++mismatches;
  }
  if (mismatches != 0) {
    std::printf("check query vectors: %zu differ\n", mismatches);
    std::exit(3);
  }

  const std::string big = std::to_string(n);
  Row add{"add, BoW + direct index given (mean over 0 → " + big + "), µs", "%.0f", {}, {}};
  Row add_desc{"add from descriptors, transform included (mean over 0 → 1k), ms", "%.2f", {}, {}};
  Row q1k{"query top 10, N = 1,000 (median of the queries), ms", "%.2f", {}, {}};
  Row qn{"query top 10, N = " + big + ", ms", "%.2f", {}, {}};
  Row mem1k{"memory per entry, N = 1,000, KiB", "%.1f", {}, {}};
  Row memn{"memory per entry, N = " + big + ", KiB", "%.1f", {}, {}};
  std::size_t queries_compared = 0, queries_differing = 0;

  for (int rep = 0; rep < o.reps; ++rep) {
    auto bdb = std::make_unique<binbow::Database>(bb, binbow::DatabaseOptions{true, 4});
    auto ddb = std::make_unique<DBoW3::Database>(db, true, 4);
    double heap_b = 0, heap_d = 0, sum_b = 0, sum_d = 0;
    binbow::BowVector bv;
    binbow::FeatureVector bf;
    DBoW3::BowVector dv;
    DBoW3::FeatureVector df;
    auto timed_add = [&](std::size_t i) {
      bb.transform(peers::view(data.entries[i]), bv, bf, 4);
      db.transform(peers::rows_of(data.entries[i]), dv, df, 4);
      if (!same_bow(bv, dv)) ++mismatches;
      auto [b, d] = interleaved((rep + i) % 2 == 0,
                                [&] {
                                  const double h = peers::heap_bytes(), t0 = peers::thread_cpu_us();
                                  bdb->add(bv, bf);
                                  const double t = peers::thread_cpu_us() - t0;
                                  heap_b += peers::heap_bytes() - h;
                                  return t;
                                },
                                [&] {
                                  const double h = peers::heap_bytes(), t0 = peers::thread_cpu_us();
                                  ddb->add(dv, df);
                                  const double t = peers::thread_cpu_us() - t0;
                                  heap_d += peers::heap_bytes() - h;
                                  return t;
                                });
      sum_b += b;
      sum_d += d;
    };
    auto timed_queries = [&](Row& row) {
      std::vector<double> tb, td;
      for (std::size_t q = 0; q < bq.size(); ++q) {
        std::vector<binbow::QueryResult> rb;
        DBoW3::QueryResults rd;
        auto [b, d] = interleaved((rep + q) % 2 == 0,
                                  [&] {
                                    const double t0 = peers::thread_cpu_us();
                                    rb = bdb->query(bq[q], 10);
                                    return peers::thread_cpu_us() - t0;
                                  },
                                  [&] {
                                    const double t0 = peers::thread_cpu_us();
                                    ddb->query(dq[q], rd, 10);
                                    return peers::thread_cpu_us() - t0;
                                  });
        tb.push_back(b * 1e-3);
        td.push_back(d * 1e-3);
        bool same = rb.size() == rd.size();
        for (std::size_t r = 0; same && r < rb.size(); ++r)
          same = rb[r].entry == rd[r].Id &&
                 std::fabs(rb[r].score - rd[r].Score) <= 1e-6 * std::fabs(rd[r].Score);
        ++queries_compared;
        if (!same) ++queries_differing;
      }
      row.binbow.push_back(peers::median(tb));
      row.dbow3.push_back(peers::median(td));
    };
    for (std::size_t i = 0; i < 1000; ++i) timed_add(i);
    timed_queries(q1k);
    mem1k.binbow.push_back(heap_b / 1000 / 1024);
    mem1k.dbow3.push_back(heap_d / 1000 / 1024);
    for (std::size_t i = 1000; i < n; ++i) timed_add(i);
    timed_queries(qn);
    memn.binbow.push_back(heap_b / n / 1024);
    memn.dbow3.push_back(heap_d / n / 1024);
    add.binbow.push_back(sum_b / n);
    add.dbow3.push_back(sum_d / n);
    bdb.reset();
    ddb.reset();

    // From descriptors: each library transforms inside its add.
    binbow::Database bdesc(bb, binbow::DatabaseOptions{true, 4});
    DBoW3::Database ddesc(db, true, 4);
    sum_b = sum_d = 0;
    for (std::size_t i = 0; i < 1000; ++i) {
      auto [b, d] = interleaved((rep + i) % 2 == 0,
                                [&] {
                                  const double t0 = peers::thread_cpu_us();
                                  bdesc.add(peers::view(data.entries[i]));
                                  return peers::thread_cpu_us() - t0;
                                },
                                [&] {
                                  const double t0 = peers::thread_cpu_us();
                                  ddesc.add(data.entries[i]);
                                  return peers::thread_cpu_us() - t0;
                                });
      sum_b += b;
      sum_d += d;
    }
    add_desc.binbow.push_back(sum_b / 1000 * 1e-3);
    add_desc.dbow3.push_back(sum_d / 1000 * 1e-3);
  }
  std::printf(
      "check: %zu entries' vectors differ; %zu of %zu top-10 results differ (entries in order, "
      "scores within 1e-6)\n",
      mismatches, queries_differing, queries_compared);
  table_head("**Database** (thread CPU time; memory: heap growth during each library's adds):");
  add.print();
  add_desc.print();
  q1k.print();
  qn.print();
  mem1k.print();
  memn.print();
  if (mismatches != 0 || queries_differing != 0) std::exit(3);
}

}  // namespace

int main(int argc, char** argv) {
  const Options o = parse(argc, argv);
  std::setvbuf(stdout, nullptr, _IOLBF, 0);  // tables appear as they are made, even through tee
  std::printf("binbow / DBoW3, %d repetitions; figures: min–max (median) over them\n", o.reps);
  if (o.tables.count("load")) load_table(o);
  if (!o.tables.count("transform") && !o.tables.count("database")) return 0;
  const binbow::Vocabulary bb = binbow::Vocabulary::load(o.bbw);
  DBoW3::Vocabulary db;
  db.load(o.dbow3);
  std::printf("\nvocabulary: %s; DBoW3: %u words, k=%d L=%d\n", bb.description().c_str(), db.size(),
              db.getBranchingFactor(), db.getDepthLevels());
  if (o.tables.count("transform")) transform_table(bb, db, o);
  if (o.tables.count("database")) database_table(bb, db, o);
  return 0;
}
