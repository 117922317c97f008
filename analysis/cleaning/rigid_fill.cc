#include "analysis/cleaning/rigid_fill.h"

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>
#include <limits>
#include <nlohmann/json.hpp>
#include <set>
#include <sstream>
#include <utility>

#include "core/error.h"

namespace csw::cleaning {
namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

std::string Num(double v, int precision = 3) {
  std::ostringstream s;
  s.precision(precision);
  s << v;
  return s.str();
}

double Round4(double v) { return std::isfinite(v) ? std::round(v * 1e4) / 1e4 : v; }

void CheckGap(const MarkerArray& in, const Gap& gap, const char* who) {
  if (gap.marker < 0 || gap.marker >= in.markers() || gap.start < 0 || gap.length < 1 ||
      gap.start + gap.length > in.frames())
    throw InvalidInput(std::string(who) + ": gap (column " + std::to_string(gap.marker) + ", start " +
                       std::to_string(gap.start) + ", length " + std::to_string(gap.length) + ") lies outside the " +
                       std::to_string(in.frames()) + " × " + std::to_string(in.markers()) + " marker array");
}

Eigen::Vector3d Point(const MarkerArray& in, int64_t frame, int column) {
  const float* p = in.at(frame, column);
  return {p[0], p[1], p[2]};
}

// Coordinate-wise median (the mean of the two middle values for an even count).
double Median(std::vector<double>& v) {
  const size_t n = v.size(), mid = n / 2;
  std::nth_element(v.begin(), v.begin() + static_cast<std::ptrdiff_t>(mid), v.end());
  const double hi = v[mid];
  if (n % 2 == 1) return hi;
  const double lo = *std::max_element(v.begin(), v.begin() + static_cast<std::ptrdiff_t>(mid));
  return 0.5 * (lo + hi);
}

double Percentile(std::vector<double> v, double p) {
  if (v.empty()) return kNaN;
  std::sort(v.begin(), v.end());
  const double pos = p * static_cast<double>(v.size() - 1);
  const auto i = static_cast<size_t>(std::floor(pos));
  const size_t j = std::min(i + 1, v.size() - 1);
  return v[i] + (pos - static_cast<double>(i)) * (v[j] - v[i]);
}

// RMS distance of the points (columns of a 3 × k matrix) from their principal line, and the
// inertia tensor about their centroid.
struct Spread {
  Eigen::Vector3d centroid;
  Eigen::Matrix3d inertia;
  double off_line_mm;
};
Spread SpreadOf(const Eigen::Matrix3Xd& p) {
  Spread s;
  const auto k = static_cast<double>(p.cols());
  s.centroid = p.rowwise().mean();
  const Eigen::Matrix3Xd c = p.colwise() - s.centroid;
  const Eigen::Matrix3d scatter = c * c.transpose();
  s.inertia = scatter.trace() * Eigen::Matrix3d::Identity() - scatter;
  Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eig(s.inertia, Eigen::EigenvaluesOnly);
  s.off_line_mm = std::sqrt(std::max(0.0, eig.eigenvalues()[0]) / k);
  return s;
}

Eigen::Matrix3d Cross(const Eigen::Vector3d& q) {
  Eigen::Matrix3d m;
  m << 0, -q.z(), q.y(), q.z(), 0, -q.x(), -q.y(), q.x(), 0;
  return m;
}

std::string ColumnList(const std::vector<int>& columns) {
  std::string s;
  for (size_t i = 0; i < columns.size(); ++i) s += (i ? "," : "") + std::to_string(columns[i]);
  return s;
}

}  // namespace

bool ClusterReference::Has(int column) const {
  const int i = IndexOf(column);
  return i >= 0 && i < shape.cols() && problem.empty() && !std::isnan(shape(0, i));
}

namespace {
void CheckReference(const ClusterReference& ref) {
  if (ref.shape.cols() != static_cast<Eigen::Index>(ref.columns.size()))
    throw InvalidInput("rigid fill: the cluster reference has " + std::to_string(ref.shape.cols()) + " positions for " +
                       std::to_string(ref.columns.size()) + " columns");
}
}  // namespace

int ClusterReference::IndexOf(int column) const {
  auto it = std::find(columns.begin(), columns.end(), column);
  return it == columns.end() ? -1 : static_cast<int>(it - columns.begin());
}

