// Hand model inversion throughput (issue 4: hand ≥ 3,600 frames/s single
// thread, ≈ 50 markers). A synthetic model sized like the virtual cuer's hand:
// 7 forearm cluster markers, 43 hand markers on 16 segments (palm 8 markers,
// 15 phalanges of 2, 2 and 3 markers), 48 joint angles (10 constant twists),
// 12 PCA parameters and a random [1, cos, sin] map; takes of 1,200 frames
// (10 s at 120 Hz) with 0.2 mm noise and 5% of the samples missing.
#include <benchmark/benchmark.h>

#include <Eigen/QR>
#include <atomic>
#include <cmath>
#include <random>
#include <thread>

#include "models/hand_model.h"

namespace csw {
namespace {

HandModel BenchModel() {
  std::mt19937 rng(42);
  std::normal_distribution<double> g;
  std::uniform_real_distribution<double> u(-1, 1);
  HandModel m;
  HandLayout& l = m.layout;
  for (int i = 0; i < 7; ++i) l.forearm.push_back("FA" + std::to_string(i));
  auto add = [&](const std::string& name) {
    l.hand.push_back(name);
    return static_cast<int>(l.hand.size()) - 1;
  };
  HandSegmentDef palm{"palm", -1, {}};
  for (int i = 0; i < 8; ++i) palm.markers.push_back(add("P" + std::to_string(i)));
  l.segments.push_back(palm);
  for (int f = 0; f < 5; ++f) {
    for (int p = 0; p < 3; ++p) {
      HandSegmentDef seg{
          "f" + std::to_string(f) + std::to_string(p), p == 0 ? 0 : static_cast<int>(l.segments.size()) - 1, {}};
      const int k = p == 2 ? 3 : 2;
      for (int j = 0; j < k; ++j) seg.markers.push_back(add(seg.name + "m" + std::to_string(j)));
      l.segments.push_back(seg);
    }
  }
  const int nh = l.num_shape_markers();                   // 43
  const int n = 3 * static_cast<int>(l.segments.size());  // 48
  const int p = 12;
  m.forearm.name = "forearm";
  m.forearm.markers = l.forearm;
  m.forearm.reference.resize(3, 7);
  for (int i = 0; i < 7; ++i) m.forearm.reference.col(i) << 40 * u(rng), 100 * u(rng), 30 * u(rng);
  m.forearm.info.training_rms_mm = 0.2;
  m.info.training_rms_mm = 2.0;
  // Twists of the 2-marker segments are constant: no component moves them, no feature uses them.
  std::vector<int> moving;
  for (size_t s = 0; s < l.segments.size(); ++s) {
    for (int a = 0; a < 3; ++a) {
      if (a == 2 && l.segments[s].markers.size() == 2) continue;
      moving.push_back(3 * static_cast<int>(s) + a);
    }
  }
  Eigen::MatrixXd c(moving.size(), p);
  for (Eigen::Index i = 0; i < c.size(); ++i) c.data()[i] = g(rng);
  Eigen::HouseholderQR<Eigen::MatrixXd> qr(c);
  const Eigen::MatrixXd q = qr.householderQ() * Eigen::MatrixXd::Identity(c.rows(), p);
  AnglePca& pca = m.shape.angle_pca;
  pca.mean = Eigen::VectorXd::Zero(n);
  pca.components = Eigen::MatrixXd::Zero(n, p);
  pca.variances.resize(p);
  m.param_scale.resize(p);
  for (int k = 0; k < p; ++k) {
    m.param_scale(k) = 0.8 / (1 + k);
    pca.variances(k) = m.param_scale(k) * m.param_scale(k);
  }
  HandRegression& reg = m.shape.regression;
  reg.num_angles = n;
  reg.coefficients = Eigen::MatrixXd::Zero(1 + 2 * n, 3 * nh);
  for (int c2 = 0; c2 < 3 * nh; ++c2) reg.coefficients(0, c2) = 80 * u(rng);
  for (size_t i = 0; i < moving.size(); ++i) {
    const int a = moving[i];
    pca.mean(a) = 0.3 * u(rng);
    pca.components.row(a) = q.row(static_cast<Eigen::Index>(i));
    for (int c2 = 0; c2 < 3 * nh; ++c2) {
      reg.coefficients(1 + a, c2) = 6 * g(rng);
      reg.coefficients(1 + n + a, c2) = 6 * g(rng);
    }
  }
  return m;
}

MarkerArray BenchTake(const HandModel& m, int frames, uint32_t seed) {
  std::mt19937 rng(seed);
  std::normal_distribution<double> noise(0, 0.2);
  std::uniform_real_distribution<double> u(0, 1);
  const int p = m.num_parameters();
  const int nm = m.layout.num_markers();
  MarkerArray take(frames, nm);
  const double phase = 10 * u(rng);
  for (int f = 0; f < frames; ++f) {
    const double t = f / 120.0 + phase;
    Eigen::VectorXd params(p);
    for (int k = 0; k < p; ++k) params(k) = m.param_scale(k) * std::sin(1.3 * t * (1 + 0.37 * k) + k);
    Eigen::Matrix<double, 6, 1> pose;
    pose << 0.4 * std::sin(0.5 * t), 0.3 * std::cos(0.7 * t), 0.2 * std::sin(0.9 * t), 200 * std::sin(0.6 * t),
        100 * std::cos(0.4 * t), 1100 + 50 * std::sin(0.8 * t);
    const Eigen::Matrix3Xd lab = m.MarkersInLab(RigidTransform::FromParameters(pose), params);
    for (int j = 0; j < nm; ++j) {
      if (u(rng) < 0.05) continue;  // missing
      float* o = take.at(f, j);
      for (int c = 0; c < 3; ++c) o[c] = static_cast<float>(lab(c, j) + noise(rng));
    }
  }
  return take;
}

void BM_HandInversionSingleThread(benchmark::State& state) {
  const HandModel model = BenchModel();
  const MarkerArray take = BenchTake(model, 1200, 1);
  int64_t frames = 0;
  for (auto _ : state) {
    const InversionResult r = InvertHand(model, take);
    benchmark::DoNotOptimize(r.params.data());
    frames += r.frames();
  }
  state.counters["frames_per_second"] = benchmark::Counter(static_cast<double>(frames), benchmark::Counter::kIsRate);
  state.counters["hand_markers"] = model.layout.num_shape_markers();
  state.counters["parameters"] = model.num_parameters();
}
BENCHMARK(BM_HandInversionSingleThread)->Unit(benchmark::kMillisecond)->UseRealTime();

// The same with the Gaussian gap filler (a random 129-D normal): the 5 % of
// samples missing at random change the pattern of seen markers nearly every
// frame, the worst case for its cached gain (real occlusions last many frames).
void BM_HandInversionGaussianFill(benchmark::State& state) {
  HandModel model = BenchModel();
  std::mt19937 rng(7);
  std::normal_distribution<double> g;
  const int d = 3 * model.layout.num_shape_markers();
  Eigen::MatrixXd l(d, 20);
  for (Eigen::Index i = 0; i < l.size(); ++i) l.data()[i] = 5 * g(rng);
  model.fill.mean = Eigen::VectorXd::Zero(d);
  model.fill.covariance = l * l.transpose() + Eigen::MatrixXd::Identity(d, d);
  const MarkerArray take = BenchTake(model, 1200, 1);
  int64_t frames = 0;
  for (auto _ : state) {
    const InversionResult r = InvertHand(model, take);
    benchmark::DoNotOptimize(r.params.data());
    frames += r.frames();
  }
  state.counters["frames_per_second"] = benchmark::Counter(static_cast<double>(frames), benchmark::Counter::kIsRate);
}
BENCHMARK(BM_HandInversionGaussianFill)->Unit(benchmark::kMillisecond)->UseRealTime();

// Several takes shared out over threads (one InvertHand per take, the model shared, const).
void BM_HandInversionThreads(benchmark::State& state) {
  const int threads = static_cast<int>(state.range(0));
  const HandModel model = BenchModel();
  std::vector<MarkerArray> takes;
  for (uint32_t i = 0; i < 4; ++i) takes.push_back(BenchTake(model, 1200, 10 + i));
  int64_t frames = 0;
  for (auto _ : state) {
    std::atomic<size_t> next{0};
    std::vector<std::thread> pool;
    for (int t = 0; t < threads; ++t) {
      pool.emplace_back([&] {
        for (size_t i = next++; i < takes.size(); i = next++) {
          const InversionResult r = InvertHand(model, takes[i]);
          benchmark::DoNotOptimize(r.params.data());
        }
      });
    }
    for (auto& th : pool) th.join();
    for (const auto& t : takes) frames += t.frames();
  }
  state.counters["frames_per_second"] = benchmark::Counter(static_cast<double>(frames), benchmark::Counter::kIsRate);
  state.counters["threads"] = threads;
}
BENCHMARK(BM_HandInversionThreads)->Arg(1)->Arg(2)->Unit(benchmark::kMillisecond)->UseRealTime();

}  // namespace
}  // namespace csw

BENCHMARK_MAIN();
