#include "analysis/signing/segmentation.h"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <iomanip>
#include <limits>
#include <sstream>

#include "analysis/cleaning/filter.h"
#include "core/error.h"

namespace csw::signing {

namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

std::string Lower(const std::string& s) {
  std::string out = s;
  for (char& c : out) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return out;
}

// The name without a namespace prefix ("mixamorig:RightHand" -> "RightHand").
std::string BaseName(const std::string& name) {
  const size_t colon = name.rfind(':');
  return colon == std::string::npos ? name : name.substr(colon + 1);
}

bool IsSeparator(char c) { return c == '_' || c == '.' || c == '-' || c == ':' || c == ' '; }

// The base name in lower case without its side word or side letter and
// without separators: "RightHand" -> "hand", "l_wrist" -> "wrist".
std::string Stem(const std::string& name) {
  std::string base = BaseName(name);
  std::string low = Lower(base);
  for (const char* word : {"right", "left"}) {
    const size_t p = low.find(word);
    if (p != std::string::npos) {
      low.erase(p, std::string(word).size());
      break;
    }
  }
  if (low.size() == base.size() && base.size() >= 2) {  // no side word: a side letter?
    const char c0 = static_cast<char>(std::tolower(static_cast<unsigned char>(base[0])));
    if ((c0 == 'r' || c0 == 'l') && (IsSeparator(base[1]) || std::isupper(static_cast<unsigned char>(base[1]))))
      low.erase(0, 1);
    else if (low.size() >= 2 && (low[low.size() - 1] == 'r' || low[low.size() - 1] == 'l') &&
             IsSeparator(low[low.size() - 2]))
      low.erase(low.size() - 1);
  }
  std::string out;
  for (char c : low)
    if (!IsSeparator(c)) out += c;
  return out;
}

std::string Seconds(double t) {
  std::ostringstream o;
  o << std::fixed << std::setprecision(3) << t << " s";
  return o.str();
}

}  // namespace

char NameSide(const std::string& name) {
  const std::string base = BaseName(name);
  const std::string low = Lower(base);
  if (low.find("right") != std::string::npos) return 'R';
  if (low.find("left") != std::string::npos) return 'L';
  if (base.size() >= 2) {
    const char c0 = low[0];
    if ((c0 == 'r' || c0 == 'l') && (IsSeparator(base[1]) || std::isupper(static_cast<unsigned char>(base[1]))))
      return c0 == 'r' ? 'R' : 'L';
    const char cn = low.back();
    if ((cn == 'r' || cn == 'l') && (low[low.size() - 2] == '_' || low[low.size() - 2] == '.'))
      return cn == 'r' ? 'R' : 'L';
  }
  return 0;
}

WristJoints FindWrists(const std::vector<std::string>& names, const std::string& right, const std::string& left,
                       bool find_right, bool find_left) {
  WristJoints w;
  auto list = [&]() {
    std::string s;
    for (size_t i = 0; i < names.size() && i < 60; ++i) s += (i ? ", " : "") + names[i];
    if (names.size() > 60) s += ", ...";
    return s.empty() ? std::string("none") : s;
  };
  for (int side = 0; side < 2; ++side) {
    if (side == 0 ? !find_right : !find_left) continue;
    const char want = side == 0 ? 'R' : 'L';
    const std::string& given = side == 0 ? right : left;
    int64_t& index = side == 0 ? w.right : w.left;
    std::string& name = side == 0 ? w.right_name : w.left_name;
    std::string& rule = side == 0 ? w.right_rule : w.left_rule;
    if (!given.empty()) {
      for (size_t i = 0; i < names.size(); ++i)
        if (names[i] == given) index = static_cast<int64_t>(i);
      if (index < 0)
        throw InvalidInput(std::string(side == 0 ? "right" : "left") + " wrist '" + given +
                           "' is not a marker of the take (markers: " + list() + ")");
      name = given;
      rule = "given";
      continue;
    }
    for (const char* r : {"wrist", "hand"}) {
      for (size_t i = 0; i < names.size(); ++i) {
        if (NameSide(names[i]) != want) continue;
        const std::string stem = Stem(names[i]);
        const bool match = std::string(r) == "wrist"
                               ? stem.find("wrist") != std::string::npos
                               : stem.size() >= 4 && stem.compare(stem.size() - 4, 4, "hand") == 0;
        if (match && (index < 0 || names[i].size() < name.size())) {
          index = static_cast<int64_t>(i);
          name = names[i];
          rule = r;
        }
      }
      if (index >= 0) break;
    }
    if (index < 0)
      throw InvalidInput(std::string("no ") + (side == 0 ? "right" : "left") +
                         " wrist among the markers (a name with 'wrist' or ending in 'hand' and a side: "
                         "Right/Left, R/L prefix or _r/_l suffix; name it explicitly otherwise): " +
                         list());
  }
  return w;
}