ClusterReference EstimateClusterReference(const MarkerArray& in, const std::vector<int>& columns,
                                          const RigidFillOptions& o) {
  if (columns.size() < 3)
    throw InvalidInput("rigid cluster: needs at least 3 columns, got " + std::to_string(columns.size()));
  std::set<int> distinct;
  for (int c : columns) {
    if (c < 0 || c >= in.markers())
      throw InvalidInput("rigid cluster: column " + std::to_string(c) + " is not a column of the " +
                         std::to_string(in.markers()) + "-marker array");
    if (!distinct.insert(c).second) throw InvalidInput("rigid cluster: column " + std::to_string(c) + " given twice");
  }
  if (o.min_reference_frames < 1 || o.max_reference_frames < o.min_reference_frames || o.max_iterations < 1)
    throw InvalidInput(
        "rigid fill options: need 1 <= min_reference_frames <= max_reference_frames, max_iterations >= 1");

  ClusterReference ref;
  ref.columns = columns;
  const int n = static_cast<int>(columns.size());
  ref.shape = Eigen::Matrix3Xd::Constant(3, n, kNaN);

  // Frames where the most cluster markers are seen: all of them when there are enough such
  // frames, else one fewer, and so on down to 3.
  std::vector<int> count(static_cast<size_t>(in.frames()), 0);
  for (int64_t f = 0; f < in.frames(); ++f)
    for (int c : columns) count[static_cast<size_t>(f)] += in.Visible(f, c) ? 1 : 0;
  std::vector<int64_t> frames;
  int level = n;
  for (; level >= 3; --level) {
    frames.clear();
    for (int64_t f = 0; f < in.frames(); ++f)
      if (count[static_cast<size_t>(f)] >= level) frames.push_back(f);
    if (static_cast<int>(frames.size()) >= o.min_reference_frames) break;
  }
  if (level < 3) {
    ref.problem = "rigid cluster (columns " + ColumnList(columns) + "): fewer than " +
                  std::to_string(o.min_reference_frames) + " frames with 3 or more of its markers visible";
    return ref;
  }
  ref.min_visible_used = level;
  if (static_cast<int>(frames.size()) > o.max_reference_frames) {
    std::vector<int64_t> even;
    const auto total = static_cast<int64_t>(frames.size());
    for (int i = 0; i < o.max_reference_frames; ++i)
      even.push_back(frames[static_cast<size_t>(i * total / o.max_reference_frames)]);
    frames = std::move(even);
  }

  // Captured coordinates of the used frames (NaN where missing).
  const size_t nf = frames.size();
  std::vector<Eigen::Matrix3Xd> x(nf, Eigen::Matrix3Xd::Constant(3, n, kNaN));
  for (size_t i = 0; i < nf; ++i)
    for (int j = 0; j < n; ++j)
      if (in.Visible(frames[i], columns[static_cast<size_t>(j)]))
        x[i].col(j) = Point(in, frames[i], columns[static_cast<size_t>(j)]);

  // Initial consensus: the first used frame, centred.
  auto centre = [](Eigen::Matrix3Xd* s) {
    Eigen::Vector3d sum = Eigen::Vector3d::Zero();
    int k = 0;
    for (Eigen::Index j = 0; j < s->cols(); ++j)
      if (!std::isnan((*s)(0, j))) sum += s->col(j), ++k;
    if (k == 0) return;
    const Eigen::Vector3d c = sum / k;
    for (Eigen::Index j = 0; j < s->cols(); ++j)
      if (!std::isnan((*s)(0, j))) s->col(j) -= c;
  };
  Eigen::Matrix3Xd consensus = x[0];
  centre(&consensus);

  std::vector<double> residuals;
  for (int it = 0; it < o.max_iterations; ++it) {
    std::vector<std::vector<double>> aligned(static_cast<size_t>(3 * n));
    residuals.clear();
    int64_t used = 0;
    for (size_t i = 0; i < nf; ++i) {
      std::vector<int> common;
      for (int j = 0; j < n; ++j)
        if (!std::isnan(x[i](0, j)) && !std::isnan(consensus(0, j))) common.push_back(j);
      if (common.size() < 3) continue;
      Eigen::Matrix3Xd src(3, static_cast<Eigen::Index>(common.size())), dst(3, src.cols());
      for (size_t k = 0; k < common.size(); ++k) {
        src.col(static_cast<Eigen::Index>(k)) = x[i].col(common[k]);
        dst.col(static_cast<Eigen::Index>(k)) = consensus.col(common[k]);
      }
      if (SpreadOf(dst).off_line_mm < o.min_off_line_mm) continue;
      Eigen::Isometry3d t;
      t.matrix() = Eigen::umeyama(src, dst, false);
      residuals.push_back(std::sqrt((t * src - dst).colwise().squaredNorm().mean()));
      ++used;
      for (int j = 0; j < n; ++j) {
        if (std::isnan(x[i](0, j))) continue;
        const Eigen::Vector3d p = t * Eigen::Vector3d(x[i].col(j));
        for (int c = 0; c < 3; ++c) aligned[static_cast<size_t>(3 * j + c)].push_back(p[c]);
      }
    }
    Eigen::Matrix3Xd next = Eigen::Matrix3Xd::Constant(3, n, kNaN);
    for (int j = 0; j < n; ++j) {
      if (static_cast<int>(aligned[static_cast<size_t>(3 * j)].size()) < o.min_reference_frames) continue;
      for (int c = 0; c < 3; ++c) next(c, j) = Median(aligned[static_cast<size_t>(3 * j + c)]);
    }
    // Fix the gauge: the median of the aligned frames may come out slightly turned; align it
    // back onto the previous consensus (on the markers both know) before comparing.
    {
      std::vector<int> both;
      for (int j = 0; j < n; ++j)
        if (!std::isnan(next(0, j)) && !std::isnan(consensus(0, j))) both.push_back(j);
      if (both.size() >= 3) {
        Eigen::Matrix3Xd src(3, static_cast<Eigen::Index>(both.size())), dst(3, src.cols());
        for (size_t k = 0; k < both.size(); ++k) {
          src.col(static_cast<Eigen::Index>(k)) = next.col(both[k]);
          dst.col(static_cast<Eigen::Index>(k)) = consensus.col(both[k]);
        }
        Eigen::Isometry3d t;
        t.matrix() = Eigen::umeyama(src, dst, false);
        for (int j = 0; j < n; ++j)
          if (!std::isnan(next(0, j))) next.col(j) = t * Eigen::Vector3d(next.col(j));
      }
    }
    centre(&next);
    double change = 0.0;
    bool same_support = true;
    for (int j = 0; j < n; ++j) {
      if (std::isnan(next(0, j)) != std::isnan(consensus(0, j))) same_support = false;
      if (!std::isnan(next(0, j)) && !std::isnan(consensus(0, j)))
        change = std::max(change, (next.col(j) - consensus.col(j)).norm());
    }
    consensus = next;
    ref.frames_used = used;
    ref.iterations = it + 1;
    if (same_support && change < o.tolerance_mm) break;
  }
  int known = 0;
  for (int j = 0; j < n; ++j) known += std::isnan(consensus(0, j)) ? 0 : 1;
  ref.shape = consensus;
  if (known < 3) {
    ref.problem = "rigid cluster (columns " + ColumnList(columns) + "): fewer than 3 markers seen together in " +
                  std::to_string(o.min_reference_frames) + " frames";
    return ref;
  }
  ref.median_residual_mm = Percentile(residuals, 0.5);
  ref.p95_residual_mm = Percentile(residuals, 0.95);
  return ref;
}

