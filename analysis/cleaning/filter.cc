#include "analysis/cleaning/filter.h"

#include <Eigen/Cholesky>
#include <algorithm>
#include <cmath>
#include <limits>
#include <string>
#include <utility>

#include "core/error.h"

namespace csw::cleaning {
namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

void CheckRate(double rate_hz, const char* what) {
  if (!(rate_hz > 0) || !std::isfinite(rate_hz))
    throw InvalidInput(std::string(what) + ": sample rate must be a positive number of Hz, got " +
                       std::to_string(rate_hz));
}

void CheckButterworth(const ButterworthOptions& o, double rate_hz) {
  CheckRate(rate_hz, "Butterworth filter");
  if (o.order < 2 || o.order > 8 || o.order % 2 != 0)
    throw InvalidInput("Butterworth filter: order must be 2, 4, 6 or 8 (single-pass design), got " +
                       std::to_string(o.order));
  if (!(o.cutoff_hz > 0) || !(o.cutoff_hz < rate_hz / 2))
    throw InvalidInput("Butterworth filter: cut-off " + std::to_string(o.cutoff_hz) +
                       " Hz must be above 0 and below half the sample rate (" + std::to_string(rate_hz / 2) + " Hz)");
}

void CheckFinite(const std::vector<double>& x, const char* what) {
  for (size_t i = 0; i < x.size(); ++i)
    if (std::isinf(x[i])) throw InvalidInput(std::string(what) + ": sample " + std::to_string(i) + " is infinite");
}

[[noreturn]] __attribute__((noinline)) void ThrowInfinite(int64_t f, int64_t k, const char* what) {
  throw InvalidInput(std::string(what) + ": marker " + std::to_string(k) + " frame " + std::to_string(f) +
                     " has an infinite coordinate");
}

// True when the three coordinates of a frame are present; throws on infinities.
inline bool FrameValid(const MarkerArray& m, int64_t f, int64_t k, const char* what) {
  const float* p = m.at(f, k);
  if (std::isfinite(p[0]) && std::isfinite(p[1]) && std::isfinite(p[2])) return true;
  if (std::isinf(p[0]) || std::isinf(p[1]) || std::isinf(p[2])) ThrowInfinite(f, k, what);
  return false;
}

// Markers are processed in blocks of kBlock: a block's channels are gathered
// frame by frame (contiguous reads) into channel-major buffers, so each channel
// is then filtered in contiguous memory.
constexpr int64_t kBlock = 8;

// buf[(k - k0) * 3 + c][f] = coordinate c of marker k at frame f, NaN (all three)
// where the frame is not valid.
void GatherBlock(const MarkerArray& m, int64_t k0, int64_t k1, const char* what,
                 std::vector<std::vector<double>>& buf) {
  const auto frames = static_cast<size_t>(m.frames());
  buf.resize(static_cast<size_t>(3 * (k1 - k0)));
  for (auto& b : buf) b.resize(frames);
  for (int64_t f = 0; f < m.frames(); ++f)
    for (int64_t k = k0; k < k1; ++k) {
      const bool valid = FrameValid(m, f, k, what);
      const float* p = m.at(f, k);
      for (int c = 0; c < 3; ++c)
        buf[static_cast<size_t>(3 * (k - k0) + c)][static_cast<size_t>(f)] = valid ? p[c] : kNaN;
    }
}

void ScatterBlock(const std::vector<std::vector<double>>& buf, int64_t k0, int64_t k1, MarkerArray& m) {
  for (int64_t f = 0; f < m.frames(); ++f)
    for (int64_t k = k0; k < k1; ++k) {
      float* p = m.at(f, k);
      for (int c = 0; c < 3; ++c)
        p[c] = static_cast<float>(buf[static_cast<size_t>(3 * (k - k0) + c)][static_cast<size_t>(f)]);
    }
}

std::vector<SampleRun> RunsOf(const std::vector<bool>& valid) {
  std::vector<SampleRun> runs;
  const int64_t n = static_cast<int64_t>(valid.size());
  for (int64_t i = 0; i < n;) {
    if (!valid[static_cast<size_t>(i)]) {
      ++i;
      continue;
    }
    int64_t j = i;
    while (j < n && valid[static_cast<size_t>(j)]) ++j;
    runs.push_back({i, j - i});
    i = j;
  }
  return runs;
}

// Direct form II transposed pass of a cascade over y (in place), each section
// started in its steady state for the constant input y[0] (unit DC gain, so
// every section's steady output is y[0] too): SciPy's sosfilt_zi.
void CascadePass(const std::vector<Biquad>& sections, std::vector<double>& y) {
  if (y.empty()) return;
  const double c = y[0];
  for (const Biquad& s : sections) {
    double z1 = c * (1 - s.b0);
    double z2 = c * (s.b2 - s.a2);
    for (double& v : y) {
      const double in = v;
      const double out = s.b0 * in + z1;
      z1 = s.b1 * in - s.a1 * out + z2;
      z2 = s.b2 * in - s.a2 * out;
      v = out;
    }
  }
}

// Forward-backward filtering of one run x[0..n) (n > pad) with odd reflection
// padding: x[-k] = 2 x[0] - x[k], x[n-1+k] = 2 x[n-1] - x[n-1-k], k = 1..pad.
void FiltFiltRun(const std::vector<Biquad>& sections, int64_t pad, const double* x, int64_t n, double* out,
                 std::vector<double>& work) {
  work.resize(static_cast<size_t>(n + 2 * pad));
  for (int64_t k = 1; k <= pad; ++k) work[static_cast<size_t>(pad - k)] = 2 * x[0] - x[k];
  for (int64_t i = 0; i < n; ++i) work[static_cast<size_t>(pad + i)] = x[i];
  for (int64_t k = 1; k <= pad; ++k) work[static_cast<size_t>(pad + n - 1 + k)] = 2 * x[n - 1] - x[n - 1 - k];
  CascadePass(sections, work);
  std::reverse(work.begin(), work.end());
  CascadePass(sections, work);
  std::reverse(work.begin(), work.end());
  for (int64_t i = 0; i < n; ++i) out[i] = work[static_cast<size_t>(pad + i)];
}

// The same cascade over the three interleaved coordinates of one marker,
// y[3 i + c], i = 0..n, forwards or backwards in time: three independent
// recursions per step instead of one (the filter is latency-bound).
void CascadePass3(const std::vector<Biquad>& sections, double* y, int64_t n, bool backward) {
  if (n == 0) return;
  const int64_t first = backward ? n - 1 : 0;
  const std::ptrdiff_t step = backward ? -3 : 3;
  double c0[3];
  for (int c = 0; c < 3; ++c) c0[c] = y[3 * first + c];
  for (const Biquad& s : sections) {
    double z1[3], z2[3];
    for (int c = 0; c < 3; ++c) {
      z1[c] = c0[c] * (1 - s.b0);
      z2[c] = c0[c] * (s.b2 - s.a2);
    }
    double* p = y + 3 * first;
    for (int64_t i = 0; i < n; ++i, p += step)
      for (int c = 0; c < 3; ++c) {
        const double in = p[c];
        const double out = s.b0 * in + z1[c];
        z1[c] = s.b1 * in - s.a1 * out + z2[c];
        z2[c] = s.b2 * in - s.a2 * out;
        p[c] = out;
      }
  }
}

// FiltFiltRun on interleaved coordinates, in place: x[3 i + c], i = 0..n (single
// precision storage, as in the take; the filter runs in double precision).
void FiltFiltRun3(const std::vector<Biquad>& sections, int64_t pad, float* x, int64_t n, std::vector<double>& work) {
  work.resize(static_cast<size_t>(3 * (n + 2 * pad)));
  double* w = work.data();
  for (int c = 0; c < 3; ++c) {
    for (int64_t k = 1; k <= pad; ++k) {
      w[3 * (pad - k) + c] = 2.0 * x[c] - x[3 * k + c];
      w[3 * (pad + n - 1 + k) + c] = 2.0 * x[3 * (n - 1) + c] - x[3 * (n - 1 - k) + c];
    }
  }
  std::copy(x, x + 3 * n, w + 3 * pad);
  CascadePass3(sections, w, n + 2 * pad, false);
  CascadePass3(sections, w, n + 2 * pad, true);
  for (int64_t i = 0; i < 3 * n; ++i) x[i] = static_cast<float>(w[3 * pad + i]);
}

// Block of markers gathered as one interleaved buffer per marker:
// buf[k - k0][3 f + c], NaN where the frame is not valid.
void GatherBlock3(const MarkerArray& m, int64_t k0, int64_t k1, const char* what,
                  std::vector<std::vector<float>>& buf) {
  const auto frames = static_cast<size_t>(m.frames());
  buf.resize(static_cast<size_t>(k1 - k0));
  for (auto& b : buf) b.resize(3 * frames);
  for (int64_t f = 0; f < m.frames(); ++f)
    for (int64_t k = k0; k < k1; ++k) {
      const bool valid = FrameValid(m, f, k, what);
      const float* p = m.at(f, k);
      float* d = buf[static_cast<size_t>(k - k0)].data() + 3 * f;
      for (int c = 0; c < 3; ++c) d[c] = valid ? p[c] : std::numeric_limits<float>::quiet_NaN();
    }
}

void ScatterBlock3(const std::vector<std::vector<float>>& buf, int64_t k0, int64_t k1, MarkerArray& m) {
  for (int64_t f = 0; f < m.frames(); ++f)
    for (int64_t k = k0; k < k1; ++k) {
      float* p = m.at(f, k);
      const float* d = buf[static_cast<size_t>(k - k0)].data() + 3 * f;
      std::copy(d, d + 3, p);
    }
}

// Filters a channel run by run; `marker` only labels the report.
void FilterChannel(const std::vector<Biquad>& sections, int64_t pad, int64_t min_run, const std::vector<double>& x,
                   const std::vector<SampleRun>& runs, std::vector<double>& y, std::vector<double>& work,
                   FilterReport* report, int64_t marker, bool count) {
  y.assign(x.size(), kNaN);
  for (const SampleRun& r : runs) {
    const double* in = x.data() + r.start;
    double* out = y.data() + r.start;
    if (r.length >= min_run) {
      FiltFiltRun(sections, std::min(pad, r.length - 1), in, r.length, out, work);
      if (report && count) ++report->runs_filtered;
    } else {
      std::copy(in, in + r.length, out);
      if (report && count) report->unfiltered.push_back({marker, r.start, r.length});
    }
  }
}

}  // namespace