std::string SpeedOptions::Check(double rate_hz) const {
  if (!(cutoff_hz >= 0.0 && std::isfinite(cutoff_hz))) return "the cut-off must be >= 0 Hz (0 = no filter)";
  if (cutoff_hz > 0.0 && !(cutoff_hz < 0.5 * rate_hz))
    return "the cut-off must be below half the frame rate (" + std::to_string(0.5 * rate_hz) + " Hz)";
  if (order < 2 || order > 8 || order % 2 != 0) return "the filter order must be 2, 4, 6 or 8";
  return "";
}

std::string RefineOptions::Check() const {
  if (!(threshold_s > 0.0 && threshold_s <= 5.0)) return "the threshold must be in (0, 5] s";
  return "";
}

std::string SegmentationOptions::Check(double rate_hz) const {
  if (!right && !left) return "no hand to refine";
  if (std::string why = speed.Check(rate_hz); !why.empty()) return why;
  if (std::string why = rest.Check(); !why.empty()) return why;
  if (std::string why = refine.Check(); !why.empty()) return why;
  return "";
}

Eigen::VectorXd WristSpeed(const MarkerArray& markers, int64_t marker, double rate_hz, const SpeedOptions& options) {
  if (std::string why = options.Check(rate_hz); !why.empty()) throw InvalidInput("wrist speed: " + why);
  if (marker < 0 || marker >= markers.markers()) throw InvalidInput("wrist speed: no marker " + std::to_string(marker));
  const int64_t n = markers.frames();
  MarkerArray one(n, 1);
  for (int64_t f = 0; f < n; ++f) std::copy(markers.at(f, marker), markers.at(f, marker) + 3, one.at(f, 0));
  if (options.cutoff_hz > 0.0) {
    cleaning::ButterworthOptions b;
    b.cutoff_hz = options.cutoff_hz;
    b.order = options.order;
    cleaning::ButterworthFilterInPlace(one, rate_hz, b);
  }
  return cleaning::MarkerKinematics(one, rate_hz).speed.col(0);
}

std::vector<int64_t> LocalMinima(const Eigen::VectorXd& s) {
  std::vector<int64_t> out;
  const Eigen::Index n = s.size();
  Eigen::Index i = 0;
  while (i < n) {
    if (!std::isfinite(s[i])) {
      ++i;
      continue;
    }
    Eigen::Index j = i + 1;  // the run of equal values [i, j)
    while (j < n && std::isfinite(s[j]) && s[j] == s[i]) ++j;
    const bool left_finite = i > 0 && std::isfinite(s[i - 1]), right_finite = j < n && std::isfinite(s[j]);
    const bool left_higher = left_finite && s[i - 1] > s[i], right_higher = right_finite && s[j] > s[i];
    const bool plateau = j - i >= 2;
    // A bottom: higher on both sides; a plateau (a still hand, e.g. below
    // rest_speed_mm_s) also where a take or a gap bounds it on one side.
    if ((left_higher && right_higher) ||
        (plateau && ((left_higher && !right_finite) || (!left_finite && right_higher)))) {
      out.push_back(i);
      if (plateau) out.push_back(j - 1);
    }
    i = j;
  }
  return out;
}

