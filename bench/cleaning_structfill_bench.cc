// Rigid-cluster and pattern fills on a 10-minute, 113-marker take at 120 Hz in memory
// (issue 12: the whole cleaning of such a take must stay under 1 s on one core).
// The take is synthetic: a 10-marker "head" and a 7-marker "forearm" rigid cluster under smooth
// rotations and translations with 0.2 mm noise, the other markers following the forearm with a
// wobble; every cluster marker has a 20-frame gap every 2 s (4,200 gaps in all).
#include <benchmark/benchmark.h>

#include <Eigen/Geometry>
#include <cmath>
#include <random>
#include <vector>

#include "analysis/cleaning/pattern_fill.h"
#include "analysis/cleaning/rigid_fill.h"

namespace {

using csw::MarkerArray;
using namespace csw::cleaning;

constexpr int64_t kFrames = 10 * 60 * 120;
constexpr int kMarkers = 113;
const std::vector<int> kHead = {0, 1, 2, 3, 4, 5, 6, 7, 8, 9};
const std::vector<int> kForearm = {10, 11, 12, 13, 14, 15, 16};

Eigen::Isometry3d Pose(double t, double speed) {
  Eigen::Isometry3d x = Eigen::Isometry3d::Identity();
  x.linear() = Eigen::AngleAxisd(0.6 * std::sin(speed * t),
                                 Eigen::Vector3d(std::sin(0.3 * t), std::cos(0.2 * t), 0.4).normalized())
                   .toRotationMatrix();
  x.translation() = Eigen::Vector3d(200 * std::sin(0.5 * speed * t), 150 * std::cos(0.7 * t), 1200 + 30 * std::sin(t));
  return x;
}

struct Take {
  MarkerArray markers;
  std::vector<Gap> cluster_gaps, other_gaps;
};

const Take& MakeTake() {
  static const Take take = [] {
    Take t;
    t.markers = MarkerArray(kFrames, kMarkers);
    std::mt19937_64 rng(1);
    std::normal_distribution<double> noise(0.0, 0.2);
    std::uniform_real_distribution<double> u(-80.0, 80.0);
    Eigen::Matrix3Xd local(3, kMarkers);
    for (int j = 0; j < kMarkers; ++j) local.col(j) = Eigen::Vector3d(u(rng), u(rng), u(rng));
    for (int64_t f = 0; f < kFrames; ++f) {
      const double s = static_cast<double>(f) / 120.0;
      const Eigen::Isometry3d head = Pose(s, 0.4), arm = Pose(s, 2.0);
      for (int j = 0; j < kMarkers; ++j) {
        Eigen::Vector3d p = j < 10 ? head * Eigen::Vector3d(local.col(j)) : arm * Eigen::Vector3d(local.col(j));
        if (j >= 17) p += 5.0 * Eigen::Vector3d(std::sin(3 * s + j), std::cos(2 * s + j), 0);
        for (int c = 0; c < 3; ++c) t.markers.at(f, j)[c] = static_cast<float>(p[c] + noise(rng));
      }
    }
    for (int j = 0; j < 17; ++j)
      for (int64_t s = 100 + 13 * j; s + 20 < kFrames; s += 240) {
        t.cluster_gaps.push_back({j, s, 20});
        for (int64_t f = s; f < s + 20; ++f) t.markers.SetMissing(f, j);
      }
    for (int j = 17; j < 27; ++j)
      for (int64_t s = 300 + 17 * j; s + 20 < kFrames; s += 2400) {
        t.other_gaps.push_back({j, s, 20});
        for (int64_t f = s; f < s + 20; ++f) t.markers.SetMissing(f, j);
      }
    return t;
  }();
  return take;
}

void BM_RigidReferences(benchmark::State& state) {
  const Take& t = MakeTake();
  for (auto _ : state) {
    RigidClusterFiller filler = RigidClusterFiller::FromMarkers(t.markers, {kHead, kForearm});
    benchmark::DoNotOptimize(filler.clusters().data());
    state.counters["head_iterations"] = filler.clusters()[0].iterations;
    state.counters["forearm_iterations"] = filler.clusters()[1].iterations;
  }
}
BENCHMARK(BM_RigidReferences)->Unit(benchmark::kMillisecond);

void BM_RigidFillAllClusterGaps(benchmark::State& state) {
  const Take& t = MakeTake();
  const RigidClusterFiller filler = RigidClusterFiller::FromMarkers(t.markers, {kHead, kForearm});
  MarkerArray out = t.markers;
  int64_t filled = 0;
  for (auto _ : state) {
    filled = 0;
    for (const Gap& g : t.cluster_gaps) {
      FillRecord rec{};
      filled += filler.Fill(t.markers, g, &out, &rec) ? 1 : 0;
    }
    benchmark::DoNotOptimize(out.data().data());
  }
  state.counters["gaps"] = static_cast<double>(t.cluster_gaps.size());
  state.counters["filled"] = static_cast<double>(filled);
}
BENCHMARK(BM_RigidFillAllClusterGaps)->Unit(benchmark::kMillisecond);

void BM_PatternFillAutoDonor(benchmark::State& state) {
  const Take& t = MakeTake();
  std::vector<int> group;
  for (int j = 17; j < 33; ++j) group.push_back(j);  // 16 candidates per gap
  const PatternFiller filler({group});
  MarkerArray out = t.markers;
  int64_t filled = 0;
  for (auto _ : state) {
    filled = 0;
    for (const Gap& g : t.other_gaps) {
      FillRecord rec{};
      filled += filler.Fill(t.markers, g, &out, &rec) ? 1 : 0;
    }
    benchmark::DoNotOptimize(out.data().data());
  }
  state.counters["gaps"] = static_cast<double>(t.other_gaps.size());
  state.counters["filled"] = static_cast<double>(filled);
}
BENCHMARK(BM_PatternFillAutoDonor)->Unit(benchmark::kMillisecond);

}  // namespace

BENCHMARK_MAIN();