std::vector<SampleRun> ValidRuns(const std::vector<double>& x) {
  std::vector<bool> valid(x.size());
  for (size_t i = 0; i < x.size(); ++i) valid[i] = !std::isnan(x[i]);
  return RunsOf(valid);
}

std::vector<SampleRun> ValidRuns(const MarkerArray& markers, int64_t marker) {
  if (marker < 0 || marker >= markers.markers())
    throw InvalidInput("ValidRuns: marker " + std::to_string(marker) + " out of range (the array has " +
                       std::to_string(markers.markers()) + " markers)");
  std::vector<bool> valid(static_cast<size_t>(markers.frames()));
  for (int64_t f = 0; f < markers.frames(); ++f)
    valid[static_cast<size_t>(f)] = FrameValid(markers, f, marker, "ValidRuns");
  return RunsOf(valid);
}

// ---------------------------------------------------------------------------
// Butterworth.

double ButterworthPassCorrection(int order, int n_passes) {
  if (order < 1 || n_passes < 1)
    throw InvalidInput("Butterworth pass correction: order and passes must be positive, got order " +
                       std::to_string(order) + ", passes " + std::to_string(n_passes));
  // Winter (2009), Biomechanics and Motor Control of Human Movement, 4th ed.,
  // §3.4.4.3: C = (2^(1/n) - 1)^(1/4) for a 2nd-order filter passed n times;
  // the exponent 1/(2 order) generalises it (|H|^2 = 1 / (1 + (w/wc)^(2 order))).
  return std::pow(std::pow(2.0, 1.0 / n_passes) - 1.0, 1.0 / (2.0 * order));
}

