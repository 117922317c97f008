#include "analysis/coarticulation/ohman.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <map>

#include "core/error.h"

namespace csw::coarticulation {

namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
constexpr double kPi = 3.14159265358979323846;

double MinJerk(double tau) {
  tau = std::clamp(tau, 0.0, 1.0);
  return tau * tau * tau * (10.0 + tau * (-15.0 + 6.0 * tau));
}

bool Contains(const std::vector<std::string>& list, const std::string& s) {
  return std::find(list.begin(), list.end(), s) != list.end();
}

bool RowFinite(const Eigen::MatrixXd& m, Eigen::Index r) { return m.row(r).allFinite(); }

// The series at time t by linear interpolation between the two nearest
// frames (NaN when either is not finite or t is outside the take).
Eigen::VectorXd ValueAt(const ParameterSeries& s, double t) {
  const Eigen::Index n = s.values.rows();
  Eigen::VectorXd out = Eigen::VectorXd::Constant(s.values.cols(), kNaN);
  if (n == 0) return out;
  const double f = t * s.rate_hz;
  if (f < 0.0 || f > static_cast<double>(n - 1)) return out;
  const auto f0 = static_cast<Eigen::Index>(std::floor(f));
  const Eigen::Index f1 = std::min(f0 + 1, n - 1);
  const double a = f - static_cast<double>(f0);
  if (!RowFinite(s.values, f0) || !RowFinite(s.values, f1)) return out;
  return ((1.0 - a) * s.values.row(f0) + a * s.values.row(f1)).transpose();
}

// Frames [first, last] whose times fall in [a, b], clipped to the take.
std::pair<Eigen::Index, Eigen::Index> FramesIn(const ParameterSeries& s, double a, double b) {
  const auto first = static_cast<Eigen::Index>(std::ceil(a * s.rate_hz - 1e-9));
  const auto last = static_cast<Eigen::Index>(std::floor(b * s.rate_hz + 1e-9));
  return {std::max<Eigen::Index>(first, 0), std::min<Eigen::Index>(last, s.values.rows() - 1)};
}

double RaisedCosine(double s) {
  if (s <= 0.0) return 0.0;
  if (s >= 1.0) return 1.0;
  return 0.5 * (1.0 - std::cos(kPi * s));
}

// One flank as a function of the time u elapsed since the flank's ramp
// starts (u = t − (start + inset − ramp) on the left).
double Flank(double u, double ramp) { return ramp > 0.0 ? RaisedCosine(u / ramp) : (u >= 0.0 ? 1.0 : 0.0); }

// Least-squares (inset, ramp) of one flank on samples (d, k), d = signed time
// from the consonant boundary towards its inside (t − start on the left,
// end − t on the right): model Flank(d − inset + ramp, ramp).
std::pair<double, double> FitFlank(const std::vector<double>& d, const std::vector<double>& k,
                                   const std::vector<double>& wt, double* sse) {
  auto loss = [&](double inset, double ramp) {
    double s = 0.0;
    for (size_t i = 0; i < d.size(); ++i) {
      const double e = k[i] - Flank(d[i] - inset + ramp, ramp);
      s += wt[i] * e * e;
    }
    return s;
  };
  double best_inset = 0.0, best_ramp = 0.05, best = std::numeric_limits<double>::infinity();
  auto search = [&](double i0, double i1, double r0, double r1, double step) {
    for (double inset = i0; inset <= i1 + 1e-12; inset += step)
      for (double ramp = std::max(r0, 0.001); ramp <= r1 + 1e-12; ramp += step) {
        const double l = loss(inset, ramp);
        if (l < best) best = l, best_inset = inset, best_ramp = ramp;
      }
  };
  search(-0.15, 0.15, 0.002, 0.3, 0.002);
  const double ci = best_inset, cr = best_ramp;
  search(ci - 0.002, ci + 0.002, cr - 0.002, cr + 0.002, 0.0001);
  *sse = best;
  return {best_inset, best_ramp};
}

}  // namespace

