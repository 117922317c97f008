// Throughput of InvertFace (issue 4 §5 target: ≥ 12,000 frames/s single
// thread, 100× real time at 120 Hz): 10 head-cluster markers + 55 face + 8
// throat markers (63 shape markers), 7 shape parameters, 0.2 mm noise, 5 % of
// samples missing at random, smooth head motion of a few degrees / mm.
// Single-thread (warm and cold start) and several takes inverted in parallel
// with std::thread (1, 2 threads; the model is shared, const).
#include <benchmark/benchmark.h>

#include <cmath>
#include <cstdint>
#include <random>
#include <string>
#include <thread>
#include <vector>

#include "models/face_model.h"

namespace {

constexpr int kHead = 10;
constexpr int kFace = 55;
constexpr int kThroat = 8;
constexpr int kParams = 7;
constexpr int kFrames = 6000;  // 50 s at 120 Hz per take

struct Setup {
  csw::FaceModel model;
  std::vector<csw::MarkerArray> takes;  // 4 takes
};

const Setup& GetSetup() {
  static const Setup s = [] {
    Setup s;
    std::mt19937 rng(7);
    std::uniform_real_distribution<double> u(-1, 1), u01(0, 1);
    std::normal_distribution<double> n(0, 1);
    csw::FaceModel& m = s.model;
    for (int i = 0; i < kHead; ++i) m.layout.head.push_back("H" + std::to_string(i));
    for (int i = 0; i < kFace; ++i) m.layout.face.push_back("F" + std::to_string(i));
    for (int i = 0; i < kThroat; ++i) {
      m.layout.throat.push_back("T" + std::to_string(i));
      m.layout.throat_weights.push_back(0.3 + 0.06 * i);
    }
    m.head.reference.resize(3, kHead);
    for (int i = 0; i < kHead; ++i) m.head.reference.col(i) = Eigen::Vector3d(70 * u(rng), 80 * u(rng), 60 * u(rng));
    m.head.reference = m.head.reference.colwise() - m.head.reference.rowwise().mean();
    const int ns = kFace + kThroat;
    m.head_weights = Eigen::VectorXd::Ones(ns);
    for (int i = 0; i < kThroat; ++i) m.head_weights(kFace + i) = m.layout.throat_weights[static_cast<size_t>(i)];
    m.shape.mean.resize(3 * ns);
    for (int j = 0; j < ns; ++j) {
      m.shape.mean.segment<3>(3 * j) = j < kFace ? Eigen::Vector3d(40 * u(rng), 80 + 10 * u(rng), -40 + 30 * u(rng))
                                                 : Eigen::Vector3d(30 * u(rng), 30 + 10 * u(rng), -140 + 20 * u(rng));
    }
    m.shape.loadings.resize(3 * ns, kParams);
    for (Eigen::Index r = 0; r < m.shape.loadings.rows(); ++r)
      for (int k = 0; k < kParams; ++k) m.shape.loadings(r, k) = 1.5 * n(rng);
    m.shape.steps = {csw::GuidedPcaStep{"shape", {}, kParams}};
    Eigen::Matrix<double, 6, 1> rest;
    rest << 0, 0, 0, 120, -80, 1450;
    m.rest_pose = csw::RigidTransform::FromParameters(rest);

    for (int t = 0; t < 4; ++t) {
      csw::MarkerArray a(kFrames, kHead + ns);
      double ph[12];
      for (double& p : ph) p = 6.28 * u01(rng);
      for (int f = 0; f < kFrames; ++f) {
        const double time = f / 120.0;
        Eigen::Matrix<double, 6, 1> pp;
        for (int c = 0; c < 6; ++c) {
          pp(c) = (c < 3 ? 0.05 : 5.0) * std::sin(0.4 * (c + 1) * time + ph[c]) + rest(c);
        }
        const csw::RigidTransform pose = csw::RigidTransform::FromParameters(pp);
        Eigen::VectorXd p(kParams);
        for (int k = 0; k < kParams; ++k) p(k) = 1.5 * std::sin((1.0 + 0.7 * k) * time + ph[6 + k % 6]);
        const Eigen::Matrix3Xd lab = m.MarkersInLab(pose, p);
        for (int c = 0; c < kHead + ns; ++c) {
          if (u01(rng) < 0.05) continue;  // missing
          for (int k = 0; k < 3; ++k) a.at(f, c)[k] = static_cast<float>(lab(k, c) + 0.2 * n(rng));
        }
      }
      s.takes.push_back(std::move(a));
    }
    return s;
  }();
  return s;
}

void BM_InvertFace(benchmark::State& state) {
  const Setup& s = GetSetup();
  csw::InversionOptions opt;
  opt.warm_start = state.range(0) != 0;
  int64_t frames = 0, converged = 0, solved = 0;
  double error_sum = 0;
  int64_t error_count = 0;
  for (auto _ : state) {
    const csw::InversionResult r = csw::InvertFace(s.model, s.takes[0], opt);
    benchmark::DoNotOptimize(r.params.data());
    frames += r.frames();
    for (int64_t f = 0; f < r.frames(); ++f) {
      solved += r.solved[static_cast<size_t>(f)];
      converged += r.converged[static_cast<size_t>(f)];
    }
    for (Eigen::Index i = 0; i < r.error_mm.size(); ++i) {
      const double e = r.error_mm.data()[i];
      if (std::isfinite(e)) {
        error_sum += e;
        ++error_count;
      }
    }
  }
  state.counters["frames_per_second"] = benchmark::Counter(static_cast<double>(frames), benchmark::Counter::kIsRate);
  state.counters["converged_fraction"] =
      static_cast<double>(converged) / static_cast<double>(std::max<int64_t>(1, solved));
  state.counters["mean_error_mm"] = error_sum / static_cast<double>(std::max<int64_t>(1, error_count));
}
BENCHMARK(BM_InvertFace)->Arg(1)->Arg(0)->ArgName("warm")->Unit(benchmark::kMillisecond)->UseRealTime();

// Several takes in parallel, one std::thread per take slot.
void BM_InvertFaceThreads(benchmark::State& state) {
  const Setup& s = GetSetup();
  const int threads = static_cast<int>(state.range(0));
  int64_t frames = 0;
  for (auto _ : state) {
    std::vector<std::thread> pool;
    std::vector<int64_t> done(static_cast<size_t>(threads), 0);
    for (int t = 0; t < threads; ++t) {
      pool.emplace_back([&, t] {
        // Each thread inverts 2 takes.
        for (int k = 0; k < 2; ++k) {
          const csw::InversionResult r =
              csw::InvertFace(s.model, s.takes[static_cast<size_t>((2 * t + k) % s.takes.size())]);
          done[static_cast<size_t>(t)] += r.frames();
        }
      });
    }
    for (std::thread& th : pool) th.join();
    for (int64_t d : done) frames += d;
  }
  state.counters["frames_per_second"] = benchmark::Counter(static_cast<double>(frames), benchmark::Counter::kIsRate);
}
BENCHMARK(BM_InvertFaceThreads)->Arg(1)->Arg(2)->ArgName("threads")->Unit(benchmark::kMillisecond)->UseRealTime();

}  // namespace

BENCHMARK_MAIN();