double ButterworthDesignFrequency(const ButterworthOptions& options, double rate_hz) {
  CheckButterworth(options, rate_hz);
  const double warped = std::tan(M_PI * options.cutoff_hz / rate_hz) / ButterworthPassCorrection(options.order, 2);
  return std::atan(warped) * rate_hz / M_PI;
}

std::vector<Biquad> DesignButterworth(const ButterworthOptions& options, double rate_hz) {
  CheckButterworth(options, rate_hz);
  // Pre-warped analog cut-off (bilinear transform s = (1 - z^-1) / (1 + z^-1)),
  // divided by Winter's C: exact for the double pass, since |H|^2 depends on
  // tan(pi f / fs) / w only.
  const double w = std::tan(M_PI * options.cutoff_hz / rate_hz) / ButterworthPassCorrection(options.order, 2);
  const int n = options.order;
  std::vector<Biquad> sections;
  for (int k = 1; k <= n / 2; ++k) {
    // Analog section 1 / ((s/w)^2 + q (s/w) + 1), q = 2 sin((2k - 1) pi / (2n)): the
    // conjugate pole pair k of the normalised Butterworth polynomial.
    const double q = 2.0 * std::sin((2.0 * k - 1.0) * M_PI / (2.0 * n));
    const double a0 = 1.0 + q * w + w * w;
    Biquad s;
    s.b0 = w * w / a0;
    s.b1 = 2.0 * s.b0;
    s.b2 = s.b0;
    s.a1 = 2.0 * (w * w - 1.0) / a0;
    s.a2 = (1.0 - q * w + w * w) / a0;
    sections.push_back(s);
  }
  return sections;
}

