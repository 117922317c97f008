#include "analysis/cleaning/label_swaps.h"

#include <Eigen/Core>
#include <algorithm>
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

// A boundary of a pair's state: confidence 1 for an exchange seen in the
// trajectories, 0 for a break only the state evidence can decide.
struct Exchange {
  int64_t frame = 0;
  double confidence = 0.0;
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

// Reference markers of a candidate pair: for each label, the markers (not of the
// pair) whose distance to it varies least over the take (median and 1.4826 ×
// MAD), with the other label's distance to the same markers.
struct Reference {
  int marker = 0;
  double own[2] = {0, 0}, own_sd[2] = {1, 1};  // distance of label a (0) / b (1) to the marker
};
struct PairReference {
  std::vector<Reference> refs;
};

void DistanceStats(const MarkerArray& m, int p, int q, double* median, double* sd, int* count) {
  const int64_t frames = m.frames();
  const int64_t step = std::max<int64_t>(1, frames / 600);
  std::vector<double> d;
  for (int64_t f = 0; f < frames; f += step)
    if (m.Visible(f, p) && m.Visible(f, q)) d.push_back((At(m, f, p) - At(m, f, q)).norm());
  *count = static_cast<int>(d.size());
  *median = Median(&d);
  for (double& v : d) v = std::abs(v - *median);
  *sd = std::max(1.0, 1.4826 * Median(&d));
}

PairReference MakeReference(const MarkerArray& m, int a, int b, const std::set<int>& near, double max_sd) {
  struct Stat {
    int c;
    double med, sd;
  };
  std::vector<Stat> sa, sb;
  for (int c : near) {
    if (c == a || c == b) continue;
    double med, sd;
    int n;
    DistanceStats(m, a, c, &med, &sd, &n);
    if (n >= 20) sa.push_back({c, med, sd});
    DistanceStats(m, b, c, &med, &sd, &n);
    if (n >= 20) sb.push_back({c, med, sd});
  }
  auto by_sd = [](const Stat& x, const Stat& y) { return x.sd < y.sd; };
  std::sort(sa.begin(), sa.end(), by_sd);
  std::sort(sb.begin(), sb.end(), by_sd);
  std::set<int> chosen;
  for (size_t i = 0; i < std::min<size_t>(3, sa.size()); ++i) chosen.insert(sa[i].c);
  for (size_t i = 0; i < std::min<size_t>(3, sb.size()); ++i) chosen.insert(sb[i].c);
  PairReference ref;
  for (int c : chosen) {
    Reference r;
    r.marker = c;
    int n0, n1;
    DistanceStats(m, a, c, &r.own[0], &r.own_sd[0], &n0);
    DistanceStats(m, b, c, &r.own[1], &r.own_sd[1], &n1);
    if (n0 >= 20 && n1 >= 20 && std::min(r.own_sd[0], r.own_sd[1]) <= max_sd) ref.refs.push_back(r);
  }
  return ref;
}

// Log-likelihood ratio (swapped over unswapped) of the frames [begin, end):
// each label's distance to each reference marker, Gaussian about the reference
// distance of that label (unswapped) or of the other label (swapped), each term
// clipped to ±8 so one wrong reference sample cannot decide.
double SegmentEvidence(const MarkerArray& m, int a, int b, const PairReference& ref, int64_t begin, int64_t end,
                       int64_t* informative, double* swapped_misfit, int64_t* terms) {
  double total = 0.0;
  *informative = 0;
  *swapped_misfit = 0.0;
  *terms = 0;
  const int label[2] = {a, b};
  for (int64_t f = begin; f < end; ++f) {
    bool any = false;
    for (int l = 0; l < 2; ++l) {
      if (!m.Visible(f, label[l])) continue;
      const Vector3d x = At(m, f, label[l]);
      for (const Reference& r : ref.refs) {
        if (!m.Visible(f, r.marker)) continue;
        const double d = (x - At(m, f, r.marker)).norm();
        const double zu = (d - r.own[l]) / r.own_sd[l], zs = (d - r.own[1 - l]) / r.own_sd[1 - l];
        total += std::clamp(0.5 * (zu * zu - zs * zs), -8.0, 8.0);
        *swapped_misfit += std::min(zs * zs, 64.0);
        ++*terms;
        any = true;
      }
    }
    if (any) ++*informative;
  }
  return total;
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
      median[static_cast<size_t>(i * nm + j)] = median[static_cast<size_t>(j * nm + i)] = Median(&d);
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
    // Boundaries: breaks where no unswapped link fits (a label seen on both
    // sides within the bridge and continuing its own trajectory rules out an
    // exchange there).
    std::vector<Exchange> boundaries;
    for (int64_t s : candidates) {
      const End ap = Before(markers, ta, a, s, bridge), an = After(markers, ta, a, s, bridge);
      const End bp = Before(markers, tb, b, s, bridge), bn = After(markers, tb, b, s, bridge);
      double u_min = INFINITY, s_max = 0.0;
      int ns = 0;
      if (ap.ok && an.ok) u_min = std::min(u_min, LinkError(ap, an));
      if (bp.ok && bn.ok) u_min = std::min(u_min, LinkError(bp, bn));
      if (u_min < report.jump_mm) continue;
      // The best-fitting swapped link decides (the other may bridge a long gap of
      // fast motion that constant velocity cannot predict).
      s_max = INFINITY;
      if (ap.ok && bn.ok) s_max = std::min(s_max, LinkError(ap, bn)), ++ns;
      if (bp.ok && an.ok) s_max = std::min(s_max, LinkError(bp, an)), ++ns;
      // The swapped links must fit (else one marker jumped alone: a spike, a step),
      // unless no link can be made across the break (both labels hidden around it).
      const double ref_error = std::isfinite(u_min) ? u_min : report.jump_mm;
      // A label without a past within the bridge cannot be linked: the state
      // evidence alone decides there.
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
      // Confirmed exchange (1) or a break the state evidence alone must decide (0):
      // a label without a past within the bridge cannot be linked.
      if (fits)
        boundaries.push_back({s, 1.0});
      else if (ns == 0 || !ap.ok || !bp.ok)
        boundaries.push_back({s, 0.0});
    }
    if (boundaries.empty()) continue;
    // State evidence per segment between boundaries: the labels' distances to
    // reference markers whose distance to them is stable over the take.
    std::set<int> near = neighbours_of[static_cast<size_t>(a)];
    near.insert(neighbours_of[static_cast<size_t>(b)].begin(), neighbours_of[static_cast<size_t>(b)].end());
    const PairReference ref = MakeReference(markers, a, b, near, options.max_reference_sd_mm);
    if (ref.refs.empty()) {
      // No steady reference: the exchanges whose swapped links fit, paired in order.
      std::vector<Exchange> fits;
      for (const Exchange& x : boundaries)
        if (x.confidence > 0.0) fits.push_back(x);
      for (size_t i = 0; i < fits.size(); i += 2) {
        DetectedSwap d;
        d.marker_a = a;
        d.marker_b = b;
        d.first_frame = fits[i].frame;
        d.open_ended = i + 1 >= fits.size();
        d.end_frame = d.open_ended ? frames : fits[i + 1].frame;
        d.confidence = d.open_ended ? 0.5 * fits[i].confidence : std::min(fits[i].confidence, fits[i + 1].confidence);
        if (d.confidence >= options.min_confidence) report.swaps.push_back(d);
      }
      continue;
    }
    std::vector<int64_t> edges = {0};
    for (const Exchange& x : boundaries) edges.push_back(x.frame);
    edges.push_back(frames);
    bool state = false;
    int64_t run_start = -1;
    double run_evidence = 0.0;
    int64_t run_frames = 0;
    bool run_confirmed = false;
    auto close_run = [&](int64_t end, bool end_confirmed) {
      if (run_start < 0) return;
      DetectedSwap d;
      d.marker_a = a;
      d.marker_b = b;
      d.first_frame = run_start;
      d.end_frame = end;
      d.open_ended = end == frames;
      d.evidence = run_evidence / std::max<double>(1.0, static_cast<double>(run_frames));
      d.confidence = 1.0 - std::exp(-d.evidence);
      if (d.open_ended) d.confidence *= 0.5;
      // Neither exchange seen in the trajectories: stronger evidence needed.
      const bool enough = run_confirmed || end_confirmed || d.evidence >= options.min_unconfirmed_evidence;
      if (enough && d.confidence >= options.min_confidence) report.swaps.push_back(d);
      run_start = -1;
    };
    for (size_t i = 0; i + 1 < edges.size(); ++i) {
      int64_t informative = 0, terms = 0;
      double misfit = 0.0;
      const double l = SegmentEvidence(markers, a, b, ref, edges[i], edges[i + 1], &informative, &misfit, &terms);
      if (std::abs(l) >= options.min_evidence) {
        // Swapped only when the exchanged labels fit the references (mean z² below
        // max_swapped_misfit), not merely better than the labels as they are.
        const bool both_confirmed = i > 0 && boundaries[i - 1].confidence > 0.0 && i + 1 < boundaries.size() + 1 &&
                                    i < boundaries.size() && boundaries[i].confidence > 0.0;
        const bool swapped =
            l > 0.0 && (both_confirmed || misfit <= options.max_swapped_misfit * static_cast<double>(terms));
        if (swapped && !state) {
          run_start = edges[i];
          run_evidence = 0.0;
          run_frames = 0;
          run_confirmed = i > 0 && boundaries[i - 1].confidence > 0.0;
        }
        if (!swapped && state) close_run(edges[i], i > 0 && boundaries[i - 1].confidence > 0.0);
        state = swapped;
      }
      if (state) {
        run_evidence += l;
        run_frames += informative;
      }
    }
    if (state) close_run(frames, false);
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