std::string RestOptions::Check() const {
  if (!(rest_speed_mm_s >= 0.0 && rest_speed_mm_s <= 1000.0)) return "the rest speed must be in [0, 1000] mm/s";
  if (!(min_rest_s > 0.0 && min_rest_s <= 10.0)) return "the shortest rest must be in (0, 10] s";
  return "";
}

std::vector<int64_t> SpeedMinima(const Eigen::VectorXd& speed, double rate_hz, const RestOptions& options) {
  if (std::string why = options.Check(); !why.empty()) throw InvalidInput("speed minima: " + why);
  std::vector<int64_t> minima = LocalMinima(speed);
  if (options.rest_speed_mm_s <= 0.0) return minima;
  const auto min_frames = static_cast<Eigen::Index>(std::ceil(options.min_rest_s * rate_hz - 1e-9));
  std::vector<std::pair<int64_t, int64_t>> rests;  // [first, last]
  const Eigen::Index n = speed.size();
  for (Eigen::Index i = 0; i < n;) {
    if (!(std::isfinite(speed[i]) && speed[i] < options.rest_speed_mm_s)) {
      ++i;
      continue;
    }
    Eigen::Index j = i;
    while (j < n && std::isfinite(speed[j]) && speed[j] < options.rest_speed_mm_s) ++j;
    if (j - i >= min_frames) rests.emplace_back(i, j - 1);
    i = j;
  }
  std::vector<int64_t> out;
  for (int64_t m : minima) {
    bool inside = false;
    for (const auto& [a, b] : rests) inside = inside || (m >= a && m <= b);
    if (!inside) out.push_back(m);
  }
  for (const auto& [a, b] : rests) {
    // A rest that starts or ends the valid samples has no arrival / departure there.
    if (a > 0 && std::isfinite(speed[a - 1])) out.push_back(a);
    if (b + 1 < n && std::isfinite(speed[b + 1])) out.push_back(b);
  }
  std::sort(out.begin(), out.end());
  out.erase(std::unique(out.begin(), out.end()), out.end());
  return out;
}

std::vector<double> TierBoundaries(const LabelTier& tier) {
  if (tier.kind != LabelTier::Kind::kInterval)
    throw InvalidInput("tier '" + tier.name + "' is a point tier: segmentation needs an interval tier");
  std::vector<double> b;
  constexpr double kEps = 1e-9;
  const auto& l = tier.labels;
  for (size_t i = 0; i < l.size(); ++i) {
    const bool touches_previous = i > 0 && std::abs(l[i - 1].end_s - l[i].start_s) < kEps;
    if (!touches_previous && l[i].start_s > tier.start_s + kEps) b.push_back(l[i].start_s);
    if (l[i].end_s < tier.end_s - kEps) b.push_back(l[i].end_s);
  }
  std::sort(b.begin(), b.end());
  b.erase(std::unique(b.begin(), b.end(), [](double x, double y) { return std::abs(x - y) < 1e-9; }), b.end());
  return b;
}