bool IsPauseLabel(const std::string& text) {
  static const char* kPauses[] = {"", "_", "#", "sil", "sp", "pau", "<p:>"};
  for (const char* p : kPauses)
    if (text == p) return true;
  return false;
}

std::string OhmanOptions::Check() const {
  if (vowels.empty()) return "no vowel context given";
  for (const std::string& v : vowels)
    if (IsPauseLabel(v)) return "a vowel context cannot be a pause label";
  if (!(min_w > 0 && min_w < 1)) return "min_w must be in (0, 1)";
  if (!(min_effect >= 0 && min_effect < 1)) return "min_effect must be in [0, 1)";
  if (!(min_vowel_spread >= 0 && min_vowel_spread < 1)) return "min_vowel_spread must be in [0, 1)";
  if (!(realisation_window_s >= 0 && realisation_window_s <= 0.2)) return "realisation window must be in [0, 0.2] s";
  if (!(min_pause_s >= 0)) return "min_pause_s must be >= 0";
  if (!(k_grid_step_s > 0 && k_grid_step_s <= 0.1)) return "k grid step must be in (0, 0.1] s";
  return "";
}

std::string GenerateOptions::Check() const {
  if (!(pause_inset_s >= 0 && pause_inset_s <= 1)) return "pause inset must be in [0, 1] s";
  if (!(lead_s >= 0 && lead_s <= 10)) return "lead must be in [0, 10] s";
  return "";
}

double KStyle::Evaluate(double t_s, double start_s, double end_s) const {
  const double left = Flank(t_s - (start_s + left_inset_s - left_ramp_s), left_ramp_s);
  const double right = Flank((end_s - right_inset_s + right_ramp_s) - t_s, right_ramp_s);
  return std::min(left, right);
}

KStyle FitKStyle(const std::vector<double>& t_s, const std::vector<double>& start_s, const std::vector<double>& end_s,
                 const std::vector<double>& k, const std::vector<double>& weights) {
  const size_t n = t_s.size();
  if (start_s.size() != n || end_s.size() != n || k.size() != n || (!weights.empty() && weights.size() != n)) {
    throw InvalidInput("FitKStyle: sizes differ");
  }
  auto weight = [&](size_t i) { return weights.empty() ? 1.0 : weights[i]; };
  std::vector<double> dl, kl, wl, dr, kr, wr;
  for (size_t i = 0; i < n; ++i) {
    if (!std::isfinite(k[i]) || !std::isfinite(t_s[i]) || !(weight(i) > 0)) continue;
    const double centre = 0.5 * (start_s[i] + end_s[i]);
    if (t_s[i] < centre) {
      dl.push_back(t_s[i] - start_s[i]);
      kl.push_back(k[i]);
      wl.push_back(weight(i));
    } else {
      dr.push_back(end_s[i] - t_s[i]);
      kr.push_back(k[i]);
      wr.push_back(weight(i));
    }
  }
  if (dl.empty() && dr.empty()) throw InvalidInput("FitKStyle: no finite sample");
  KStyle s;
  double sse_l = 0, sse_r = 0;
  if (!dl.empty()) std::tie(s.left_inset_s, s.left_ramp_s) = FitFlank(dl, kl, wl, &sse_l);
  if (!dr.empty()) std::tie(s.right_inset_s, s.right_ramp_s) = FitFlank(dr, kr, wr, &sse_r);
  if (dl.empty()) s.left_inset_s = s.right_inset_s, s.left_ramp_s = s.right_ramp_s;
  if (dr.empty()) s.right_inset_s = s.left_inset_s, s.right_ramp_s = s.left_ramp_s;
  // The (weighted) RMS residual of the whole model (min of both flanks).
  double sse = 0, wsum = 0;
  int count = 0;
  for (size_t i = 0; i < n; ++i) {
    if (!std::isfinite(k[i]) || !std::isfinite(t_s[i]) || !(weight(i) > 0)) continue;
    const double e = k[i] - s.Evaluate(t_s[i], start_s[i], end_s[i]);
    sse += weight(i) * e * e;
    wsum += weight(i);
    ++count;
  }
  s.samples = count;
  s.rms = std::sqrt(sse / wsum);
  return s;
}

