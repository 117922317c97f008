#include "analysis/cleaning/pattern_fill.h"

#include <Eigen/Core>
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

void CheckGap(const MarkerArray& in, const Gap& gap) {
  if (gap.marker < 0 || gap.marker >= in.markers() || gap.start < 0 || gap.length < 1 ||
      gap.start + gap.length > in.frames())
    throw InvalidInput("pattern fill: gap (column " + std::to_string(gap.marker) + ", start " +
                       std::to_string(gap.start) + ", length " + std::to_string(gap.length) + ") lies outside the " +
                       std::to_string(in.frames()) + " × " + std::to_string(in.markers()) + " marker array");
}

void CheckColumn(const MarkerArray& in, int column, const char* what) {
  if (column < 0 || column >= in.markers())
    throw InvalidInput(std::string("pattern fill: ") + what + " column " + std::to_string(column) +
                       " is not a column of the " + std::to_string(in.markers()) + "-marker array");
}

void CheckOptions(const PatternFillOptions& o) {
  if (o.window < 1 || o.velocity_lag < 1 || o.min_samples < 2 || o.offset_frames < 1)
    throw InvalidInput("pattern fill options: window, velocity_lag and offset_frames must be >= 1, min_samples >= 2");
}

Eigen::Vector3d Point(const MarkerArray& in, int64_t frame, int column) {
  const float* p = in.at(frame, column);
  return {p[0], p[1], p[2]};
}

// Offset m − d averaged over up to k frames next to one end of the gap where both are visible,
// and the mean frame of those (the anchor). The frame adjacent to the gap must be among them.
struct Anchor {
  bool ok = false;
  double frame = 0.0;
  Eigen::Vector3d offset = Eigen::Vector3d::Zero();
  int frames = 0;
};
Anchor AnchorAt(const MarkerArray& in, int m, int d, int64_t adjacent, int64_t step, int k) {
  Anchor a;
  if (!in.Visible(adjacent, m) || !in.Visible(adjacent, d)) return a;
  for (int i = 0; i < k; ++i) {
    const int64_t f = adjacent + step * i;
    if (f < 0 || f >= in.frames()) break;
    if (!in.Visible(f, m) || !in.Visible(f, d)) continue;
    a.offset += Point(in, f, m) - Point(in, f, d);
    a.frame += static_cast<double>(f);
    ++a.frames;
  }
  a.offset /= a.frames;
  a.frame /= a.frames;
  a.ok = true;
  return a;
}

struct Plan {
  std::string why_not;
  Anchor before, after;
};
Plan MakePlan(const MarkerArray& in, const Gap& gap, int donor, const PatternFillOptions& o) {
  CheckGap(in, gap);
  CheckColumn(in, donor, "donor");
  Plan p;
  const std::string d = "donor column " + std::to_string(donor);
  if (donor == gap.marker) {
    p.why_not = d + " is the gap's own marker";
    return p;
  }
  const int64_t end = gap.start + gap.length;
  if (gap.start == 0 || end == in.frames()) {
    p.why_not = std::string("the gap touches the ") + (gap.start == 0 ? "start" : "end") +
                " of the take: no frame on both sides to join";
    return p;
  }
  for (int64_t f = gap.start; f < end; ++f)
    if (!in.Visible(f, donor)) {
      p.why_not = d + " is missing at frame " + std::to_string(f) + " of the gap";
      return p;
    }
  p.before = AnchorAt(in, gap.marker, donor, gap.start - 1, -1, o.offset_frames);
  p.after = AnchorAt(in, gap.marker, donor, end, +1, o.offset_frames);
  if (!p.before.ok || !p.after.ok) {
    const int64_t f = p.before.ok ? end : gap.start - 1;
    p.why_not = (in.Visible(f, gap.marker) ? d : "column " + std::to_string(gap.marker)) + " is missing at frame " +
                std::to_string(f) + ", next to the gap";
  }
  return p;
}