double ZeroPhaseButterworthGain(const ButterworthOptions& options, double rate_hz, double f_hz) {
  CheckButterworth(options, rate_hz);
  if (!(f_hz >= 0) || !(f_hz < rate_hz / 2))
    throw InvalidInput("Butterworth gain: frequency " + std::to_string(f_hz) + " Hz must be in [0, rate/2)");
  const double w = std::tan(M_PI * options.cutoff_hz / rate_hz) / ButterworthPassCorrection(options.order, 2);
  const double ratio = std::tan(M_PI * f_hz / rate_hz) / w;
  return 1.0 / (1.0 + std::pow(ratio, 2.0 * options.order));  // |H|^2 of one pass = amplitude of two
}

int64_t ButterworthPadding(const ButterworthOptions& options, double rate_hz) {
  // Long enough for the slowest pole's transient (started from the steady state
  // of the first padded sample) to decay below 1e-6 before the data begin.
  double r_max = 0;
  for (const Biquad& s : DesignButterworth(options, rate_hz)) {
    const double disc = s.a1 * s.a1 - 4 * s.a2;
    const double r =
        disc < 0 ? std::sqrt(s.a2) : std::max(std::abs(-s.a1 + std::sqrt(disc)), std::abs(-s.a1 - std::sqrt(disc))) / 2;
    r_max = std::max(r_max, r);
  }
  const int64_t by_order = 3 * (options.order + 1);  // SciPy's filtfilt default
  const auto by_decay = r_max > 0 ? static_cast<int64_t>(std::ceil(std::log(1e-6) / std::log(r_max))) : 0;
  return std::max(by_order, by_decay);
}

int64_t ButterworthMinRunLength(const ButterworthOptions& options, double rate_hz) {
  CheckButterworth(options, rate_hz);
  return 3 * (options.order + 1) + 1;
}

std::vector<double> ButterworthFilter(const std::vector<double>& x, double rate_hz, const ButterworthOptions& options,
                                      FilterReport* report) {
  const std::vector<Biquad> sections = DesignButterworth(options, rate_hz);
  CheckFinite(x, "Butterworth filter");
  const int64_t pad = ButterworthPadding(options, rate_hz);
  const int64_t min_run = ButterworthMinRunLength(options, rate_hz);
  if (report) {
    *report = FilterReport();
    report->min_run_length = min_run;
  }
  std::vector<double> y, work;
  FilterChannel(sections, pad, min_run, x, ValidRuns(x), y, work, report, -1, true);
  return y;
}

Eigen::VectorXd ButterworthFilter(const Eigen::VectorXd& x, double rate_hz, const ButterworthOptions& options,
                                  FilterReport* report) {
  std::vector<double> in(x.data(), x.data() + x.size());
  std::vector<double> out = ButterworthFilter(in, rate_hz, options, report);
  return Eigen::Map<Eigen::VectorXd>(out.data(), static_cast<Eigen::Index>(out.size()));
}

void ButterworthFilterInPlace(MarkerArray& markers, double rate_hz, const ButterworthOptions& options,
                              FilterReport* report) {
  const std::vector<Biquad> sections = DesignButterworth(options, rate_hz);
  const int64_t pad = ButterworthPadding(options, rate_hz);
  const int64_t min_run = ButterworthMinRunLength(options, rate_hz);
  if (report) {
    *report = FilterReport();
    report->min_run_length = min_run;
  }
  std::vector<std::vector<float>> buf;
  std::vector<double> work;
  std::vector<bool> valid;
  for (int64_t k0 = 0; k0 < markers.markers(); k0 += kBlock) {
    const int64_t k1 = std::min(k0 + kBlock, markers.markers());
    GatherBlock3(markers, k0, k1, "Butterworth filter", buf);
    for (int64_t k = k0; k < k1; ++k) {
      std::vector<float>& x = buf[static_cast<size_t>(k - k0)];
      valid.resize(static_cast<size_t>(markers.frames()));
      for (size_t f = 0; f < valid.size(); ++f) valid[f] = !std::isnan(x[3 * f]);
      for (const SampleRun& r : RunsOf(valid)) {
        if (r.length >= min_run) {
          FiltFiltRun3(sections, std::min(pad, r.length - 1), x.data() + 3 * r.start, r.length, work);
          if (report) ++report->runs_filtered;
        } else if (report) {
          report->unfiltered.push_back({k, r.start, r.length});
        }
      }
    }
    ScatterBlock3(buf, k0, k1, markers);
  }
}