bool OhmanConsonant::Identifiable(int parameter) const {
  return parameter >= 0 && parameter < c.size() && std::isfinite(c[parameter]);
}

const OhmanConsonant* OhmanFit::Find(const std::string& consonant) const {
  for (const OhmanConsonant& c : consonants)
    if (c.consonant == consonant) return &c;
  return nullptr;
}

int OhmanFit::VowelIndex(const std::string& vowel) const {
  for (size_t i = 0; i < vowels.size(); ++i)
    if (vowels[i] == vowel) return static_cast<int>(i);
  return -1;
}

std::vector<Label> NormalisePhones(std::vector<Label> phones, double end_s, double min_pause_s) {
  std::stable_sort(phones.begin(), phones.end(), [](const Label& a, const Label& b) { return a.start_s < b.start_s; });
  std::vector<Label> out;
  auto push = [&](Label l) {
    if (IsPauseLabel(l.text)) l.text.clear();
    if (l.end_s <= l.start_s) return;
    if (!out.empty() && out.back().text.empty() && l.text.empty()) {
      out.back().end_s = std::max(out.back().end_s, l.end_s);
      return;
    }
    out.push_back(std::move(l));
  };
  double cursor = 0.0;
  for (Label l : phones) {
    const double gap = l.start_s - cursor;
    if (gap > 0.0) {
      if (gap > min_pause_s || out.empty()) {
        push(Label{cursor, l.start_s, ""});
      } else {
        out.back().end_s = l.start_s;
      }
    } else if (gap < 0.0) {
      l.start_s = cursor;  // overlapping labels: clip
    }
    cursor = std::max(cursor, l.end_s);
    push(std::move(l));
  }
  if (end_s > cursor) push(Label{cursor, end_s, ""});
  return out;
}

