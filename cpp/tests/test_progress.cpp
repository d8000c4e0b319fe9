#include <gtest/gtest.h>

#include <atomic>
#include <chrono>
#include <cmath>
#include <cstring>
#include <thread>

#include "osteon/analysis.hpp"
#include "osteon/correction.hpp"
#include "osteon/progress.hpp"
#include "test_helpers.hpp"

using namespace osteon;
using osteon::testing::prism;
using osteon::testing::regular_polygon;

namespace {

// A bar along x from 0 to `length`, bones of `bones` equal pieces in a chain, and a side branch
// (a Y at the middle joint, three bones meeting there).
Skeleton chain(double length, int bones, bool branch) {
  Skeleton s;
  for (int b = 0; b < bones; ++b) {
    s.heads.push_back(Vec3(length * b / bones, 0, 0));
    s.tails.push_back(Vec3(length * (b + 1) / bones, 0, 0));
    s.parents.push_back(b - 1);
  }
  if (branch) {
    const int mid = bones / 2;
    s.heads.push_back(s.tails[mid - 1]);
    s.tails.push_back(s.tails[mid - 1] + Vec3(0, 1.5, 0));
    s.parents.push_back(mid - 1);
  }
  return s;
}

void expect_same(const AnalysisResult& a, const AnalysisResult& b) {
  ASSERT_EQ(a.stress.size(), b.stress.size());
  EXPECT_EQ(0, std::memcmp(a.stress.data(), b.stress.data(), a.stress.size() * sizeof(double)));
  EXPECT_EQ(0, std::memcmp(a.section_area.data(), b.section_area.data(),
                           a.section_area.size() * sizeof(double)));
  EXPECT_EQ(a.vertex_stress, b.vertex_stress);
  EXPECT_EQ(a.weak, b.weak);
}

}  // namespace

TEST(Progress, CountSectionsIsThePlansLength) {
  // Closed form: a chain of n equal bones of length L/n at interval h has n * (ceil(L/(n h)) - 1)
  // interior planes, two free ends and n - 1 joints of two bones; a Y joint of three bones
  // makes three pairs and the branch one more free end.
  const auto m = prism(regular_polygon(3, 12), 90, 46);
  for (const double h : {0.7, 2.0, 4.5, 30.0}) {
    for (const bool branch : {false, true}) {
      const Skeleton s = chain(90, 4, branch);
      const std::int64_t per_bone = static_cast<std::int64_t>(std::ceil(22.5 / h)) - 1;
      std::int64_t expect = 4 * std::max<std::int64_t>(per_bone, 0) + 2 + 3;
      if (branch) expect += static_cast<std::int64_t>(std::ceil(1.5 / h)) - 1 + 1 + 2;
      EXPECT_EQ(count_sections(s, h), expect) << "h " << h << " branch " << branch;
      AnalysisOptions o;
      o.interval = h;
      const AnalysisResult r = analyze(m.view(), s, nullptr, o);
      EXPECT_EQ(static_cast<std::int64_t>(r.stress.size()), count_sections(s, h));
    }
  }
  EXPECT_THROW(count_sections(chain(90, 2, false), 0.0), std::invalid_argument);
  EXPECT_THROW(count_sections(chain(90, 2, false), NAN), std::invalid_argument);
  // Beyond the engine's limit of 10^6 sections on one bone: counted, not thrown.
  EXPECT_EQ(count_sections(chain(90, 1, false), 1e-5), 8999999 + 2);
}

TEST(Progress, CountsSectionsAndRuns) {
  const auto m = prism(regular_polygon(3, 12), 90, 46);
  const Skeleton s = chain(90, 3, true);
  AnalysisOptions o;
  o.interval = 1.0;
  Progress p;
  Analyzer analyzer(m.f.data(), m.view().num_faces, m.view().num_vertices, nullptr, s.num_bones(),
                    o);
  const AnalysisResult r = analyzer.run(m.v.data(), s, &p);
  EXPECT_EQ(p.sections_total.load(), static_cast<std::int64_t>(r.stress.size()));
  EXPECT_EQ(p.sections_done.load(), p.sections_total.load());
  EXPECT_EQ(p.runs_done.load(), 1);
}

TEST(Progress, CancelFromAnotherThreadStopsEarlyAndLeavesNoTrace) {
  // A long analysis (fine interval, one worker) cancelled from another thread once 200
  // sections are cut: it throws Cancelled well before the end, and the same Analyzer's next
  // run equals a fresh Analyzer's, bit for bit.
  const auto m = prism(regular_polygon(3, 24), 400, 401);
  const Skeleton s = chain(400, 4, false);
  AnalysisOptions o;
  o.interval = 0.05;  // ~8000 sections
  o.threads = 1;
  Analyzer analyzer(m.f.data(), m.view().num_faces, m.view().num_vertices, nullptr, s.num_bones(),
                    o);
  // A last run to forget, on moved vertices (so the cancelled run re-cuts every section).
  std::vector<double> moved = m.v;
  for (std::size_t i = 1; i < moved.size(); i += 3) moved[i] += 0.01;
  analyzer.run(moved.data(), s);
  Progress p;
  std::atomic<bool> stop_watch{false};
  std::thread watcher([&] {
    while (!stop_watch && p.sections_done.load() < 200) std::this_thread::yield();
    p.cancel();
  });
  EXPECT_THROW(analyzer.run(m.v.data(), s, &p), Cancelled);
  stop_watch = true;
  watcher.join();
  EXPECT_TRUE(p.cancelled());
  EXPECT_GE(p.sections_done.load(), 200);
  EXPECT_LT(p.sections_done.load(), p.sections_total.load() / 2);
  EXPECT_EQ(p.runs_done.load(), 0);
  // The next run (no progress) is whole and equals a fresh analyzer's.
  const AnalysisResult again = analyzer.run(m.v.data(), s);
  Analyzer fresh(m.f.data(), m.view().num_faces, m.view().num_vertices, nullptr, s.num_bones(), o);
  expect_same(again, fresh.run(m.v.data(), s));
  // A progress cancelled before the start stops at once; reset() makes it usable again.
  EXPECT_THROW(analyzer.run(m.v.data(), s, &p), Cancelled);
  p.reset();
  EXPECT_FALSE(p.cancelled());
  expect_same(analyzer.run(m.v.data(), s, &p), again);
}

TEST(Progress, CancelStopsACorrection) {
  const auto m = prism(regular_polygon(2, 12), 90, 46);
  const Skeleton s = chain(90, 2, false);
  std::vector<double> w(m.v.size() / 3 * 2);
  for (std::size_t v = 0; v < m.v.size() / 3; ++v) w[2 * v + (m.v[3 * v] < 45 ? 0 : 1)] = 1.0;
  const BoneWeights weights = BoneWeights::from_dense(w.data(), m.v.size() / 3, 2);
  AnalysisOptions o;
  o.force = 50;
  o.interval = 2;
  Progress p;
  p.cancel();
  EXPECT_THROW(correct(m.view(), s, weights, o, CorrectionOptions{}, &p), Cancelled);
  p.reset();
  const CorrectionResult r = correct(m.view(), s, weights, o, CorrectionOptions{}, &p);
  EXPECT_FALSE(r.rounds.empty());  // the load is too much for a 4 mm bar: it had to work
  // The first analysis, one per round, the final one.
  EXPECT_EQ(p.runs_done.load(), static_cast<std::int64_t>(r.rounds.size()) + 2);
}