RigidFrameFit FitClusterFrame(const MarkerArray& in, const ClusterReference& ref, int64_t frame, int exclude,
                              const RigidFillOptions& o) {
  CheckReference(ref);
  if (frame < 0 || frame >= in.frames())
    throw InvalidInput("rigid fill: frame " + std::to_string(frame) + " is outside the " + std::to_string(in.frames()) +
                       "-frame marker array");
  RigidFrameFit fit;
  const std::string at = "frame " + std::to_string(frame) + ": ";
  if (!ref.problem.empty()) {
    fit.why_not = ref.problem;
    return fit;
  }
  std::vector<int> idx;
  for (size_t j = 0; j < ref.columns.size(); ++j) {
    const int c = ref.columns[j];
    if (c != exclude && !std::isnan(ref.shape(0, static_cast<Eigen::Index>(j))) && in.Visible(frame, c))
      idx.push_back(static_cast<int>(j));
  }
  fit.visible = static_cast<int>(idx.size());
  const int need = std::max(3, o.min_visible);
  if (fit.visible < need) {
    fit.why_not = at + std::to_string(fit.visible) + " visible cluster neighbour" + (fit.visible == 1 ? "" : "s") +
                  ", " + std::to_string(need) + " needed";
    return fit;
  }
  Eigen::Matrix3Xd p(3, fit.visible), y(3, fit.visible);
  for (int k = 0; k < fit.visible; ++k) {
    p.col(k) = ref.shape.col(idx[static_cast<size_t>(k)]);
    y.col(k) = Point(in, frame, ref.columns[static_cast<size_t>(idx[static_cast<size_t>(k)])]);
  }
  const Spread s = SpreadOf(p);
  fit.off_line_mm = s.off_line_mm;
  if (s.off_line_mm < o.min_off_line_mm) {
    fit.why_not = at + "the " + std::to_string(fit.visible) + " visible cluster neighbours are collinear (" +
                  Num(s.off_line_mm) + " mm RMS off their line, " + Num(o.min_off_line_mm) + " mm needed)";
    return fit;
  }
  const int ei = exclude >= 0 ? ref.IndexOf(exclude) : -1;
  if (ei >= 0 && !std::isnan(ref.shape(0, ei))) {
    const Eigen::Vector3d q = ref.shape.col(ei) - s.centroid;
    const Eigen::Matrix3d qx = Cross(q);
    const Eigen::Matrix3d cov = Eigen::Matrix3d::Identity() / fit.visible + qx * s.inertia.inverse() * qx.transpose();
    fit.error_gain = std::sqrt(std::max(0.0, cov.trace() / 3.0));
    if (!(fit.error_gain <= o.max_error_gain)) {
      fit.why_not = at + "ill-conditioned fit from " + std::to_string(fit.visible) + " neighbours (noise gain " +
                    Num(fit.error_gain) + " at the filled marker, at most " + Num(o.max_error_gain) + ")";
      return fit;
    }
  }
  fit.pose.matrix() = Eigen::umeyama(p, y, false);
  fit.rms_residual_mm = std::sqrt((fit.pose * p - y).colwise().squaredNorm().mean());
  fit.ok = true;
  return fit;
}