OhmanFit FitOhman(const std::vector<ParameterSeries>& series, const OhmanOptions& options) {
  if (const std::string why = options.Check(); !why.empty()) throw InvalidInput("Öhman options: " + why);
  if (series.empty()) throw InvalidInput("Öhman fit: no parameter series");
  const Eigen::Index P = series.front().values.cols();
  for (const ParameterSeries& s : series) {
    if (!(s.rate_hz > 0)) throw InvalidInput("Öhman fit: take '" + s.name + "': frame rate must be > 0");
    if (s.values.cols() != P) {
      throw InvalidInput("Öhman fit: take '" + s.name + "' has " + std::to_string(s.values.cols()) +
                         " parameters, take '" + series.front().name + "' " + std::to_string(P));
    }
  }
  if (P == 0) throw InvalidInput("Öhman fit: no parameter");
  OhmanFit fit;
  fit.num_parameters = static_cast<int>(P);
  fit.vowels = options.vowels;
  const auto nv = static_cast<Eigen::Index>(options.vowels.size());

  // Parameter ranges over every finite frame.
  Eigen::VectorXd lo = Eigen::VectorXd::Constant(P, std::numeric_limits<double>::infinity());
  Eigen::VectorXd hi = -lo;
  for (const ParameterSeries& s : series)
    for (Eigen::Index f = 0; f < s.values.rows(); ++f) {
      if (!RowFinite(s.values, f)) continue;
      lo = lo.cwiseMin(s.values.row(f).transpose());
      hi = hi.cwiseMax(s.values.row(f).transpose());
    }
  if (!lo.allFinite()) throw InvalidInput("Öhman fit: no frame with every parameter finite");
  fit.range = hi - lo;
  Eigen::VectorXd scale = fit.range;
  for (Eigen::Index x = 0; x < P; ++x)
    if (!(scale[x] > 0)) scale[x] = 1.0;

  // Pass 1: isolated vowels, pause centres, VCV tokens.
  Eigen::MatrixXd iso_sum = Eigen::MatrixXd::Zero(nv, P), vcv_sum = iso_sum;
  std::vector<int> iso_n(static_cast<size_t>(nv), 0), vcv_n(static_cast<size_t>(nv), 0);
  Eigen::VectorXd rest_sum = Eigen::VectorXd::Zero(P);
  int rest_n = 0;
  for (size_t si = 0; si < series.size(); ++si) {
    const ParameterSeries& s = series[si];
    const double duration = static_cast<double>(s.values.rows()) / s.rate_hz;
    const std::vector<Label> ph = NormalisePhones(s.phones, duration, options.min_pause_s);
    auto pause_at = [&](long i) {
      return i < 0 || i >= static_cast<long>(ph.size()) || ph[static_cast<size_t>(i)].text.empty();
    };
    auto centre = [&](long i) { return 0.5 * (ph[static_cast<size_t>(i)].start_s + ph[static_cast<size_t>(i)].end_s); };
    for (long i = 0; i < static_cast<long>(ph.size()); ++i) {
      const std::string& text = ph[static_cast<size_t>(i)].text;
      if (text.empty()) {
        if (ph[static_cast<size_t>(i)].end_s - ph[static_cast<size_t>(i)].start_s >= 0.1) {
          const Eigen::VectorXd v = ValueAt(s, centre(i));
          if (v.allFinite()) rest_sum += v, ++rest_n;
        }
        continue;
      }
      const int vi = fit.VowelIndex(text);
      if (vi >= 0 && pause_at(i - 1) && pause_at(i + 1)) {
        const Eigen::VectorXd v = ValueAt(s, centre(i));
        if (v.allFinite()) iso_sum.row(vi) += v.transpose(), ++iso_n[static_cast<size_t>(vi)];
      }
      if (vi >= 0 && pause_at(i - 1) && i + 3 <= static_cast<long>(ph.size()) && pause_at(i + 3) && !pause_at(i + 1) &&
          !pause_at(i + 2) && ph[static_cast<size_t>(i + 2)].text == text &&
          !Contains(options.vowels, ph[static_cast<size_t>(i + 1)].text)) {
        VcvToken t;
        t.series = static_cast<int>(si);
        t.vowel = text;
        t.consonant = ph[static_cast<size_t>(i + 1)].text;
        t.v1_centre_s = centre(i);
        t.c_start_s = ph[static_cast<size_t>(i + 1)].start_s;
        t.c_end_s = ph[static_cast<size_t>(i + 1)].end_s;
        t.v2_centre_s = centre(i + 2);
        for (double c : {t.v1_centre_s, t.v2_centre_s}) {
          const Eigen::VectorXd v = ValueAt(s, c);
          if (v.allFinite()) vcv_sum.row(vi) += v.transpose(), ++vcv_n[static_cast<size_t>(vi)];
        }
        fit.tokens.push_back(std::move(t));
      }
    }
  }
  if (fit.tokens.empty()) {
    throw InvalidInput("Öhman fit: no symmetric VCV token (V C V between pauses, V in the vowel contexts) in " +
                       std::to_string(series.size()) + " take(s)");
  }
  fit.rest = rest_n > 0 ? Eigen::VectorXd(rest_sum / rest_n) : Eigen::VectorXd(Eigen::VectorXd::Zero(P));
  if (rest_n == 0) fit.warnings.push_back("no pause of 0.1 s or more: the rest value is 0");
  fit.vowel_targets = Eigen::MatrixXd::Constant(nv, P, kNaN);
  for (Eigen::Index v = 0; v < nv; ++v) {
    const size_t vs = static_cast<size_t>(v);
    if (iso_n[vs] > 0) {
      fit.vowel_targets.row(v) = iso_sum.row(v) / iso_n[vs];
      fit.vowel_source.emplace_back("isolated");
      fit.vowel_occurrences.push_back(iso_n[vs]);
    } else if (vcv_n[vs] > 0) {
      fit.vowel_targets.row(v) = vcv_sum.row(v) / vcv_n[vs];
      fit.vowel_source.emplace_back("vcv");
      fit.vowel_occurrences.push_back(vcv_n[vs]);
      fit.warnings.push_back("vowel '" + options.vowels[vs] +
                             "' never occurs alone: its reference is taken at the centres of its VCV vowels, "
                             "which the consonants already pull (effects underestimated)");
    } else {
      fit.vowel_source.emplace_back("none");
      fit.vowel_occurrences.push_back(0);
    }
  }

  // Pass 2: maximum realisation of every token.
  std::vector<VcvToken> kept;
  for (VcvToken& t : fit.tokens) {
    const ParameterSeries& s = series[static_cast<size_t>(t.series)];
    const Eigen::VectorXd vref = fit.vowel_targets.row(fit.VowelIndex(t.vowel)).transpose();
    if (!vref.allFinite()) continue;
    auto [first, last] = FramesIn(s, t.c_start_s, t.c_end_s);
    if (first > last)
      first = last = std::clamp<Eigen::Index>(
          static_cast<Eigen::Index>(std::lround(0.5 * (t.c_start_s + t.c_end_s) * s.rate_hz)), 0, s.values.rows() - 1);
    // The window (± half frames, inside the interval) whose mean is farthest from v_V.
    const auto half = static_cast<Eigen::Index>(std::floor(options.realisation_window_s * s.rate_hz + 1e-9));
    Eigen::Index best = -1;
    double best_d = -1;
    Eigen::VectorXd best_mean;
    for (Eigen::Index f = first; f <= last; ++f) {
      Eigen::VectorXd sum = Eigen::VectorXd::Zero(P);
      int n = 0;
      for (Eigen::Index g = std::max(first, f - half); g <= std::min(last, f + half); ++g)
        if (RowFinite(s.values, g)) sum += s.values.row(g).transpose(), ++n;
      if (n == 0) continue;
      const Eigen::VectorXd mean = sum / n;
      const double d = ((mean - vref).cwiseQuotient(scale)).squaredNorm();
      if (d > best_d) best_d = d, best = f, best_mean = mean;
    }
    if (best < 0) {
      fit.warnings.push_back("take '" + s.name + "': no solved frame in the consonant '" + t.consonant + "' at " +
                             std::to_string(t.c_start_s) + " s: token skipped");
      continue;
    }
    t.realisation = best_mean;
    t.realisation_s = static_cast<double>(best) / s.rate_hz;
    kept.push_back(std::move(t));
  }
  fit.tokens = std::move(kept);
  if (fit.tokens.empty()) throw InvalidInput("Öhman fit: no VCV token with a vowel reference and solved frames");

  // Pass 3: per consonant, the line through the contexts.
  std::vector<std::string> order;
  for (const VcvToken& t : fit.tokens)
    if (!Contains(order, t.consonant)) order.push_back(t.consonant);
  for (const std::string& cons : order) {
    OhmanConsonant oc;
    oc.consonant = cons;
    std::vector<Eigen::VectorXd> r_mean, v_ref;
    for (Eigen::Index v = 0; v < nv; ++v) {
      Eigen::VectorXd sum = Eigen::VectorXd::Zero(P);
      int n = 0;
      for (const VcvToken& t : fit.tokens)
        if (t.consonant == cons && t.vowel == options.vowels[static_cast<size_t>(v)]) sum += t.realisation, ++n;
      if (n == 0) continue;
      oc.tokens += n;
      oc.vowels.push_back(options.vowels[static_cast<size_t>(v)]);
      r_mean.push_back(sum / n);
      v_ref.push_back(fit.vowel_targets.row(v).transpose());
    }
    const auto nc = static_cast<Eigen::Index>(oc.vowels.size());
    oc.w = Eigen::VectorXd::Constant(P, kNaN);
    oc.intercept = oc.w;
    oc.c = oc.w;
    oc.residual = Eigen::VectorXd::Zero(P);
    oc.effect.resize(nc, P);
    oc.measured_effect.resize(nc, P);
    oc.realisation.resize(nc, P);
    for (Eigen::Index j = 0; j < nc; ++j) {
      oc.realisation.row(j) = r_mean[static_cast<size_t>(j)].transpose();
      oc.measured_effect.row(j) = (r_mean[static_cast<size_t>(j)] - v_ref[static_cast<size_t>(j)]).transpose();
    }
    oc.effect = oc.measured_effect;
    for (Eigen::Index x = 0; x < P; ++x) {
      if (nc < 2) continue;
      double vm = 0, rm = 0;
      for (Eigen::Index j = 0; j < nc; ++j)
        vm += v_ref[static_cast<size_t>(j)][x], rm += r_mean[static_cast<size_t>(j)][x];
      vm /= static_cast<double>(nc);
      rm /= static_cast<double>(nc);
      double svv = 0, svr = 0, vmin = std::numeric_limits<double>::infinity(), vmax = -vmin;
      for (Eigen::Index j = 0; j < nc; ++j) {
        const double dv = v_ref[static_cast<size_t>(j)][x] - vm;
        svv += dv * dv;
        svr += dv * (r_mean[static_cast<size_t>(j)][x] - rm);
        vmin = std::min(vmin, v_ref[static_cast<size_t>(j)][x]);
        vmax = std::max(vmax, v_ref[static_cast<size_t>(j)][x]);
      }
      if (!(vmax - vmin >= options.min_vowel_spread * scale[x]) || !(vmax - vmin > 0)) continue;  // no slope
      const double b = svr / svv;
      const double a = rm - b * vm;
      oc.w[x] = 1.0 - b;
      oc.intercept[x] = a;
      if (std::abs(oc.w[x]) >= options.min_w) oc.c[x] = a / oc.w[x];
      double sse = 0;
      for (Eigen::Index j = 0; j < nc; ++j) {
        const double vj = v_ref[static_cast<size_t>(j)][x];
        const double fitted = a + b * vj;
        oc.effect(j, x) = fitted - vj;
        const double e = r_mean[static_cast<size_t>(j)][x] - fitted;
        sse += e * e;
      }
      oc.residual[x] = std::sqrt(sse / static_cast<double>(nc));
    }
    fit.consonants.push_back(std::move(oc));
  }

  // Pass 4: k(t) per token, mean k and its stylisation per consonant.
  for (VcvToken& t : fit.tokens) {
    const ParameterSeries& s = series[static_cast<size_t>(t.series)];
    const OhmanConsonant& oc = *fit.Find(t.consonant);
    const int vi = fit.VowelIndex(t.vowel);
    const Eigen::VectorXd vref = fit.vowel_targets.row(vi).transpose();
    const auto j =
        static_cast<Eigen::Index>(std::find(oc.vowels.begin(), oc.vowels.end(), t.vowel) - oc.vowels.begin());
    const Eigen::VectorXd e = oc.effect.row(j).transpose();
    auto [first, last] = FramesIn(s, t.v1_centre_s, t.v2_centre_s);
    const Eigen::Index n = std::max<Eigen::Index>(0, last - first + 1);
    t.k_per_parameter = Eigen::MatrixXd::Constant(n, P, kNaN);
    for (Eigen::Index f = first; f <= last; ++f) {
      t.k_times_s.push_back(static_cast<double>(f) / s.rate_hz);
      double num = 0, den = 0;
      if (RowFinite(s.values, f)) {
        for (Eigen::Index x = 0; x < P; ++x) {
          if (!(std::abs(e[x]) > 0)) continue;
          const double d = s.values(f, x) - vref[x];
          if (std::abs(e[x]) >= options.min_effect * scale[x]) t.k_per_parameter(f - first, x) = d / e[x];
          const double en = e[x] / scale[x];
          num += en * d / scale[x];
          den += en * en;
        }
      }
      t.k.push_back(den > 0 ? num / den : kNaN);
      t.k_weight.push_back(den);
    }
  }
  for (OhmanConsonant& oc : fit.consonants) {
    std::vector<double> ts, starts, ends, ks, ws;
    double lo_tau = std::numeric_limits<double>::infinity(), hi_tau = -lo_tau;
    for (const VcvToken& t : fit.tokens) {
      if (t.consonant != oc.consonant) continue;
      const double c = 0.5 * (t.c_start_s + t.c_end_s);
      for (size_t i = 0; i < t.k.size(); ++i) {
        if (!std::isfinite(t.k[i])) continue;
        ts.push_back(t.k_times_s[i]);
        starts.push_back(t.c_start_s);
        ends.push_back(t.c_end_s);
        ks.push_back(t.k[i]);
        ws.push_back(t.k_weight[i]);
        lo_tau = std::min(lo_tau, t.k_times_s[i] - c);
        hi_tau = std::max(hi_tau, t.k_times_s[i] - c);
      }
    }
    if (ks.empty()) {
      fit.warnings.push_back("consonant '" + oc.consonant +
                             "': no parameter effect: " + "k(t) not derived, stylised k left at its default");
      continue;
    }
    oc.k_style = FitKStyle(ts, starts, ends, ks, ws);
    const double step = options.k_grid_step_s;
    for (double tau = std::ceil(lo_tau / step) * step; tau <= hi_tau + 1e-12; tau += step) {
      double sum = 0, wsum = 0;
      for (const VcvToken& t : fit.tokens) {
        if (t.consonant != oc.consonant || t.k.size() < 2) continue;
        const double time = 0.5 * (t.c_start_s + t.c_end_s) + tau;
        if (time < t.k_times_s.front() || time > t.k_times_s.back()) continue;
        auto it = std::upper_bound(t.k_times_s.begin(), t.k_times_s.end(), time);
        size_t i1 = std::min(static_cast<size_t>(it - t.k_times_s.begin()), t.k_times_s.size() - 1);
        size_t i0 = i1 > 0 ? i1 - 1 : 0;
        const double span = t.k_times_s[i1] - t.k_times_s[i0];
        const double a = span > 0 ? (time - t.k_times_s[i0]) / span : 0.0;
        const double k = (1 - a) * t.k[i0] + a * t.k[i1];
        const double w = (1 - a) * t.k_weight[i0] + a * t.k_weight[i1];
        if (std::isfinite(k) && w > 0) sum += w * k, wsum += w;
      }
      if (!(wsum > 0)) continue;
      oc.mean_k_times_s.push_back(tau);
      oc.mean_k.push_back(sum / wsum);
    }
  }
  return fit;
}

