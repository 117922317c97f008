#include "analysis/cleaning/label_swaps.h"

#include <Eigen/Core>
#include <algorithm>
#include <array>
#include <cmath>
#include <set>
#include <string>

#include "core/error.h"

namespace csw::cleaning {

namespace {

using Eigen::Vector3d;

Vector3d At(const MarkerArray& m, int64_t f, int64_t k) {
  const float* p = m.at(f, k);
  return Vector3d(p[0], p[1], p[2]);
}

double Median(std::vector<double>* v) {
  if (v->empty()) return 0.0;
  auto mid = v->begin() + static_cast<std::ptrdiff_t>(v->size() / 2);
  std::nth_element(v->begin(), mid, v->end());
  return *mid;
}

// One label's trajectory: where it is seen and where it breaks (jumps).
struct Track {
  std::vector<uint8_t> visible;
  std::vector<uint8_t> broken;  // broken[f]: the trajectory breaks between the samples at f-1 and f
  std::vector<int64_t> breaks;  // frames that jump or reappear after missing samples
};

Track MakeTrack(const MarkerArray& m, int k, double jump_mm) {
  const int64_t frames = m.frames();
  Track t;
  t.visible.resize(static_cast<size_t>(frames));
  t.broken.assign(static_cast<size_t>(frames), 0);
  for (int64_t f = 0; f < frames; ++f) t.visible[static_cast<size_t>(f)] = m.Visible(f, k) ? 1 : 0;
  auto vis = [&](int64_t f) { return f >= 0 && f < frames && t.visible[static_cast<size_t>(f)]; };
  for (int64_t f = 0; f < frames; ++f) {
    if (!vis(f)) continue;
    if (!vis(f - 1)) {
      if (f > 0) t.breaks.push_back(f);  // reappears
      continue;
    }
    // Forward constant-velocity prediction when the two samples before are one
    // trajectory; else backward from the two samples after; else the step.
    double residual;
    if (vis(f - 2) && !t.broken[static_cast<size_t>(f - 1)])
      residual = (At(m, f, k) - 2.0 * At(m, f - 1, k) + At(m, f - 2, k)).norm();
    else if (vis(f + 1))
      residual = (At(m, f - 1, k) - 2.0 * At(m, f, k) + At(m, f + 1, k)).norm();
    else
      residual = (At(m, f, k) - At(m, f - 1, k)).norm();
    if (residual > jump_mm) {
      t.broken[static_cast<size_t>(f)] = 1;
      t.breaks.push_back(f);
    }
  }
  return t;
}

// The end of a label's segment next to a break: position and, when the
// neighbouring sample is on the same segment, velocity (mm/frame).
struct End {
  bool ok = false;
  int64_t frame = 0;
  Vector3d x = Vector3d::Zero();
  bool has_v = false;
  Vector3d v = Vector3d::Zero();
};

End Before(const MarkerArray& m, const Track& t, int k, int64_t s, int64_t bridge) {
  End e;
  for (int64_t p = s - 1; p >= 0 && p >= s - bridge; --p) {
    if (!t.visible[static_cast<size_t>(p)]) continue;
    e.ok = true;
    e.frame = p;
    e.x = At(m, p, k);
    if (p >= 1 && t.visible[static_cast<size_t>(p - 1)] && !t.broken[static_cast<size_t>(p)]) {
      e.has_v = true;
      e.v = e.x - At(m, p - 1, k);
    }
    break;
  }
  return e;
}

End After(const MarkerArray& m, const Track& t, int k, int64_t s, int64_t bridge) {
  End e;
  const int64_t frames = m.frames();
  for (int64_t n = s; n < frames && n < s + bridge; ++n) {
    if (!t.visible[static_cast<size_t>(n)]) continue;
    e.ok = true;
    e.frame = n;
    e.x = At(m, n, k);
    if (n + 1 < frames && t.visible[static_cast<size_t>(n + 1)] && !t.broken[static_cast<size_t>(n + 1)]) {
      e.has_v = true;
      e.v = At(m, n + 1, k) - e.x;
    }
    break;
  }
  return e;
}

// Constant-velocity extrapolation error (mm) of linking a segment's end to the
// next segment's start, averaged over the two directions that have a velocity.
double LinkError(const End& pre, const End& post) {
  const double d = static_cast<double>(post.frame - pre.frame);
  double sum = 0.0;
  int n = 0;
  if (pre.has_v) {
    sum += (post.x - (pre.x + d * pre.v)).norm();
    ++n;
  }
  if (post.has_v) {
    sum += (pre.x - (post.x - d * post.v)).norm();
    ++n;
  }
  return n == 0 ? (post.x - pre.x).norm() : sum / n;
}

// A boundary of a pair's state: a break where neither label continues its own
// trajectory. Confirmed: the swapped links fit (an exchange seen in the
// trajectories); open: a label has no past within the bridge; broken: both
// labels jump but the swapped links do not fit either.
struct Boundary {
  enum Kind { kConfirmed, kOpen, kBroken };
  int64_t frame = 0;
  Kind kind = kBroken;
};

double RobustResidualSigma(const MarkerArray& m) {
  const int64_t frames = m.frames(), nm = m.markers();
  std::vector<double> values;
  const int64_t step = std::max<int64_t>(1, frames * nm / 40000);
  for (int64_t k = 0; k < nm; ++k)
    for (int64_t f = 2 + (k % step); f < frames; f += step) {
      if (!m.Visible(f, k) || !m.Visible(f - 1, k) || !m.Visible(f - 2, k)) continue;
      const Vector3d r = At(m, f, k) - 2.0 * At(m, f - 1, k) + At(m, f - 2, k);
      for (int c = 0; c < 3; ++c) values.push_back(r[c]);
    }
  const double med = Median(&values);
  for (double& v : values) v = std::abs(v - med);
  return 1.4826 * Median(&values);
}

// Rigid references (swap-invariant): a marker c whose distance to one of the
// pair's markers stays at m over the take. The pair's labels may be exchanged
// over part of the take, so each frame is judged by whichever label is nearer
// m: the spread of that deviation is the same with or without a swap.
struct Rigid {
  int marker = 0;
  int label = 0;  // 0: rigid with marker a, 1: with marker b
  double distance = 0.0, sd = 1.0;
};

bool RigidReference(const MarkerArray& m, int a, int b, int c, int label, double* distance, double* sd) {
  const int64_t frames = m.frames();
  std::vector<double> own, both_a, both_b;
  std::vector<int64_t> seen;
  for (int64_t f = 0; f < frames; ++f) {
    if (!m.Visible(f, c)) continue;
    const Vector3d x = At(m, f, c);
    const bool va = m.Visible(f, a), vb = m.Visible(f, b);
    if (!va && !vb) continue;
    seen.push_back(f);
    both_a.push_back(va ? (At(m, f, a) - x).norm() : NAN);
    both_b.push_back(vb ? (At(m, f, b) - x).norm() : NAN);
    const double d = label == 0 ? both_a.back() : both_b.back();
    if (!std::isnan(d)) own.push_back(d);
  }
  if (own.size() < 20) return false;
  double centre = Median(&own);
  std::vector<double> dev;
  for (int iter = 0; iter < 2; ++iter) {
    std::vector<double> nearest;
    dev.clear();
    for (size_t i = 0; i < seen.size(); ++i) {
      double best = INFINITY, bd = NAN;
      for (double d : {both_a[i], both_b[i]})
        if (!std::isnan(d) && std::abs(d - centre) < best) best = std::abs(d - centre), bd = d;
      nearest.push_back(bd);
      dev.push_back(best);
    }
    centre = Median(&nearest);
  }
  for (double& v : dev) v = std::abs(v);
  auto q = dev.begin() + static_cast<std::ptrdiff_t>(dev.size() * 9 / 10);
  std::nth_element(dev.begin(), q, dev.end());
  *distance = centre;
  *sd = *q / 1.645;
  // The marker's own label must be the one at that distance most of the time
  // (a swap exchanges a minority of the frames).
  const double tol = 3.0 * std::max(*sd, 1.0);
  size_t own_fits = 0, other_fits = 0;
  const std::vector<double>& mine = label == 0 ? both_a : both_b;
  const std::vector<double>& theirs = label == 0 ? both_b : both_a;
  for (size_t i = 0; i < seen.size(); ++i) {
    if (!std::isnan(mine[i]) && std::abs(mine[i] - centre) <= tol) ++own_fits;
    if (!std::isnan(theirs[i]) && std::abs(theirs[i] - centre) <= tol) ++other_fits;
  }
  return own_fits >= 2 * other_fits && own_fits >= 20;
}

// 1.4826 × MAD of the distance between markers p and q (infinite when seen
// together in fewer than 20 frames).
double OwnSpread(const MarkerArray& m, int p, int q) {
  std::vector<double> d;
  for (int64_t f = 0; f < m.frames(); ++f)
    if (m.Visible(f, p) && m.Visible(f, q)) d.push_back((At(m, f, p) - At(m, f, q)).norm());
  if (d.size() < 20) return INFINITY;
  const double centre = Median(&d);
  for (double& v : d) v = std::abs(v - centre);
  return 1.4826 * Median(&d);
}

// Evidence that a label sits at a rigid reference's distance: log of a
// Gaussian-with-outliers likelihood over the outlier floor, in [0, clip].
double Fit(double d, const Rigid& r, double floor_sd, double clip) {
  const double z = (d - r.distance) / std::max(r.sd, floor_sd);
  return std::log1p(std::exp(clip - 0.5 * z * z));
}

}  // namespace

std::vector<std::pair<int, int>> NeighbourPairs(const MarkerArray& markers, int neighbours, double max_distance_mm) {
  if (neighbours < 1) throw InvalidInput("label swaps: neighbours must be ≥ 1");
  const int64_t frames = markers.frames();
  const int nm = static_cast<int>(markers.markers());
  const int64_t step = std::max<int64_t>(1, frames / 400);
  std::vector<double> median(static_cast<size_t>(nm) * static_cast<size_t>(nm), INFINITY);
  std::vector<double> d;
  for (int i = 0; i < nm; ++i)
    for (int j = i + 1; j < nm; ++j) {
      d.clear();
      for (int64_t f = 0; f < frames; f += step)
        if (markers.Visible(f, i) && markers.Visible(f, j)) d.push_back((At(markers, f, i) - At(markers, f, j)).norm());
      if (d.size() < 5) continue;
      auto q = d.begin() + static_cast<std::ptrdiff_t>(d.size() / 10);
      std::nth_element(d.begin(), q, d.end());
      median[static_cast<size_t>(i * nm + j)] = median[static_cast<size_t>(j * nm + i)] = *q;
    }
  std::set<std::pair<int, int>> pairs;
  std::vector<int> order(static_cast<size_t>(nm));
  for (int i = 0; i < nm; ++i) {
    for (int j = 0; j < nm; ++j) order[static_cast<size_t>(j)] = j;
    const double* row = &median[static_cast<size_t>(i * nm)];
    std::sort(order.begin(), order.end(), [&](int x, int y) { return row[x] < row[y]; });
    int taken = 0;
    for (int j : order) {
      if (taken >= neighbours || !(row[j] <= max_distance_mm)) break;
      if (j == i) continue;
      pairs.insert({std::min(i, j), std::max(i, j)});
      ++taken;
    }
  }
  return {pairs.begin(), pairs.end()};
}

SwapReport DetectLabelSwaps(const MarkerArray& markers, double rate_hz, const SwapOptions& options) {
  if (!(rate_hz > 0.0)) throw InvalidInput("label swaps: the frame rate must be positive");
  if (options.jump_mm < 0.0 || options.jump_floor_mm < 0.0 || !(options.jump_noise_factor > 0.0) ||
      !(options.max_bridge_s > 0.0) || !(options.max_cost_ratio > 0.0 && options.max_cost_ratio < 1.0))
    throw InvalidInput(
        "label swaps: jump thresholds must be ≥ 0, the noise factor and bridge > 0, the cost ratio in (0, 1)");
  if (options.references < 1 || !(options.reference_clip > 0.0) || !(options.evidence_weight > 0.0) ||
      options.confirmed_bonus < 0.0 || options.open_penalty < 0.0 || options.broken_penalty < 0.0 ||
      options.start_penalty < 0.0 || !(options.max_reference_sd_mm > 0.0))
    throw InvalidInput(
        "label swaps: references must be ≥ 1, the reference clip, evidence weight and reference spread > 0, the "
        "state-change bonus and penalties ≥ 0");
  const int nm = static_cast<int>(markers.markers());
  const int64_t frames = markers.frames();
  auto check = [&](int c) {
    if (c < 0 || c >= nm)
      throw InvalidInput("label swaps: column " + std::to_string(c) + " is not in the take's " + std::to_string(nm) +
                         " markers");
  };
  SwapReport report;
  std::set<std::pair<int, int>> pairs;
  if (!options.pairs.empty()) {
    for (auto [a, b] : options.pairs) {
      check(a);
      check(b);
      if (a == b)
        throw InvalidInput("label swaps: pair (" + std::to_string(a) + ", " + std::to_string(b) + ") is one marker");
      pairs.insert({std::min(a, b), std::max(a, b)});
    }
  } else if (!options.groups.empty()) {
    for (const auto& g : options.groups)
      for (size_t i = 0; i < g.size(); ++i) {
        check(g[i]);
        for (size_t j = i + 1; j < g.size(); ++j)
          if (g[i] != g[j]) pairs.insert({std::min(g[i], g[j]), std::max(g[i], g[j])});
      }
  } else {
    for (auto p : NeighbourPairs(markers, options.neighbours, options.max_pair_distance_mm)) pairs.insert(p);
  }
  report.candidate_pairs.assign(pairs.begin(), pairs.end());
  report.jump_mm = options.jump_mm > 0.0
                       ? options.jump_mm
                       : std::max(options.jump_floor_mm, options.jump_noise_factor * RobustResidualSigma(markers));
  const int64_t bridge = std::max<int64_t>(1, static_cast<int64_t>(std::lround(options.max_bridge_s * rate_hz)));

  std::vector<std::set<int>> neighbours_of(static_cast<size_t>(nm));
  for (auto [a, b] : report.candidate_pairs) {
    neighbours_of[static_cast<size_t>(a)].insert(b);
    neighbours_of[static_cast<size_t>(b)].insert(a);
  }
  std::vector<float> own_spread(static_cast<size_t>(nm) * static_cast<size_t>(nm), -1.0f);
  std::vector<Track> tracks(static_cast<size_t>(nm));
  std::vector<uint8_t> made(static_cast<size_t>(nm), 0);
  auto track = [&](int k) -> const Track& {
    if (!made[static_cast<size_t>(k)]) {
      tracks[static_cast<size_t>(k)] = MakeTrack(markers, k, report.jump_mm);
      made[static_cast<size_t>(k)] = 1;
    }
    return tracks[static_cast<size_t>(k)];
  };

  for (auto [a, b] : report.candidate_pairs) {
    const Track& ta = track(a);
    const Track& tb = track(b);
    std::vector<int64_t> candidates;
    std::merge(ta.breaks.begin(), ta.breaks.end(), tb.breaks.begin(), tb.breaks.end(), std::back_inserter(candidates));
    candidates.erase(std::unique(candidates.begin(), candidates.end()), candidates.end());
    // Boundaries: breaks where neither label continues its own trajectory (a
    // label seen on both sides within the bridge and continuing its own
    // trajectory rules out an exchange there).
    std::vector<Boundary> boundaries;
    for (int64_t s : candidates) {
      const End ap = Before(markers, ta, a, s, bridge), an = After(markers, ta, a, s, bridge);
      const End bp = Before(markers, tb, b, s, bridge), bn = After(markers, tb, b, s, bridge);
      double u_min = INFINITY;
      if (ap.ok && an.ok) u_min = std::min(u_min, LinkError(ap, an));
      if (bp.ok && bn.ok) u_min = std::min(u_min, LinkError(bp, bn));
      if (u_min < report.jump_mm) continue;
      // The best-fitting swapped link decides (the other may bridge a long gap of
      // fast motion that constant velocity cannot predict).
      double s_max = INFINITY;
      int ns = 0;
      if (ap.ok && bn.ok) s_max = std::min(s_max, LinkError(ap, bn)), ++ns;
      if (bp.ok && an.ok) s_max = std::min(s_max, LinkError(bp, an)), ++ns;
      const double ref_error = std::isfinite(u_min) ? u_min : report.jump_mm;
      bool fits = ns > 0 && s_max <= options.max_cost_ratio * ref_error;
      if (!fits && ap.frame == s - 1 && bp.frame == s - 1 && an.frame == s && bn.frame == s) {
        // Both seen across the break: the pair's relative vector, which the hand's
        // common motion leaves slow, flips sign at an exchange.
        Vector3d r_pred = bp.x - ap.x;
        if (ap.has_v && bp.has_v) r_pred += bp.v - ap.v;
        const Vector3d r_now = bn.x - an.x;
        const double flip = (r_now + r_pred).norm(), keep = (r_now - r_pred).norm();
        fits = keep >= report.jump_mm && flip <= options.max_cost_ratio * keep;
      }
      Boundary x;
      x.frame = s;
      x.kind = fits ? Boundary::kConfirmed : (ns == 0 || !ap.ok || !bp.ok) ? Boundary::kOpen : Boundary::kBroken;
      boundaries.push_back(x);
    }
    if (boundaries.empty()) continue;
    // Rigid references of either marker among the pair's neighbours.
    std::set<int> near = neighbours_of[static_cast<size_t>(a)];
    near.insert(neighbours_of[static_cast<size_t>(b)].begin(), neighbours_of[static_cast<size_t>(b)].end());
    std::vector<Rigid> refs;
    for (int label = 0; label < 2; ++label) {
      std::vector<Rigid> mine;
      for (int c : near) {
        if (c == a || c == b) continue;
        // Quick screen (cached per marker pair): the own label's robust spread
        // (1.4826 × MAD, unmoved by a swap over a minority of the frames).
        float& screen =
            own_spread[static_cast<size_t>(label == 0 ? a : b) * static_cast<size_t>(nm) + static_cast<size_t>(c)];
        if (screen < 0.0f) screen = static_cast<float>(OwnSpread(markers, label == 0 ? a : b, c));
        if (!(screen <= options.max_reference_sd_mm)) continue;
        Rigid r;
        r.marker = c;
        r.label = label;
        if (RigidReference(markers, a, b, c, label, &r.distance, &r.sd) && r.sd <= options.max_reference_sd_mm)
          mine.push_back(r);
      }
      std::sort(mine.begin(), mine.end(), [](const Rigid& x, const Rigid& y) { return x.sd < y.sd; });
      if (mine.size() > static_cast<size_t>(options.references)) mine.resize(static_cast<size_t>(options.references));
      refs.insert(refs.end(), mine.begin(), mine.end());
    }
    if (refs.empty()) {
      // No steady reference: the exchanges whose swapped links fit, paired in order.
      std::vector<int64_t> fits;
      for (const Boundary& x : boundaries)
        if (x.kind == Boundary::kConfirmed) fits.push_back(x.frame);
      for (size_t i = 0; i < fits.size(); i += 2) {
        DetectedSwap d;
        d.marker_a = a;
        d.marker_b = b;
        d.first_frame = fits[i];
        d.open_ended = i + 1 >= fits.size();
        d.end_frame = d.open_ended ? frames : fits[i + 1];
        d.confidence = d.open_ended ? 0.5 : 1.0;
        // Unpaired, an exchange is only reported for pairs the caller named.
        if (d.open_ended && options.pairs.empty()) continue;
        if (d.confidence >= options.min_confidence) report.swaps.push_back(d);
      }
      continue;
    }
    // Segments between boundaries and their reference evidence (swapped over not).
    std::vector<int64_t> edges = {0};
    for (const Boundary& x : boundaries) edges.push_back(x.frame);
    edges.push_back(frames);
    const size_t n = edges.size() - 1;
    std::vector<double> evidence(n, 0.0);
    std::vector<std::array<double, 2>> side_evidence(n, {0.0, 0.0});
    std::vector<int64_t> informative(n, 0);
    const int label_col[2] = {a, b};
    bool sides[2] = {false, false};
    for (const Rigid& r : refs) sides[r.label] = true;
    for (size_t i = 0; i < n; ++i)
      for (int64_t f = edges[i]; f < edges[i + 1]; ++f) {
        double sum[2] = {0.0, 0.0};
        int count[2] = {0, 0};
        for (const Rigid& r : refs) {
          if (!markers.Visible(f, r.marker)) continue;
          const Vector3d c = At(markers, f, r.marker);
          const int own = label_col[r.label], other = label_col[1 - r.label];
          const bool vo = markers.Visible(f, own), vx = markers.Visible(f, other);
          if (!vo && !vx) continue;
          const double fit_own = vo ? Fit((At(markers, f, own) - c).norm(), r, 1.0, options.reference_clip) : 0.0;
          const double fit_other = vx ? Fit((At(markers, f, other) - c).norm(), r, 1.0, options.reference_clip) : 0.0;
          sum[r.label] += fit_other - fit_own;
          ++count[r.label];
        }
        if (count[0] + count[1] == 0) continue;
        ++informative[i];
        for (int l = 0; l < 2; ++l)
          if (count[l] > 0) {
            evidence[i] += sum[l] / count[l];
            side_evidence[i][l] += sum[l] / count[l];
          }
      }
    // Two-state Viterbi over the segments: the state's evidence plus the cost
    // of switching at each boundary (a bonus at a confirmed exchange).
    auto switch_score = [&](size_t j) {  // boundary j separates segments j and j + 1
      switch (boundaries[j].kind) {
        case Boundary::kConfirmed:
          return options.confirmed_bonus;
        case Boundary::kOpen:
          return -options.open_penalty;
        default:
          return -options.broken_penalty;
      }
    };
    const double w = options.evidence_weight;
    std::vector<std::array<int, 2>> from(n);
    std::array<double, 2> score = {0.0, w * evidence[0] - options.start_penalty};
    from[0] = {0, 1};
    for (size_t i = 1; i < n; ++i) {
      const double sw = switch_score(i - 1);
      std::array<double, 2> next;
      for (int st = 0; st < 2; ++st) {
        const double stay = score[st], change = score[1 - st] + sw;
        from[i][st] = stay >= change ? st : 1 - st;
        next[st] = std::max(stay, change) + (st == 1 ? w * evidence[i] : 0.0);
      }
      score = next;
    }
    std::vector<int> state(n);
    state[n - 1] = score[1] > score[0] ? 1 : 0;
    for (size_t i = n - 1; i > 0; --i) state[i - 1] = from[i][state[i]];
    // A swapped run also takes the neighbouring segments the references find
    // swapped (positive evidence) but the boundary costs kept out: a marker seen
    // for a frame or two in a gap around an exchange.
    for (size_t i = 1; i < n; ++i)
      if (state[i] == 1 && state[i - 1] == 0)
        for (size_t k = i - 1;
             k > 0 && state[k] == 0 && evidence[k] > 0.0 && informative[k] <= options.max_absorbed_frames; --k)
          state[k] = 1;
    for (size_t i = n - 1; i > 0; --i)
      if (state[i - 1] == 1 && state[i] == 0)
        for (size_t k = i; k < n && state[k] == 0 && evidence[k] > 0.0 && informative[k] <= options.max_absorbed_frames;
             ++k)
          state[k] = 1;
    // Runs of the swapped state; the reference fit is judged over the whole run.
    for (size_t i = 0; i < n;) {
      if (state[i] == 0) {
        ++i;
        continue;
      }
      size_t j = i;
      double ev = 0.0;
      int64_t inf = 0;
      double side[2] = {0.0, 0.0};
      while (j < n && state[j] == 1) {
        ev += evidence[j], inf += informative[j];
        side[0] += side_evidence[j][0], side[1] += side_evidence[j][1];
        ++j;
      }
      DetectedSwap d;
      d.marker_a = a;
      d.marker_b = b;
      d.first_frame = edges[i];
      d.end_frame = edges[j];
      d.open_ended = j == n;
      d.evidence = ev / std::max<double>(1.0, static_cast<double>(inf));
      d.confidence = 1.0 - std::exp(-d.evidence);
      if (d.open_ended) d.confidence *= 0.5;
      const bool confirmed_both = i > 0 && j < n && boundaries[i - 1].kind == Boundary::kConfirmed &&
                                  boundaries[j - 1].kind == Boundary::kConfirmed;
      // Each marker's references must agree; one marker's alone must be strong.
      // A marker hidden over the whole run gives no evidence (0): enough when an
      // end of the run is a confirmed exchange.
      const bool confirmed_end = (i > 0 && boundaries[i - 1].kind == Boundary::kConfirmed) ||
                                 (j < n && boundaries[j - 1].kind == Boundary::kConfirmed);
      const bool agree = (!sides[0] || side[0] > 0.0 || (side[0] == 0.0 && confirmed_end)) &&
                         (!sides[1] || side[1] > 0.0 || (side[1] == 0.0 && confirmed_end));
      const bool sided = (sides[0] && sides[1]) || options.one_sided;
      if ((confirmed_both || (sided && agree && d.evidence >= options.min_run_evidence)) &&
          d.confidence >= options.min_confidence)
        report.swaps.push_back(d);
      i = j;
    }
  }
  // Exchanges back within a few frames are jitter, not a swap of labels.
  report.swaps.erase(
      std::remove_if(report.swaps.begin(), report.swaps.end(),
                     [&](const DetectedSwap& d) { return d.end_frame - d.first_frame < options.min_frames; }),
      report.swaps.end());
  // Conflicts: a label swapped with two partners at once (the partner of a true
  // swap also looks exchanged with a third marker); the stronger evidence wins.
  std::stable_sort(report.swaps.begin(), report.swaps.end(),
                   [](const DetectedSwap& x, const DetectedSwap& y) { return x.evidence > y.evidence; });
  std::vector<DetectedSwap> kept;
  for (const DetectedSwap& d : report.swaps) {
    bool clash = false;
    for (const DetectedSwap& k : kept) {
      const bool share =
          d.marker_a == k.marker_a || d.marker_a == k.marker_b || d.marker_b == k.marker_a || d.marker_b == k.marker_b;
      if (share && d.first_frame < k.end_frame && k.first_frame < d.end_frame) clash = true;
    }
    if (!clash) kept.push_back(d);
  }
  report.swaps = std::move(kept);
  std::sort(report.swaps.begin(), report.swaps.end(), [](const DetectedSwap& x, const DetectedSwap& y) {
    if (x.first_frame != y.first_frame) return x.first_frame < y.first_frame;
    return std::make_pair(x.marker_a, x.marker_b) < std::make_pair(y.marker_a, y.marker_b);
  });
  return report;
}

void FixLabelSwaps(const std::vector<DetectedSwap>& swaps, MarkerArray* markers) {
  for (const DetectedSwap& s : swaps) {
    if (s.marker_a < 0 || s.marker_a >= markers->markers() || s.marker_b < 0 || s.marker_b >= markers->markers() ||
        s.first_frame < 0 || s.end_frame > markers->frames() || s.first_frame > s.end_frame)
      throw InvalidInput("label swap fix: markers " + std::to_string(s.marker_a) + ", " + std::to_string(s.marker_b) +
                         " frames [" + std::to_string(s.first_frame) + ", " + std::to_string(s.end_frame) +
                         ") are outside the take");
    for (int64_t f = s.first_frame; f < s.end_frame; ++f) {
      float* pa = markers->at(f, s.marker_a);
      float* pb = markers->at(f, s.marker_b);
      for (int c = 0; c < 3; ++c) std::swap(pa[c], pb[c]);
    }
  }
}

}  // namespace csw::cleaning