std::vector<double> ClusterResiduals(const MarkerArray& in, const ClusterReference& ref, const RigidFillOptions& o) {
  std::vector<double> out(static_cast<size_t>(in.frames()), kNaN);
  RigidFillOptions any = o;
  any.min_visible = 3;
  for (int64_t f = 0; f < in.frames(); ++f) {
    RigidFrameFit fit = FitClusterFrame(in, ref, f, -1, any);
    if (fit.ok) out[static_cast<size_t>(f)] = fit.rms_residual_mm;
  }
  return out;
}

RigidGapFit FitRigidGap(const MarkerArray& in, const ClusterReference& ref, const Gap& gap, const RigidFillOptions& o) {
  CheckGap(in, gap, "rigid fill");
  CheckReference(ref);
  RigidGapFit g;
  if (!ref.problem.empty()) {
    g.why_not = ref.problem;
    return g;
  }
  const int ei = ref.IndexOf(gap.marker);
  if (ei < 0) {
    g.why_not = "column " + std::to_string(gap.marker) + " is not in the rigid cluster (columns " +
                ColumnList(ref.columns) + ")";
    return g;
  }
  if (std::isnan(ref.shape(0, ei))) {
    g.why_not = "column " + std::to_string(gap.marker) + " was seen with its cluster in fewer than " +
                std::to_string(o.min_reference_frames) + " frames: no reference position";
    return g;
  }
  g.min_visible = static_cast<int>(ref.columns.size());
  for (int64_t f = gap.start; f < gap.start + gap.length; ++f) {
    RigidFrameFit fit = FitClusterFrame(in, ref, f, gap.marker, o);
    if (!fit.ok) {
      g.why_not = fit.why_not;
      g.positions.clear();
      return g;
    }
    if (!(fit.rms_residual_mm <= o.max_residual_mm)) {
      g.why_not = "frame " + std::to_string(f) + ": the cluster is not rigid (fit residual " +
                  Num(fit.rms_residual_mm) + " mm RMS over " + std::to_string(fit.visible) + " neighbours, at most " +
                  Num(o.max_residual_mm) + " mm)";
      g.positions.clear();
      return g;
    }
    g.positions.push_back(fit.pose * Eigen::Vector3d(ref.shape.col(ei)));
    g.residual_mm.push_back(fit.rms_residual_mm);
    g.min_visible = std::min(g.min_visible, fit.visible);
    g.max_residual_mm = std::max(g.max_residual_mm, fit.rms_residual_mm);
    g.max_error_gain = std::max(g.max_error_gain, fit.error_gain);
  }
  return g;
}