namespace {

struct Anchor {
  double t;
  Eigen::VectorXd v;
};

std::vector<Anchor> CarrierAnchors(const OhmanFit& fit, const std::vector<Label>& phones,
                                   const GenerateOptions& options) {
  std::vector<Anchor> anchors;
  for (const Label& ph : phones) {
    if (IsPauseLabel(ph.text)) {
      const double d = ph.end_s - ph.start_s;
      if (d > 2.0 * options.pause_inset_s + 0.04) {
        anchors.push_back({ph.start_s + options.pause_inset_s, fit.rest});
        anchors.push_back({ph.end_s - options.pause_inset_s, fit.rest});
      } else {
        anchors.push_back({0.5 * (ph.start_s + ph.end_s), fit.rest});
      }
      continue;
    }
    const int vi = fit.VowelIndex(ph.text);
    if (vi >= 0) {
      if (!fit.vowel_targets.row(vi).allFinite()) {
        throw InvalidInput("Öhman generation: vowel '" + ph.text + "' at " + std::to_string(ph.start_s) +
                           " s has no reference in the fit");
      }
      anchors.push_back({0.5 * (ph.start_s + ph.end_s), fit.vowel_targets.row(vi).transpose()});
      continue;
    }
    if (!fit.Find(ph.text) && !options.skip_unknown) {
      throw InvalidInput("Öhman generation: phone '" + ph.text + "' at " + std::to_string(ph.start_s) +
                         " s is neither a vowel nor a consonant of the fit");
    }
  }
  if (!phones.empty()) {
    if (anchors.empty() || anchors.front().t > phones.front().start_s)
      anchors.insert(anchors.begin(), {phones.front().start_s - options.lead_s, fit.rest});
    if (anchors.back().t < phones.back().end_s) anchors.push_back({phones.back().end_s + options.lead_s, fit.rest});
  }
  std::stable_sort(anchors.begin(), anchors.end(), [](const Anchor& a, const Anchor& b) { return a.t < b.t; });
  return anchors;
}

}  // namespace