DonorScore Score(const MarkerArray& in, const Gap& gap, int donor, const PatternFillOptions& o) {
  DonorScore s;
  s.donor = donor;
  s.correlation = kNaN;
  s.why_not = MakePlan(in, gap, donor, o).why_not;
  if (!s.why_not.empty()) return s;
  const int m = gap.marker;
  const int64_t end = gap.start + gap.length;
  std::vector<Eigen::Vector3d> vm, vd;
  auto side = [&](int64_t first, int64_t last) {  // inclusive, clipped to the take
    first = std::max<int64_t>(first, 0);
    last = std::min<int64_t>(last, in.frames() - 1);
    for (int64_t f = first + o.velocity_lag; f <= last; ++f) {
      const int64_t g = f - o.velocity_lag;
      if (!in.Visible(f, m) || !in.Visible(g, m) || !in.Visible(f, donor) || !in.Visible(g, donor)) continue;
      vm.push_back(Point(in, f, m) - Point(in, g, m));
      vd.push_back(Point(in, f, donor) - Point(in, g, donor));
    }
  };
  side(gap.start - o.window, gap.start - 1);
  side(end, end + o.window - 1);
  s.samples = static_cast<int64_t>(vm.size());
  if (s.samples < o.min_samples) {
    s.why_not = "donor column " + std::to_string(donor) + ": " + std::to_string(s.samples) +
                " velocity samples around the gap, " + std::to_string(o.min_samples) + " needed";
    return s;
  }
  Eigen::Vector3d mm = Eigen::Vector3d::Zero(), md = Eigen::Vector3d::Zero();
  for (size_t i = 0; i < vm.size(); ++i) mm += vm[i], md += vd[i];
  mm /= static_cast<double>(vm.size());
  md /= static_cast<double>(vd.size());
  double sab = 0, saa = 0, sbb = 0;
  for (size_t i = 0; i < vm.size(); ++i) {
    const Eigen::Vector3d a = vm[i] - mm, b = vd[i] - md;
    sab += a.dot(b);
    saa += a.squaredNorm();
    sbb += b.squaredNorm();
  }
  if (!(saa > 0 && sbb > 0)) {
    s.why_not = "donor column " + std::to_string(donor) + ": no motion around the gap to correlate";
    return s;
  }
  s.correlation = sab / std::sqrt(saa * sbb);
  return s;
}

}  // namespace

std::vector<DonorScore> ScoreDonors(const MarkerArray& in, const Gap& gap, const std::vector<int>& candidates,
                                    const PatternFillOptions& o) {
  CheckOptions(o);
  CheckGap(in, gap);
  std::vector<DonorScore> out;
  std::set<int> seen;
  for (int c : candidates) {
    CheckColumn(in, c, "candidate");
    if (c == gap.marker || !seen.insert(c).second) continue;
    out.push_back(Score(in, gap, c, o));
  }
  std::stable_sort(out.begin(), out.end(), [](const DonorScore& a, const DonorScore& b) {
    if (a.why_not.empty() != b.why_not.empty()) return a.why_not.empty();
    return a.why_not.empty() && a.correlation > b.correlation;
  });
  return out;
}

std::string PatternFillCheck(const MarkerArray& in, const Gap& gap, int donor, const PatternFillOptions& o) {
  CheckOptions(o);
  return MakePlan(in, gap, donor, o).why_not;
}

std::string PatternFillGap(const MarkerArray& in, const Gap& gap, int donor, MarkerArray* out,
                           const PatternFillOptions& o) {
  CheckOptions(o);
  if (out == nullptr || out->frames() != in.frames() || out->markers() != in.markers())
    throw InvalidInput("pattern fill: the output marker array must have the input's shape");
  Plan p = MakePlan(in, gap, donor, o);
  if (!p.why_not.empty()) return p.why_not;
  const double span = p.after.frame - p.before.frame;
  for (int64_t f = gap.start; f < gap.start + gap.length; ++f) {
    const double a = (static_cast<double>(f) - p.before.frame) / span;
    const Eigen::Vector3d x = Point(in, f, donor) + (1.0 - a) * p.before.offset + a * p.after.offset;
    float* dst = out->at(f, gap.marker);
    for (int c = 0; c < 3; ++c) dst[c] = static_cast<float>(x[c]);
  }
  return "";
}