namespace {
void WriteGap(const Gap& gap, const std::vector<Eigen::Vector3d>& positions, MarkerArray* out) {
  for (int64_t i = 0; i < gap.length; ++i) {
    float* p = out->at(gap.start + i, gap.marker);
    for (int c = 0; c < 3; ++c) p[c] = static_cast<float>(positions[static_cast<size_t>(i)][c]);
  }
}
void CheckOut(const MarkerArray& in, const MarkerArray* out) {
  if (out == nullptr || out->frames() != in.frames() || out->markers() != in.markers())
    throw InvalidInput("rigid fill: the output marker array must have the input's shape");
}
}  // namespace

std::string RigidFillGap(const MarkerArray& in, const ClusterReference& ref, const Gap& gap, MarkerArray* out,
                         const RigidFillOptions& o, RigidGapFit* fit) {
  CheckOut(in, out);
  RigidGapFit g = FitRigidGap(in, ref, gap, o);
  if (g.why_not.empty()) WriteGap(gap, g.positions, out);
  std::string why = g.why_not;
  if (fit != nullptr) *fit = std::move(g);
  return why;
}

RigidClusterFiller::RigidClusterFiller(std::vector<ClusterReference> clusters, RigidFillOptions options)
    : clusters_(std::move(clusters)), options_(options) {}

RigidClusterFiller RigidClusterFiller::FromMarkers(const MarkerArray& in, const std::vector<std::vector<int>>& clusters,
                                                   const RigidFillOptions& options) {
  std::vector<ClusterReference> refs;
  for (const auto& c : clusters) refs.push_back(EstimateClusterReference(in, c, options));
  return RigidClusterFiller(std::move(refs), options);
}

int RigidClusterFiller::Choose(const MarkerArray& in, const Gap& gap, RigidGapFit* fit, std::string* why_not) const {
  CheckGap(in, gap, "rigid fill");
  std::string reasons;
  for (size_t i = 0; i < clusters_.size(); ++i) {
    if (clusters_[i].IndexOf(gap.marker) < 0) continue;
    RigidGapFit g = FitRigidGap(in, clusters_[i], gap, options_);
    if (g.why_not.empty()) {
      if (fit != nullptr) *fit = std::move(g);
      return static_cast<int>(i);
    }
    reasons += (reasons.empty() ? "" : "; ") + std::string("cluster ") + std::to_string(i) + ": " + g.why_not;
  }
  if (why_not != nullptr)
    *why_not = reasons.empty() ? "column " + std::to_string(gap.marker) + " is in no rigid cluster" : reasons;
  return -1;
}

bool RigidClusterFiller::CanFill(const MarkerArray& in, const Gap& gap, std::string* why_not) const {
  return Choose(in, gap, nullptr, why_not) >= 0;
}

bool RigidClusterFiller::Fill(const MarkerArray& in, const Gap& gap, MarkerArray* out, FillRecord* record) const {
  CheckOut(in, out);
  RigidGapFit g;
  std::string why;
  const int i = Choose(in, gap, &g, &why);
  if (i < 0) return false;
  WriteGap(gap, g.positions, out);
  if (record != nullptr) {
    const ClusterReference& ref = clusters_[static_cast<size_t>(i)];
    nlohmann::json p;
    p["cluster"] = ref.columns;
    p["reference"] = {{"method", "GPA, coordinate-wise median"},
                      {"frames", ref.frames_used},
                      {"min_visible", ref.min_visible_used},
                      {"median_residual_mm", Round4(ref.median_residual_mm)}};
    p["min_visible"] = g.min_visible;
    p["max_residual_mm"] = Round4(g.max_residual_mm);
    p["max_error_gain"] = Round4(g.max_error_gain);
    p["limits"] = {{"min_visible", std::max(3, options_.min_visible)},
                   {"max_residual_mm", options_.max_residual_mm},
                   {"max_error_gain", options_.max_error_gain}};
    record->marker = gap.marker;
    record->start = gap.start;
    record->length = gap.length;
    record->method = name();
    record->parameters = p.dump();
  }
  return true;
}

}  // namespace csw::cleaning