Eigen::MatrixXd OhmanCarrier(const OhmanFit& fit, const std::vector<Label>& phones, const std::vector<double>& times_s,
                             const GenerateOptions& options) {
  if (const std::string why = options.Check(); !why.empty()) throw InvalidInput("Öhman generation: " + why);
  const Eigen::Index P = fit.num_parameters;
  if (fit.rest.size() != P) throw InvalidInput("Öhman generation: the fit has no rest value");
  const std::vector<Label> sorted = NormalisePhones(phones, 0.0);
  const std::vector<Anchor> anchors = CarrierAnchors(fit, sorted, options);
  Eigen::MatrixXd out(static_cast<Eigen::Index>(times_s.size()), P);
  for (size_t i = 0; i < times_s.size(); ++i) {
    const double t = times_s[i];
    Eigen::VectorXd v = fit.rest;
    if (!anchors.empty()) {
      auto it = std::upper_bound(anchors.begin(), anchors.end(), t, [](double x, const Anchor& a) { return x < a.t; });
      if (it == anchors.begin()) {
        v = anchors.front().v;
      } else if (it == anchors.end()) {
        v = anchors.back().v;
      } else {
        const Anchor& a = *(it - 1);
        const Anchor& b = *it;
        const double span = b.t - a.t;
        v = a.v + (b.v - a.v) * (span > 0 ? MinJerk((t - a.t) / span) : 1.0);
      }
    }
    out.row(static_cast<Eigen::Index>(i)) = v.transpose();
  }
  return out;
}