MarkerArray ButterworthFilter(const MarkerArray& markers, double rate_hz, const ButterworthOptions& options,
                              FilterReport* report) {
  MarkerArray out = markers;
  ButterworthFilterInPlace(out, rate_hz, options, report);
  return out;
}

// ---------------------------------------------------------------------------
// Kalman smoother.

double EstimateNoiseSd(const std::vector<double>& x) {
  // 4th-order differences d = x[i] - 4 x[i+1] + 6 x[i+2] - 4 x[i+3] + x[i+4]
  // within runs: for white noise of sd s, sd(d) = s sqrt(70); a smooth signal
  // contributes (2 sin(pi f / fs))^4 of its amplitude at f, negligible well below
  // Nyquist. The median absolute value / 0.6745 resists spikes and fast moves.
  std::vector<double> d;
  for (const SampleRun& r : ValidRuns(x))
    for (int64_t i = r.start; i + 4 < r.start + r.length; ++i) {
      const double* p = x.data() + i;
      d.push_back(std::abs(p[0] - 4 * p[1] + 6 * p[2] - 4 * p[3] + p[4]));
    }
  if (d.empty()) return 0.0;
  auto mid = d.begin() + static_cast<std::ptrdiff_t>(d.size() / 2);
  std::nth_element(d.begin(), mid, d.end());
  return *mid / 0.6744897501960817 / std::sqrt(70.0);
}

