#include "synth/fragments.h"

#include <Eigen/LU>
#include <algorithm>
#include <cmath>
#include <map>
#include <utility>

#include "core/error.h"

namespace csw::dict {

namespace {

// Piecewise linear map through (from[k], to[k]), both strictly increasing,
// extended past the ends with the end segments' slopes (slope 1 with one point).
struct Warp {
  std::vector<double> from, to;
  double operator()(double t) const {
    if (from.size() == 1) return to[0] + (t - from[0]);
    size_t k = 0;
    if (t >= from.back()) {
      k = from.size() - 2;
    } else if (t > from.front()) {
      k = static_cast<size_t>(std::upper_bound(from.begin(), from.end(), t) - from.begin()) - 1;
    }
    const double slope = (to[k + 1] - to[k]) / (from[k + 1] - from[k]);
    return to[k] + slope * (t - from[k]);
  }
};

// A running mean of rows.
struct RowMean {
  Eigen::RowVectorXd sum;
  int count = 0;
  void Add(const Eigen::RowVectorXd& v) {
    if (count == 0) sum = Eigen::RowVectorXd::Zero(v.size());
    sum += v;
    ++count;
  }
  Eigen::RowVectorXd Value() const { return sum / static_cast<double>(count); }
};

struct Chosen {
  FragmentReport report;
  double start_s = 0, end_s = 0;  // target phone middles: the fragment's core
  // Resampled values on output frames first_frame .. first_frame + rows - 1.
  int64_t first_frame = 0;
  Eigen::MatrixXd values;
  Eigen::RowVectorXd at_start, at_end;  // held outside the computed frames
  Eigen::RowVectorXd Value(int64_t frame) const {
    if (frame < first_frame) return at_start;
    if (frame >= first_frame + values.rows()) return at_end;
    return values.row(frame - first_frame);
  }
};

}  // namespace

const char* ResamplingName(Resampling r) { return r == Resampling::kRbf ? "rbf" : "linear"; }

bool ParseResampling(const std::string& name, Resampling* r) {
  if (name == "rbf") {
    *r = Resampling::kRbf;
  } else if (name == "linear") {
    *r = Resampling::kLinear;
  } else {
    return false;
  }
  return true;
}

std::string FragmentOptions::Check() const {
  if (!(rate_hz > 0) || !std::isfinite(rate_hz)) return "rate_hz must be positive";
  if (!(rbf_shape > 0 && rbf_shape <= 100)) return "rbf_shape must be in (0, 100]";
  if (!(blend_fraction >= 0 && blend_fraction <= 1)) return "blend_fraction must be in [0, 1]";
  if (max_fragment_diphones < 0) return "max_fragment_diphones must be >= 0";
  return "";
}

double FragmentTrack::mean_diphones_per_fragment() const {
  if (fragments.empty()) return 0.0;
  double n = 0;
  for (const FragmentReport& f : fragments) n += f.slots;
  return n / static_cast<double>(fragments.size());
}

double BlendWeight(double u) { return 1.0 - MinimumJerk(u); }

Eigen::MatrixXd ResampleLinear(const Eigen::VectorXd& times, const Eigen::MatrixXd& values,
                               const Eigen::VectorXd& query) {
  const Eigen::Index n = times.size();
  Eigen::MatrixXd out(query.size(), values.cols());
  for (Eigen::Index q = 0; q < query.size(); ++q) {
    const double t = query(q);
    if (n == 1 || t <= times(0)) {
      out.row(q) = values.row(0);
    } else if (t >= times(n - 1)) {
      out.row(q) = values.row(n - 1);
    } else {
      const auto k = static_cast<Eigen::Index>(std::upper_bound(times.data(), times.data() + n, t) - times.data()) - 1;
      const double u = (t - times(k)) / (times(k + 1) - times(k));
      out.row(q) = (1 - u) * values.row(k) + u * values.row(k + 1);
    }
  }
  return out;
}

namespace {

// The global interpolant through samples [i0, i1] evaluated at `query`
// rows `rows` (all inside [times(i0), times(i1)]).
void RbfBlock(const Eigen::VectorXd& times, const Eigen::MatrixXd& values, Eigen::Index i0, Eigen::Index i1,
              const Eigen::VectorXd& query, const std::vector<Eigen::Index>& rows, double shape_s,
              Eigen::MatrixXd* out) {
  const Eigen::Index n = i1 - i0 + 1;
  // Times centred and scaled by the shape, for conditioning: φ(r) = 1/sqrt(r² + 1).
  const double t0 = times.segment(i0, n).mean();
  const Eigen::VectorXd x = (times.segment(i0, n).array() - t0) / shape_s;
  Eigen::MatrixXd a = Eigen::MatrixXd::Zero(n + 2, n + 2);
  for (Eigen::Index i = 0; i < n; ++i) {
    for (Eigen::Index j = 0; j < n; ++j) {
      const double r = x(i) - x(j);
      a(i, j) = 1.0 / std::sqrt(r * r + 1.0);
    }
    a(i, n) = a(n, i) = 1.0;
    a(i, n + 1) = a(n + 1, i) = x(i);
  }
  Eigen::MatrixXd rhs = Eigen::MatrixXd::Zero(n + 2, values.cols());
  rhs.topRows(n) = values.middleRows(i0, n);
  const Eigen::MatrixXd w = a.partialPivLu().solve(rhs);
  for (const Eigen::Index q : rows) {
    const double xq = (query(q) - t0) / shape_s;
    Eigen::RowVectorXd v = w.row(n) + xq * w.row(n + 1);
    for (Eigen::Index i = 0; i < n; ++i) {
      const double r = xq - x(i);
      v += w.row(i) / std::sqrt(r * r + 1.0);
    }
    out->row(q) = v;
  }
}

}  // namespace

Eigen::MatrixXd ResampleRbf(const Eigen::VectorXd& times, const Eigen::MatrixXd& values, const Eigen::VectorXd& query,
                            double shape_s) {
  const Eigen::Index n = times.size();
  if (n < 3 || !(shape_s > 0)) return ResampleLinear(times, values, query);
  Eigen::MatrixXd out(query.size(), values.cols());
  // Queries by block of kRbfBlock samples (the interval starting at sample
  // k belongs to block k / kRbfBlock); each block's interpolant passes through
  // its samples and kRbfPad more on each side, so switching block at a
  // sample keeps the track continuous. One block when n ≤ kRbfBlock + 2 pads.
  const Eigen::Index blocks = n <= kRbfBlock + 2 * kRbfPad ? 1 : (n - 1 + kRbfBlock - 1) / kRbfBlock;
  std::vector<std::vector<Eigen::Index>> rows(static_cast<size_t>(blocks));
  for (Eigen::Index q = 0; q < query.size(); ++q) {
    const double t = query(q);
    if (t <= times(0)) {
      out.row(q) = values.row(0);
    } else if (t >= times(n - 1)) {
      out.row(q) = values.row(n - 1);
    } else {
      const auto k = static_cast<Eigen::Index>(std::upper_bound(times.data(), times.data() + n, t) - times.data()) - 1;
      rows[static_cast<size_t>(blocks == 1 ? 0 : std::min(k / kRbfBlock, blocks - 1))].push_back(q);
    }
  }
  for (Eigen::Index b = 0; b < blocks; ++b) {
    if (rows[static_cast<size_t>(b)].empty()) continue;
    const Eigen::Index i0 = blocks == 1 ? 0 : std::max<Eigen::Index>(0, b * kRbfBlock - kRbfPad);
    const Eigen::Index i1 = blocks == 1 ? n - 1 : std::min<Eigen::Index>(n - 1, (b + 1) * kRbfBlock + kRbfPad);
    RbfBlock(times, values, i0, i1, query, rows[static_cast<size_t>(b)], shape_s, &out);
  }
  return out;
}

FragmentTrack ConcatenateFragments(const Dictionary& d, const std::vector<PhoneTarget>& phones, double duration_s,
                                   const FragmentOptions& o) {
  if (const std::string why = o.Check(); !why.empty()) throw InvalidInput(why);
  CheckDiphoneUnits(d);
  const Eigen::Index Q = d.diphones.front().face_params.cols();
  const std::vector<double> mid = PhoneMiddles(phones, duration_s);

  std::map<std::pair<std::string, int>, int> by_position;  // (take, first phone index) → unit
  std::map<std::string, RowMean> phone_mean;
  RowMean global;
  for (size_t j = 0; j < d.diphones.size(); ++j) {
    const DiphoneUnit& u = d.diphones[j];
    by_position[{u.take, u.index}] = static_cast<int>(j);
    phone_mean[u.phone1].Add(u.face_params.row(0));
    phone_mean[u.phone2].Add(u.face_params.row(u.frames() - 1));
    global.Add(u.face_params.row(0));
    global.Add(u.face_params.row(u.frames() - 1));
  }
  auto unit_at = [&](const std::string& take, int index) -> const DiphoneUnit* {
    const auto it = by_position.find({take, index});
    return it == by_position.end() ? nullptr : &d.diphones[static_cast<size_t>(it->second)];
  };
  auto id_at = [&](const std::string& take, int index) { return by_position.at({take, index}); };

  const int slots = static_cast<int>(phones.size()) - 1;
  const int limit = o.max_fragment_diphones > 0 ? o.max_fragment_diphones : slots;
  std::vector<Chosen> chosen;
  // 1. Greedy longest match.
  for (int i = 0; i < slots;) {
    int best_len = 0, best_context = -1;
    double best_timing = 0;
    const DiphoneUnit* best = nullptr;
    for (const DiphoneUnit& u : d.diphones) {
      if (u.phone1 != phones[static_cast<size_t>(i)].phone || u.phone2 != phones[static_cast<size_t>(i) + 1].phone)
        continue;
      int len = 1;
      while (i + len < slots && len < limit) {
        const DiphoneUnit* next = unit_at(u.take, u.index + len);
        if (!next || next->phone1 != phones[static_cast<size_t>(i + len)].phone ||
            next->phone2 != phones[static_cast<size_t>(i + len) + 1].phone)
          break;
        ++len;
      }
      if (len < best_len) continue;
      int context = 0;
      const DiphoneUnit* before = unit_at(u.take, u.index - 1);
      if (i > 0 && before && before->phone1 == phones[static_cast<size_t>(i) - 1].phone) ++context;
      const DiphoneUnit* after = unit_at(u.take, u.index + len);
      if (i + len + 1 < static_cast<int>(phones.size()) && after &&
          after->phone2 == phones[static_cast<size_t>(i + len) + 1].phone)
        ++context;
      // Durations: the first phone's second half, the inner phones, the last phone's first half.
      double sq = 0;
      for (int k = 0; k <= len; ++k) {
        const PhoneTarget& p = phones[static_cast<size_t>(i + k)];
        double target = p.end_s - p.start_s, source = 0;
        if (k == 0) {
          target = p.end_s - mid[static_cast<size_t>(i)];
          source = u.phone1_end_s - u.start_s;
        } else {
          const DiphoneUnit& v = *unit_at(u.take, u.index + k - 1);
          if (k == len) {
            target = mid[static_cast<size_t>(i + k)] - p.start_s;
            source = v.end_s - v.phone2_start_s;
          } else {
            source = v.phone2_end_s - v.phone2_start_s;
          }
        }
        sq += (source - target) * (source - target);
      }
      const double timing = std::sqrt(sq / (len + 1));
      if (len > best_len || context > best_context || (context == best_context && timing < best_timing)) {
        best_len = len;
        best_context = context;
        best_timing = timing;
        best = &u;
      }
    }
    Chosen c;
    c.start_s = mid[static_cast<size_t>(i)];
    c.report.first_slot = i;
    if (best) {
      c.report.take = best->take;
      c.report.slots = best_len;
      c.report.context_matches = best_context;
      c.report.timing_rms_s = best_timing;
      for (int k = 0; k < best_len; ++k) c.report.units.push_back(id_at(best->take, best->index + k));
    } else {
      c.report.slots = 1;
      c.report.interpolated = true;
    }
    for (int k = 0; k <= c.report.slots; ++k)
      c.report.phones += (k ? " " : "") + phones[static_cast<size_t>(i + k)].phone;
    i += c.report.slots;
    c.end_s = mid[static_cast<size_t>(i)];
    chosen.push_back(std::move(c));
  }

  // Overlap half-widths at each join (between fragment k and k + 1).
  std::vector<double> half(chosen.size(), 0.0);
  for (size_t k = 0; k + 1 < chosen.size(); ++k) {
    const PhoneTarget& p = phones[static_cast<size_t>(chosen[k + 1].report.first_slot)];
    half[k] = 0.5 * o.blend_fraction * (p.end_s - p.start_s);
  }
  const int64_t frames = static_cast<int64_t>(std::llround(duration_s * o.rate_hz)) + 1;
  auto frame_of = [&](double t) { return static_cast<int64_t>(std::floor(t * o.rate_hz)); };

  // 2-3. Warp and resample each fragment over its core and overlaps.
  for (size_t k = 0; k < chosen.size(); ++k) {
    Chosen& c = chosen[k];
    const double from_t = c.start_s - (k > 0 ? half[k - 1] : 0.0), to_t = c.end_s + half[k];
    const int64_t f0 = std::max<int64_t>(0, frame_of(from_t)), f1 = std::min<int64_t>(frames - 1, frame_of(to_t) + 1);
    c.first_frame = f0;
    const Eigen::Index rows = std::max<int64_t>(0, f1 - f0 + 1);
    Eigen::VectorXd query(rows);
    for (Eigen::Index r = 0; r < rows; ++r) query(r) = static_cast<double>(f0 + r) / o.rate_hz;
    if (c.report.interpolated) {
      const std::string& p1 = phones[static_cast<size_t>(c.report.first_slot)].phone;
      const std::string& p2 = phones[static_cast<size_t>(c.report.first_slot) + 1].phone;
      c.at_start = phone_mean.count(p1) ? phone_mean.at(p1).Value() : global.Value();
      c.at_end = phone_mean.count(p2) ? phone_mean.at(p2).Value() : global.Value();
      c.values.resize(rows, Q);
      for (Eigen::Index r = 0; r < rows; ++r)
        c.values.row(r) =
            c.at_start + MinimumJerk((query(r) - c.start_s) / (c.end_s - c.start_s)) * (c.at_end - c.at_start);
      continue;
    }
    const DiphoneUnit& first = d.diphones[static_cast<size_t>(c.report.units.front())];
    const DiphoneUnit& last = d.diphones[static_cast<size_t>(c.report.units.back())];
    // The take's samples: the fragment's units and, as context, their neighbours.
    std::map<int64_t, Eigen::RowVectorXd> samples;
    auto add = [&](const DiphoneUnit* u) {
      if (!u) return;
      for (Eigen::Index r = 0; r < u->frames(); ++r) samples.emplace(u->first_frame + r, u->face_params.row(r));
    };
    add(unit_at(first.take, first.index - 1));
    for (int id : c.report.units) add(&d.diphones[static_cast<size_t>(id)]);
    add(unit_at(last.take, last.index + 1));
    // The warp: source label times → target label times.
    Warp warp;
    auto anchor = [&](double s, double t) {
      if (warp.from.empty() || (s > warp.from.back() + 1e-9 && t > warp.to.back() + 1e-9)) {
        warp.from.push_back(s);
        warp.to.push_back(t);
      }
    };
    anchor(first.start_s, c.start_s);
    if (o.align_phones) {
      for (size_t m = 0; m < c.report.units.size(); ++m) {
        const DiphoneUnit& u = d.diphones[static_cast<size_t>(c.report.units[m])];
        anchor(u.phone1_end_s, phones[static_cast<size_t>(c.report.first_slot) + m].end_s);
      }
    }
    anchor(last.end_s, c.end_s);
    if (warp.from.size() < 2 || !(last.end_s > first.start_s)) {  // a fragment without duration
      c.at_start = first.face_params.row(0);
      c.at_end = last.face_params.row(last.frames() - 1);
      c.values = c.at_start.replicate(rows, 1);
      continue;
    }
    // Warped samples closer than half an output frame are merged (their
    // mean time and value): a fragment squeezed onto a short slot packs its
    // samples, which add nothing at the output rate and would make the
    // interpolation ill-conditioned.
    const double min_gap = 0.5 / o.rate_hz;
    std::vector<double> tv;
    std::vector<Eigen::RowVectorXd> vv;
    double cluster_t0 = 0;
    int cluster_n = 0;
    for (const auto& [frame, row] : samples) {
      const double t = warp(static_cast<double>(frame) / first.rate_hz);
      if (cluster_n > 0 && t - cluster_t0 < min_gap) {
        tv.back() = (tv.back() * cluster_n + t) / (cluster_n + 1);
        vv.back() = (vv.back() * cluster_n + row) / (cluster_n + 1);
        ++cluster_n;
        continue;
      }
      tv.push_back(t);
      vv.push_back(row);
      cluster_t0 = t;
      cluster_n = 1;
    }
    const auto n = static_cast<Eigen::Index>(tv.size());
    Eigen::VectorXd times(n);
    Eigen::MatrixXd values(n, Q);
    double spacing = 0;
    for (Eigen::Index r = 0; r < n; ++r) {
      times(r) = tv[static_cast<size_t>(r)];
      values.row(r) = vv[static_cast<size_t>(r)];
      if (r > 0) spacing = r == 1 ? times(1) - times(0) : std::min(spacing, times(r) - times(r - 1));
    }
    if (o.resampling == Resampling::kRbf && spacing > 0) {
      // The shape from the closest pair: its conditioning is then that of
      // evenly spaced samples at rbf_shape; where the warp stretched the
      // samples apart the bases are narrower relative to them.
      c.values = ResampleRbf(times, values, query, o.rbf_shape * spacing);
      // A safety net: an interpolant that strays beyond the samples' range
      // by more than that range is numerically broken; linear instead.
      const Eigen::RowVectorXd lo = values.colwise().minCoeff(), hi = values.colwise().maxCoeff();
      const Eigen::RowVectorXd span = (hi - lo).cwiseMax(1e-9);
      bool broken = !c.values.allFinite();
      for (Eigen::Index r = 0; r < c.values.rows() && !broken; ++r)
        broken = ((c.values.row(r) - hi).array() > span.array()).any() ||
                 ((lo - c.values.row(r)).array() > span.array()).any();
      if (broken) {
        c.values = ResampleLinear(times, values, query);
        c.report.linear_fallback = true;
      }
    } else {
      c.values = ResampleLinear(times, values, query);
    }
    c.at_start = values.row(0);
    c.at_end = values.row(n - 1);
    if (rows > 0) {
      c.at_start = c.values.row(0);
      c.at_end = c.values.row(rows - 1);
    }
  }

  // 4. Render with blended overlaps; hold before the first middle and after the last.
  FragmentTrack out;
  out.rate_hz = o.rate_hz;
  out.face_params.resize(frames, Q);
  size_t k = 0;
  for (int64_t f = 0; f < frames; ++f) {
    const double t = static_cast<double>(f) / o.rate_hz;
    while (k + 1 < chosen.size() && t >= chosen[k].end_s) ++k;
    Eigen::RowVectorXd v = chosen[k].Value(f);
    if (k > 0 && half[k - 1] > 0 && t < chosen[k].start_s + half[k - 1]) {
      const double u = (t - (chosen[k].start_s - half[k - 1])) / (2 * half[k - 1]);
      v = BlendWeight(u) * chosen[k - 1].Value(f) + (1 - BlendWeight(u)) * v;
    } else if (k + 1 < chosen.size() && half[k] > 0 && t > chosen[k].end_s - half[k]) {
      const double u = (t - (chosen[k].end_s - half[k])) / (2 * half[k]);
      v = BlendWeight(u) * v + (1 - BlendWeight(u)) * chosen[k + 1].Value(f);
    }
    out.face_params.row(f) = v;
  }
  for (Chosen& c : chosen) out.fragments.push_back(std::move(c.report));
  return out;
}

FaceTrack ToFaceTrack(const FragmentTrack& track, const std::vector<PhoneTarget>& phones) {
  FaceTrack out;
  out.rate_hz = track.rate_hz;
  out.face_params = track.face_params;
  for (const FragmentReport& f : track.fragments) {
    for (int s = 0; s < f.slots; ++s) {
      const size_t i = static_cast<size_t>(f.first_slot + s);
      DiphoneReport r;
      r.phone1 = phones[i].phone;
      r.phone2 = phones[i + 1].phone;
      r.start_s = 0.5 * (phones[i].start_s + phones[i].end_s);
      r.end_s = 0.5 * (phones[i + 1].start_s + phones[i + 1].end_s);
      r.level = f.interpolated ? DiphoneLevel::kInterpolated : DiphoneLevel::kWhole;
      if (!f.interpolated) r.units.push_back(f.units[static_cast<size_t>(s)]);
      out.fallback_per_diphone.push_back(static_cast<int>(r.level));
      out.diphones.push_back(std::move(r));
    }
  }
  return out;
}

}  // namespace csw::dict