std::vector<BoundaryRefinement> RefineBoundaries(const std::vector<double>& boundaries,
                                                 const std::vector<int64_t>& minima, double rate_hz,
                                                 const RefineOptions& options) {
  if (std::string why = options.Check(); !why.empty()) throw InvalidInput("refinement: " + why);
  if (!(rate_hz > 0)) throw InvalidInput("refinement: no frame rate");
  std::vector<BoundaryRefinement> out(boundaries.size());
  const double eps = 1e-6 / rate_hz;
  for (size_t i = 0; i < boundaries.size(); ++i) {
    BoundaryRefinement& r = out[i];
    r.manual_s = r.refined_s = boundaries[i];
    double best = kNaN;
    for (int64_t m : minima) {
      const double t = static_cast<double>(m) / rate_hz;
      const double d = std::abs(t - boundaries[i]);
      if (d <= options.threshold_s + eps && !(d >= best)) {
        best = d;
        r.frame = m;
      }
    }
    if (r.frame >= 0) {
      r.refined_s = static_cast<double>(r.frame) / rate_hz;
      r.moved = true;
    } else {
      r.why = "no minimum within " + Seconds(options.threshold_s);
    }
  }
  // Collisions: two boundaries on one minimum, or out of order after moving.
  for (bool changed = true; changed;) {
    changed = false;
    for (size_t i = 1; i < out.size(); ++i) {
      if (out[i].refined_s > out[i - 1].refined_s + eps) continue;
      // The one farther from its minimum keeps its manual time (a kept one never yields).
      const double di = out[i].moved ? std::abs(out[i].refined_s - out[i].manual_s) : -1.0;
      const double dp = out[i - 1].moved ? std::abs(out[i - 1].refined_s - out[i - 1].manual_s) : -1.0;
      if (di < 0 && dp < 0) continue;  // the manual tags themselves are out of order
      const size_t keep = di >= dp ? i : i - 1;
      const size_t other = keep == i ? i - 1 : i;
      out[keep].why = "its minimum at " + Seconds(out[keep].refined_s) + " is nearer to the boundary at " +
                      Seconds(out[other].manual_s);
      out[keep].refined_s = out[keep].manual_s;
      out[keep].frame = -1;
      out[keep].moved = false;
      changed = true;
    }
  }
  return out;
}

LabelTier ApplyRefinement(const LabelTier& tier, const std::vector<BoundaryRefinement>& boundaries,
                          const std::string& name) {
  LabelTier out = tier;
  out.name = name;
  auto map = [&](double t) {
    for (const BoundaryRefinement& b : boundaries)
      if (std::abs(b.manual_s - t) < 1e-9) return b.refined_s;
    return t;
  };
  for (Label& l : out.labels) {
    l.start_s = map(l.start_s);
    l.end_s = map(l.end_s);
  }
  return out;
}

int HandSegmentation::moved() const {
  int n = 0;
  for (const BoundaryRefinement& b : boundaries) n += b.moved ? 1 : 0;
  return n;
}

std::vector<HandSegmentation> RefineSegmentation(const Take& take, const LabelTier& manual,
                                                 const SegmentationOptions& options) {
  const std::string where = "take '" + take.name + "'";
  if (!(take.rate_hz > 0)) throw InvalidInput(where + ": no frame rate");
  if (std::string why = options.Check(take.rate_hz); !why.empty()) throw InvalidInput(where + ": " + why);
  if (manual.kind != LabelTier::Kind::kInterval)
    throw InvalidInput(where + ": tier '" + manual.name + "' is a point tier: segmentation needs an interval tier");
  // Only the wrists asked for (a one-armed skeleton still refines its hand).
  WristJoints w;
  try {
    w = FindWrists(take.marker_names, options.right_wrist, options.left_wrist, options.right, options.left);
  } catch (const InvalidInput& e) {
    throw InvalidInput(where + ": " + e.what());
  }
  const std::vector<double> tags = TierBoundaries(manual);
  std::vector<HandSegmentation> out;
  for (int side = 0; side < 2; ++side) {
    if (side == 0 ? !options.right : !options.left) continue;
    HandSegmentation h;
    h.hand = side == 0 ? 'R' : 'L';
    h.marker = side == 0 ? w.right : w.left;
    h.marker_name = side == 0 ? w.right_name : w.left_name;
    h.speed = WristSpeed(take.markers, h.marker, take.rate_hz, options.speed);
    h.minima = SpeedMinima(h.speed, take.rate_hz, options.rest);
    h.boundaries = RefineBoundaries(tags, h.minima, take.rate_hz, options.refine);
    const std::string& given = side == 0 ? options.right_tier : options.left_tier;
    h.tier =
        ApplyRefinement(manual, h.boundaries, given.empty() ? manual.name + (side == 0 ? "_right" : "_left") : given);
    out.push_back(std::move(h));
  }
  return out;
}

}  // namespace csw::signing