namespace {

// The discretised white-noise models of Bar-Shalom, Li & Kirubarajan (2001),
// Estimation with Applications to Tracking and Navigation, §6.2.2 (white noise
// acceleration, D = 2) and §6.2.3 (white noise jerk, D = 3), spectral density q.
template <int D>
struct Model {
  using Vec = Eigen::Matrix<double, D, 1>;
  using Mat = Eigen::Matrix<double, D, D>;
  Mat F, Q;
  Model(double dt, double q) {
    if constexpr (D == 2) {
      F << 1, dt, 0, 1;
      Q << dt * dt * dt / 3, dt * dt / 2, dt * dt / 2, dt;
    } else {
      F << 1, dt, dt * dt / 2, 0, 1, dt, 0, 0, 1;
      const double d2 = dt * dt, d3 = d2 * dt, d4 = d3 * dt, d5 = d4 * dt;
      Q << d5 / 20, d4 / 8, d3 / 6, d4 / 8, d3 / 3, d2 / 2, d3 / 6, d2 / 2, dt;
    }
    Q *= q;
  }
};

// Diffuse-ish start: position from the first sample (variance r), velocity sd
// 10 m/s, acceleration sd 100 m/s^2 (far beyond human movement).
template <int D>
void InitialState(double y0, double r, typename Model<D>::Vec& x, typename Model<D>::Mat& P) {
  x.setZero();
  x(0) = y0;
  P.setZero();
  P(0, 0) = r;
  P(1, 1) = 1e8;
  if constexpr (D == 3) P(2, 2) = 1e10;
}

// Forward Kalman filter over x[first..last] (NaN: prediction only). Returns the
// negative log-likelihood of the innovations (prediction error decomposition,
// Harvey 1989 §3.4), skipping the first D updates that the start dominates. When
// store is true, keeps predicted and filtered moments for the RTS pass.
template <int D>
double Forward(const Model<D>& m, const std::vector<double>& y, int64_t first, int64_t last, double r, bool store,
               std::vector<typename Model<D>::Vec>* xp, std::vector<typename Model<D>::Mat>* Pp,
               std::vector<typename Model<D>::Vec>* xf, std::vector<typename Model<D>::Mat>* Pf) {
  using Vec = typename Model<D>::Vec;
  using Mat = typename Model<D>::Mat;
  Vec x;
  Mat P;
  InitialState<D>(y[static_cast<size_t>(first)], r, x, P);
  const int64_t n = last - first + 1;
  if (store) {
    xp->resize(static_cast<size_t>(n));
    Pp->resize(static_cast<size_t>(n));
    xf->resize(static_cast<size_t>(n));
    Pf->resize(static_cast<size_t>(n));
  }
  double nll = 0;
  int updates = 0;
  // The covariances depend only on which samples are missing: along a run they
  // converge to the steady state (Riccati equation). Once the filtered
  // covariance repeats to 1e-10 (relative), the steady gain is reused until the
  // next missing sample.
  bool steady = false, prev_updated = false;
  Mat P_pred_ss = Mat::Zero(), P_filt_ss = Mat::Zero(), P_prev = Mat::Zero();
  Vec k_ss = Vec::Zero();
  double s_ss = 0;
  for (int64_t i = 0; i < n; ++i) {
    if (i > 0) {
      x = m.F * x;
      if (steady) {
        P = P_pred_ss;
      } else {
        P = m.F * P * m.F.transpose() + m.Q;
      }
    }
    if (store) {
      (*xp)[static_cast<size_t>(i)] = x;
      (*Pp)[static_cast<size_t>(i)] = P;
    }
    const double yi = y[static_cast<size_t>(first + i)];
    if (!std::isnan(yi) && i > 0) {
      const double e = yi - x(0);
      double s;
      if (steady) {
        s = s_ss;
        x += k_ss * e;
        P = P_filt_ss;
      } else {
        s = P(0, 0) + r;
        const Vec k = P.col(0) / s;
        const Mat P_pred = P;
        x += k * e;
        P -= k * P.row(0);
        P = 0.5 * (P + P.transpose()).eval();
        if (prev_updated && (P - P_prev).cwiseAbs().maxCoeff() <= 1e-10 * P.cwiseAbs().maxCoeff()) {
          steady = true;
          P_pred_ss = P_pred;
          P_filt_ss = P;
          k_ss = k;
          s_ss = s;
        }
        P_prev = P;
      }
      prev_updated = true;
      if (++updates > D) nll += 0.5 * (std::log(s) + e * e / s);
    } else {
      steady = prev_updated = false;
    }
    if (store) {
      (*xf)[static_cast<size_t>(i)] = x;
      (*Pf)[static_cast<size_t>(i)] = P;
    }
  }
  return nll;
}

// Process noise of equivalent bandwidth f_hz: the steady-state smoother of the
// model is the Wiener smoother 1 / (1 + (r dt / q) w^(2D)) (the smoothing spline
// of degree 2D - 1, Wecker & Ansley 1983), half gain at w = 2 pi f_hz.
double ProcessNoiseForBandwidth(int d, double r, double dt, double f_hz) {
  return r * dt * std::pow(2 * M_PI * f_hz, 2 * d);
}

template <int D>
struct Workspace {  // storage of the forward pass, reused across channels
  std::vector<typename Model<D>::Vec> xp, xf;
  std::vector<typename Model<D>::Mat> Pp, Pf;
};

template <int D>
KalmanChannel SmoothChannel(const std::vector<double>& y, double rate_hz, const KalmanOptions& o, Workspace<D>& ws) {
  using Vec = typename Model<D>::Vec;
  using Mat = typename Model<D>::Mat;
  KalmanChannel out;
  const size_t n_all = y.size();
  out.position.assign(n_all, kNaN);
  out.velocity.assign(n_all, kNaN);
  int64_t first = -1, last = -1;
  for (size_t i = 0; i < n_all; ++i)
    if (!std::isnan(y[i])) {
      if (first < 0) first = static_cast<int64_t>(i);
      last = static_cast<int64_t>(i);
    }
  out.measurement_sd = o.measurement_sd_mm > 0 ? o.measurement_sd_mm : EstimateNoiseSd(y);
  if (first < 0) return out;
  const double dt = 1.0 / rate_hz;
  // Noise-free (or constant) data: floor r so the filter follows the data.
  const double r = std::max(out.measurement_sd * out.measurement_sd, 1e-12);
  double q = o.process_noise;
  if (q <= 0) {
    // Maximum likelihood over the equivalent bandwidth (log scale), golden
    // section between 0.05 Hz and 0.45 rate.
    // Long channels: the likelihood of 10 evenly spaced windows of 1,200
    // samples (each started afresh) stands for the whole.
    std::vector<std::pair<int64_t, int64_t>> windows;
    constexpr int64_t kWindow = 1200, kWindows = 10;
    if (last - first + 1 <= kWindow * kWindows) {
      windows.push_back({first, last});
    } else {
      const int64_t step = (last - first + 1 - kWindow) / (kWindows - 1);
      for (int64_t w = 0; w < kWindows; ++w) {
        int64_t a = first + w * step, b = std::min(last, a + kWindow - 1);
        while (a < b && std::isnan(y[static_cast<size_t>(a)])) ++a;
        while (b > a && std::isnan(y[static_cast<size_t>(b)])) --b;
        if (b > a) windows.push_back({a, b});
      }
    }
    auto nll = [&](double log_f) {
      Model<D> m(dt, ProcessNoiseForBandwidth(D, r, dt, std::exp(log_f)));
      double sum = 0;
      for (const auto& [a, b] : windows) sum += Forward<D>(m, y, a, b, r, false, nullptr, nullptr, nullptr, nullptr);
      return sum;
    };
    double a = std::log(0.05), b = std::log(0.45 * rate_hz);
    const double g = (std::sqrt(5.0) - 1) / 2;
    double c = b - g * (b - a), d = a + g * (b - a);
    double fc = nll(c), fd = nll(d);
    for (int it = 0; it < 16; ++it) {  // bracket 0.618^16 = 5e-4 of ln(0.45 rate / 0.05 Hz)
      if (fc < fd) {
        b = d;
        d = c;
        fd = fc;
        c = b - g * (b - a);
        fc = nll(c);
      } else {
        a = c;
        c = d;
        fc = fd;
        d = a + g * (b - a);
        fd = nll(d);
      }
    }
    q = ProcessNoiseForBandwidth(D, r, dt, std::exp(0.5 * (a + b)));
  }
  out.process_noise = q;
  const Model<D> m(dt, q);
  std::vector<Vec>& xp = ws.xp;
  std::vector<Vec>& xf = ws.xf;
  std::vector<Mat>& Pp = ws.Pp;
  std::vector<Mat>& Pf = ws.Pf;
  Forward<D>(m, y, first, last, r, true, &xp, &Pp, &xf, &Pf);
  // Rauch, Tung & Striebel (1965): x_s[i] = x_f[i] + G (x_s[i+1] - x_p[i+1]),
  // G = P_f[i] F' P_p[i+1]^-1, computed as (P_p[i+1] \ (F P_f[i]))'.
  const int64_t n = last - first + 1;
  Vec xs = xf[static_cast<size_t>(n - 1)];
  auto emit = [&](int64_t i, const Vec& s) {
    const auto at = static_cast<size_t>(first + i);
    if (!std::isnan(y[at]) || o.fill_gaps) {
      out.position[at] = s(0);
      out.velocity[at] = s(1);
    }
  };
  emit(n - 1, xs);
  Mat G = Mat::Zero(), G_pf = Mat::Zero(),
      G_pp = Mat::Zero();  // the last gain and the covariances it was computed from
  bool have_g = false;
  for (int64_t i = n - 2; i >= 0; --i) {
    const auto k = static_cast<size_t>(i);
    if (!have_g || Pf[k] != G_pf || Pp[k + 1] != G_pp) {  // steady state: same covariances, same gain
      G = Pp[k + 1].llt().solve(m.F * Pf[k]).transpose();
      G_pf = Pf[k];
      G_pp = Pp[k + 1];
      have_g = true;
    }
    xs = xf[k] + G * (xs - xp[k + 1]);
    emit(i, xs);
  }
  return out;
}

}  // namespace