Eigen::MatrixXd GenerateOhman(const OhmanFit& fit, const std::vector<Label>& phones, const std::vector<double>& times_s,
                              const GenerateOptions& options) {
  Eigen::MatrixXd p = OhmanCarrier(fit, phones, times_s, options);
  struct Occurrence {
    const OhmanConsonant* c;
    double start, end;
    Eigen::VectorXd offset;  // mean measured effect: used where w is undefined
  };
  std::vector<Occurrence> occ;
  for (const Label& ph : phones) {
    if (IsPauseLabel(ph.text) || fit.VowelIndex(ph.text) >= 0) continue;
    const OhmanConsonant* c = fit.Find(ph.text);
    if (c == nullptr) continue;  // unknown and skipped (OhmanCarrier threw otherwise)
    occ.push_back({c, ph.start_s, ph.end_s, c->measured_effect.colwise().mean().transpose()});
  }
  const Eigen::Index P = fit.num_parameters;
  for (Eigen::Index x = 0; x < P; ++x) {
    std::vector<const Occurrence*> order;
    for (const Occurrence& o : occ) order.push_back(&o);
    auto w_of = [x](const Occurrence* o) {
      const double w = o->c->w[x];
      return std::isfinite(w) ? w : 0.0;
    };
    std::stable_sort(order.begin(), order.end(),
                     [&](const Occurrence* a, const Occurrence* b) { return w_of(a) < w_of(b); });
    for (const Occurrence* o : order) {
      const OhmanConsonant& c = *o->c;
      const double w = c.w[x], a = c.intercept[x];
      const KStyle& ks = c.k_style;
      const double from = o->start + ks.left_inset_s - ks.left_ramp_s;
      const double to = o->end - ks.right_inset_s + ks.right_ramp_s;
      for (size_t i = 0; i < times_s.size(); ++i) {
        const double t = times_s[i];
        if (t <= from || t >= to) continue;
        const double k = ks.Evaluate(t, o->start, o->end);
        auto row = static_cast<Eigen::Index>(i);
        if (std::isfinite(w) && std::isfinite(a)) {
          p(row, x) += k * (a - w * p(row, x));
        } else if (std::isfinite(o->offset[x])) {
          p(row, x) += k * o->offset[x];
        }
      }
    }
  }
  return p;
}

}  // namespace csw::coarticulation