PatternFiller::PatternFiller(std::vector<std::vector<int>> candidate_groups, PatternFillOptions options,
                             std::map<int, int> named_donors)
    : groups_(std::move(candidate_groups)), options_(options), named_(std::move(named_donors)) {
  CheckOptions(options_);
}

std::vector<int> PatternFiller::Candidates(int marker) const {
  std::vector<int> out;
  for (const auto& g : groups_) {
    if (std::find(g.begin(), g.end(), marker) == g.end()) continue;
    for (int c : g)
      if (c != marker && std::find(out.begin(), out.end(), c) == out.end()) out.push_back(c);
  }
  return out;
}

int PatternFiller::ChooseDonor(const MarkerArray& in, const Gap& gap, DonorScore* score, std::string* why_not) const {
  CheckGap(in, gap);
  auto named = named_.find(gap.marker);
  if (named != named_.end()) {
    CheckColumn(in, named->second, "donor");
    DonorScore s = Score(in, gap, named->second, options_);
    const std::string plan = MakePlan(in, gap, named->second, options_).why_not;
    if (!plan.empty()) {
      if (why_not != nullptr) *why_not = "named " + plan;
      return -1;
    }
    s.why_not.clear();  // a named donor is used even when there is too little motion to score it
    if (score != nullptr) *score = s;
    return named->second;
  }
  const std::vector<int> candidates = Candidates(gap.marker);
  if (candidates.empty()) {
    if (why_not != nullptr) *why_not = "column " + std::to_string(gap.marker) + " has no donor candidates";
    return -1;
  }
  std::vector<DonorScore> scores = ScoreDonors(in, gap, candidates, options_);
  if (!scores.front().why_not.empty()) {
    if (why_not != nullptr) {
      std::string s = "no usable donor among " + std::to_string(candidates.size()) + " candidates";
      for (size_t i = 0; i < std::min<size_t>(scores.size(), 3); ++i) s += "; " + scores[i].why_not;
      *why_not = s;
    }
    return -1;
  }
  if (!(scores.front().correlation >= options_.min_correlation)) {
    if (why_not != nullptr)
      *why_not = "best donor column " + std::to_string(scores.front().donor) + " correlates at " +
                 Num(scores.front().correlation) + ", below " + Num(options_.min_correlation);
    return -1;
  }
  if (score != nullptr) *score = scores.front();
  return scores.front().donor;
}

bool PatternFiller::CanFill(const MarkerArray& in, const Gap& gap, std::string* why_not) const {
  return ChooseDonor(in, gap, nullptr, why_not) >= 0;
}

bool PatternFiller::Fill(const MarkerArray& in, const Gap& gap, MarkerArray* out, FillRecord* record) const {
  DonorScore s;
  std::string why;
  const int donor = ChooseDonor(in, gap, &s, &why);
  if (donor < 0) return false;
  if (!PatternFillGap(in, gap, donor, out, options_).empty()) return false;
  if (record != nullptr) {
    const Plan p = MakePlan(in, gap, donor, options_);
    nlohmann::json j;
    j["donor"] = donor;
    j["choice"] = named_.count(gap.marker) ? "named" : "auto";
    j["correlation"] = Round4(s.correlation);
    j["samples"] = s.samples;
    if (!named_.count(gap.marker)) j["candidates"] = Candidates(gap.marker);
    j["offset_frames"] = options_.offset_frames;
    j["offset_before_mm"] = {Round4(p.before.offset.x()), Round4(p.before.offset.y()), Round4(p.before.offset.z())};
    j["offset_after_mm"] = {Round4(p.after.offset.x()), Round4(p.after.offset.y()), Round4(p.after.offset.z())};
    j["window"] = options_.window;
    j["velocity_lag"] = options_.velocity_lag;
    record->marker = gap.marker;
    record->start = gap.start;
    record->length = gap.length;
    record->method = name();
    record->parameters = j.dump();
  }
  return true;
}

}  // namespace csw::cleaning