namespace {

void CheckKalman(double rate_hz, const KalmanOptions& options) {
  CheckRate(rate_hz, "Kalman smoother");
  if (!(options.measurement_sd_mm >= 0) || !std::isfinite(options.measurement_sd_mm))
    throw InvalidInput("Kalman smoother: measurement sd must be >= 0 mm (0 = estimate), got " +
                       std::to_string(options.measurement_sd_mm));
  if (!(options.process_noise >= 0) || !std::isfinite(options.process_noise))
    throw InvalidInput("Kalman smoother: process noise must be >= 0 (0 = estimate), got " +
                       std::to_string(options.process_noise));
}

KalmanChannel Smooth(const std::vector<double>& x, double rate_hz, const KalmanOptions& options, Workspace<2>& w2,
                     Workspace<3>& w3) {
  return options.model == MotionModel::kConstantVelocity ? SmoothChannel<2>(x, rate_hz, options, w2)
                                                         : SmoothChannel<3>(x, rate_hz, options, w3);
}

}  // namespace

KalmanChannel KalmanSmooth(const std::vector<double>& x, double rate_hz, const KalmanOptions& options) {
  CheckKalman(rate_hz, options);
  CheckFinite(x, "Kalman smoother");
  Workspace<2> w2;
  Workspace<3> w3;
  return Smooth(x, rate_hz, options, w2, w3);
}

MarkerArray KalmanSmooth(const MarkerArray& markers, double rate_hz, const KalmanOptions& options) {
  CheckKalman(rate_hz, options);
  MarkerArray out(markers.frames(), markers.markers());
  std::vector<std::vector<double>> buf;
  Workspace<2> w2;
  Workspace<3> w3;
  for (int64_t k0 = 0; k0 < markers.markers(); k0 += kBlock) {
    const int64_t k1 = std::min(k0 + kBlock, markers.markers());
    GatherBlock(markers, k0, k1, "Kalman smoother", buf);  // infinities throw here
    for (auto& x : buf) x = Smooth(x, rate_hz, options, w2, w3).position;
    ScatterBlock(buf, k0, k1, out);
  }
  return out;
}

// ---------------------------------------------------------------------------
// Speeds and accelerations.

namespace {

// Central differences of positions p (frames x 3, NaN rows missing).
void CentralDifferences(const Eigen::MatrixXd& p, double rate_hz, Eigen::Ref<Eigen::VectorXd> speed,
                        Eigen::Ref<Eigen::VectorXd> acceleration) {
  const Eigen::Index n = p.rows();
  speed.setConstant(kNaN);
  acceleration.setConstant(kNaN);
  for (Eigen::Index i = 1; i + 1 < n; ++i) {
    if (std::isnan(p(i - 1, 0)) || std::isnan(p(i, 0)) || std::isnan(p(i + 1, 0))) continue;
    const Eigen::RowVector3d d1 = p.row(i + 1) - p.row(i - 1);
    const Eigen::RowVector3d d2 = p.row(i + 1) - 2 * p.row(i) + p.row(i - 1);
    speed(i) = d1.norm() * rate_hz / 2;
    acceleration(i) = d2.norm() * rate_hz * rate_hz;
  }
}

}  // namespace

Kinematics MarkerKinematics(const MarkerArray& markers, double rate_hz) {
  CheckRate(rate_hz, "marker kinematics");
  Kinematics k;
  k.speed.setConstant(markers.frames(), markers.markers(), kNaN);
  k.acceleration.setConstant(markers.frames(), markers.markers(), kNaN);
  std::vector<std::vector<double>> buf;
  for (int64_t k0 = 0; k0 < markers.markers(); k0 += kBlock) {
    const int64_t k1 = std::min(k0 + kBlock, markers.markers());
    GatherBlock(markers, k0, k1, "marker kinematics", buf);
    for (int64_t m = k0; m < k1; ++m) {
      const double* x = buf[static_cast<size_t>(3 * (m - k0))].data();
      const double* y = buf[static_cast<size_t>(3 * (m - k0) + 1)].data();
      const double* z = buf[static_cast<size_t>(3 * (m - k0) + 2)].data();
      double* v = k.speed.col(m).data();
      double* a = k.acceleration.col(m).data();
      for (int64_t i = 1; i + 1 < markers.frames(); ++i) {
        if (std::isnan(x[i - 1]) || std::isnan(x[i]) || std::isnan(x[i + 1])) continue;
        const double dx = x[i + 1] - x[i - 1], dy = y[i + 1] - y[i - 1], dz = z[i + 1] - z[i - 1];
        const double ax = x[i + 1] - 2 * x[i] + x[i - 1], ay = y[i + 1] - 2 * y[i] + y[i - 1],
                     az = z[i + 1] - 2 * z[i] + z[i - 1];
        v[i] = std::sqrt(dx * dx + dy * dy + dz * dz) * rate_hz / 2;
        a[i] = std::sqrt(ax * ax + ay * ay + az * az) * rate_hz * rate_hz;
      }
    }
  }
  return k;
}

PointKinematics MeanPointKinematics(const MarkerArray& markers, const std::vector<int>& columns, double rate_hz) {
  CheckRate(rate_hz, "point kinematics");
  if (columns.empty()) throw InvalidInput("point kinematics: no marker columns given for the point");
  for (int c : columns)
    if (c < 0 || c >= markers.markers())
      throw InvalidInput("point kinematics: marker column " + std::to_string(c) + " out of range (the array has " +
                         std::to_string(markers.markers()) + " markers)");
  PointKinematics k;
  k.position.setZero(markers.frames(), 3);
  for (int64_t f = 0; f < markers.frames(); ++f) {
    for (int c : columns) {
      if (!FrameValid(markers, f, c, "point kinematics")) {
        k.position.row(f).setConstant(kNaN);
        break;
      }
      const float* v = markers.at(f, c);
      k.position.row(f) += Eigen::RowVector3d(v[0], v[1], v[2]);
    }
  }
  k.position /= static_cast<double>(columns.size());
  k.speed.resize(markers.frames());
  k.acceleration.resize(markers.frames());
  CentralDifferences(k.position, rate_hz, k.speed, k.acceleration);
  return k;
}

}  // namespace csw::cleaning
