#include "datasets/virtual_signer.h"

#include <algorithm>
#include <cmath>
#include <iomanip>
#include <limits>
#include <random>
#include <sstream>

#include "core/error.h"
#include "datasets/motion.h"

namespace csw {

namespace {

constexpr double kDeg = M_PI / 180.0;
constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

uint64_t SplitMix(uint64_t x) {
  x += 0x9E3779B97F4A7C15ULL;
  x = (x ^ (x >> 30)) * 0xBF58476D1CE4E5B9ULL;
  x = (x ^ (x >> 27)) * 0x94D049BB133111EBULL;
  return x ^ (x >> 31);
}

uint64_t Fnv1a(const std::string& s) {
  uint64_t h = 1469598103934665603ULL;
  for (unsigned char c : s) {
    h ^= c;
    h *= 1099511628211ULL;
  }
  return h;
}

std::mt19937_64 Stream(uint64_t seed, const std::string& take, uint64_t purpose) {
  return std::mt19937_64(SplitMix(SplitMix(seed ^ Fnv1a(take)) + purpose));
}

double Uniform(std::mt19937_64& rng) { return static_cast<double>(rng() >> 11) * 0x1.0p-53; }

double Normal(std::mt19937_64& rng) {
  double u1 = Uniform(rng), u2 = Uniform(rng);
  if (u1 < 1e-300) u1 = 1e-300;
  return std::sqrt(-2.0 * std::log(u1)) * std::cos(2.0 * M_PI * u2);
}

// A whole number uniformly in [lo, hi].
int64_t UniformInt(std::mt19937_64& rng, int64_t lo, int64_t hi) {
  if (hi <= lo) return lo;
  return lo + static_cast<int64_t>(rng() % static_cast<uint64_t>(hi - lo + 1));
}

std::string Fixed(double v, int digits) {
  std::ostringstream o;
  o << std::fixed << std::setprecision(digits) << v;
  return o.str();
}

// Joint names of one naming: torso, head end, then per side collar, shoulder,
// elbow, wrist, thumb1, index1, index2, pinky1.
struct Names {
  std::string hips, spine, chest, neck, head;
  std::string collar, shoulder, elbow, wrist, thumb1, index1, index2, pinky1;  // with "{S}" for the side
};

Names NamingOf(const std::string& naming) {
  if (naming == "mixamo")
    return {"mixamorig:Hips",         "mixamorig:Spine",         "mixamorig:Spine2",        "mixamorig:Neck",
            "mixamorig:Head",         "mixamorig:{S}Shoulder",   "mixamorig:{S}Arm",        "mixamorig:{S}ForeArm",
            "mixamorig:{S}Hand",      "mixamorig:{S}HandThumb1", "mixamorig:{S}HandIndex1", "mixamorig:{S}HandIndex2",
            "mixamorig:{S}HandPinky1"};
  return {"Hips",     "Spine",    "Chest",     "Neck",      "Head",      "{S}Collar", "{S}Shoulder",
          "{S}Elbow", "{S}Wrist", "{S}Thumb1", "{S}Index1", "{S}Index2", "{S}Pinky1"};
}

std::string Sided(std::string pattern, const std::string& side) {
  const size_t p = pattern.find("{S}");
  if (p != std::string::npos) pattern.replace(p, 3, side);
  return pattern;
}

const std::vector<std::string> kRotations = {"Zrotation", "Xrotation", "Yrotation"};

}  // namespace

const char* SignTypeName(SignType type) {
  switch (type) {
    case SignType::kOneHand:
      return "one_hand";
    case SignType::kTwoHands:
      return "two_hands";
    case SignType::kSymmetric:
      return "symmetric";
  }
  return "?";
}

const char* DurationLawName(DurationLaw law) { return law == DurationLaw::kSurface ? "surface" : "simple"; }

bool ParseDurationLaw(const std::string& name, DurationLaw* law) {
  if (name == "surface") {
    *law = DurationLaw::kSurface;
    return true;
  }
  if (name == "simple") {
    *law = DurationLaw::kSimple;
    return true;
  }
  return false;
}

std::vector<std::string> SignerNamings() { return {"csw", "mixamo"}; }

std::string SignerOptions::Check() const {
  if (!(rate_hz >= 20.0 && rate_hz <= 1000.0)) return "rate_hz must be in [20, 1000]";
  if (min_signs < 1 || max_signs < min_signs || max_signs > 100) return "signs per take: need 1 <= min <= max <= 100";
  for (double t : theta)
    if (!std::isfinite(t)) return "theta must be finite";
  if (!(simple_alpha >= 0.0 && simple_alpha <= 1.0)) return "simple_alpha must be in [0, 1]";
  if (!(distance_unit_mm > 0.0 && std::isfinite(distance_unit_mm))) return "distance_unit_mm must be > 0";
  if (!(duration_noise_sd_s >= 0.0 && duration_noise_sd_s <= 1.0)) return "duration_noise_sd_s must be in [0, 1]";
  if (!(min_movement_s > 0.0 && max_movement_s >= min_movement_s && max_movement_s <= 10.0))
    return "need 0 < min_movement_s <= max_movement_s <= 10";
  if (!(hand_offset_max_s >= 0.0 && hand_offset_max_s <= 0.2)) return "hand_offset_max_s must be in [0, 0.2]";
  if (!(stroke_time_sd >= 0.0 && stroke_time_sd <= 0.4)) return "stroke_time_sd must be in [0, 0.4]";
  if (!(posture_sd_deg >= 0.0 && posture_sd_deg <= 10.0)) return "posture_sd_deg must be in [0, 10]";
  if (!(noise_mm >= 0.0 && noise_mm <= 20.0)) return "noise_mm must be in [0, 20]";
  if (!(rest_s >= hand_offset_max_s + 0.1 && rest_s <= 10.0)) return "rest_s must be in [hand_offset_max_s + 0.1, 10]";
  const auto namings = SignerNamings();
  if (std::find(namings.begin(), namings.end(), naming) == namings.end())
    return "unknown naming \"" + naming + "\" (known: csw, mixamo)";
  if (!(body_scale >= 0.3 && body_scale <= 3.0)) return "body_scale must be in [0.3, 3]";
  if (!(arm_scale >= 0.5 && arm_scale <= 2.0)) return "arm_scale must be in [0.5, 2]";
  return "";
}

// ---------------------------------------------------------------- lexicon

ArmPosture SignerRestPosture() { return {80, 5, 10, 60, 0, 0, 0, 20}; }

const std::vector<LexiconSign>& SignerLexicon() {
  using T = SignType;
  static const std::vector<LexiconSign> kLexicon = {
      // gloss, type, movements, stroke_s, right start, right end, left start, left end
      {"MUSEUM", T::kOneHand, 1, 0.40, {65, 15, 20, 100, 0, 0, 0, 10}, {65, 30, 25, 115, 10, 0, 10, 30}, {}, {}},
      {"AFTERNOON", T::kOneHand, 2, 0.55, {60, 10, 25, 110, 0, 0, 0, 0}, {60, 25, 15, 95, 0, 20, 0, 0}, {}, {}},
      {"WHERE", T::kOneHand, 1, 0.35, {70, 5, 30, 90, 0, -10, 0, 40}, {62, 0, 35, 100, 20, -10, 0, 40}, {}, {}},
      {"NOON", T::kOneHand, 1, 0.35, {72, 25, 10, 125, 0, 0, -10, 20}, {72, 35, 15, 135, 0, 10, -10, 20}, {}, {}},
      {"HELLO", T::kOneHand, 1, 0.45, {55, -10, 20, 120, 0, 0, 0, 0}, {50, -20, 30, 110, 0, 0, 20, 0}, {}, {}},
      {"HOUR",
       T::kTwoHands,
       1,
       0.40,
       {65, 30, 20, 100, 0, 10, 0, 40},
       {65, 35, 25, 95, 0, 25, 0, 40},
       {72, 25, 20, 90, 0, 0, 0, 10},
       {70, 28, 27, 96, 0, 0, 0, 10}},
      {"TO_PAY",
       T::kTwoHands,
       1,
       0.45,
       {62, 20, 25, 105, 0, 0, 0, 20},
       {62, 35, 35, 100, 0, 0, 10, 20},
       {70, 20, 20, 95, 0, 0, 0, 0},
       {68, 25, 27, 100, 0, 0, 0, 0}},
      {"EXHIBITION",
       T::kTwoHands,
       1,
       0.50,
       {58, 5, 30, 110, 10, 0, 0, 0},
       {55, 15, 40, 100, -10, 0, 0, 0},
       {60, 10, 25, 105, 0, 0, 0, 0},
       {62, 15, 30, 100, 0, 0, 0, 0}},
      {"THEATER",
       T::kTwoHands,
       2,
       0.60,
       {60, 15, 20, 115, 0, 0, 0, 10},
       {60, 20, 28, 105, 0, 0, 0, 10},
       {66, 20, 18, 110, 0, 0, 0, 10},
       {64, 22, 25, 106, 0, 0, 0, 10}},
      {"SWIMMING_POOL", T::kSymmetric, 2, 0.60, {62, 20, 25, 95, 0, 0, 0, 0}, {55, 5, 35, 90, 0, 0, -15, 0}, {}, {}},
      {"OPEN", T::kSymmetric, 1, 0.40, {68, 35, 20, 100, 0, 0, 0, 10}, {58, 5, 30, 100, 0, 20, 0, 10}, {}, {}},
      {"CLOSE", T::kSymmetric, 1, 0.40, {58, 5, 30, 100, 0, 20, 0, 10}, {68, 35, 20, 100, 0, 0, 0, 10}, {}, {}},
      {"BUILDING", T::kSymmetric, 1, 0.50, {66, 25, 25, 95, 0, 0, 0, 0}, {60, 20, 15, 135, 0, 0, 0, 0}, {}, {}},
      {"TODAY", T::kSymmetric, 1, 0.35, {70, 15, 20, 90, 0, 0, 0, 20}, {72, 15, 27, 78, 0, 0, 0, 20}, {}, {}},
  };
  return kLexicon;
}

// ---------------------------------------------------------------- kinematics

double MeanGeodesicDistance(const SkeletonPose& a, const SkeletonPose& b) {
  const size_t n = std::min(a.orientations.size(), b.orientations.size());
  if (n == 0) return 0.0;
  double sum = 0.0;
  for (size_t j = 0; j < n; ++j) {
    const Eigen::Quaterniond d = a.orientations[j].conjugate() * b.orientations[j];
    // ‖log q‖ = atan2(|v|, |w|): half the rotation angle, in [0, π/2] (q and −q alike).
    sum += std::atan2(d.vec().norm(), std::abs(d.w()));
  }
  return sum / static_cast<double>(n);
}

double MeanEuclideanDistance(const SkeletonPose& a, const SkeletonPose& b, double unit_mm) {
  const Eigen::Index n = std::min(a.positions.cols(), b.positions.cols());
  if (n == 0) return 0.0;
  return (a.positions.leftCols(n) - b.positions.leftCols(n)).colwise().norm().mean() / unit_mm;
}

SkeletonPose ForwardKinematics(const std::vector<SkeletonJoint>& skeleton, const Eigen::VectorXd& values) {
  SkeletonPose pose;
  const size_t n = skeleton.size();
  pose.positions.resize(3, static_cast<Eigen::Index>(n));
  pose.orientations.resize(n);
  Eigen::Index c = 0;
  for (size_t j = 0; j < n; ++j) {
    const SkeletonJoint& joint = skeleton[j];
    Eigen::Vector3d t(joint.offset_mm[0], joint.offset_mm[1], joint.offset_mm[2]);
    Eigen::Quaterniond r = Eigen::Quaterniond::Identity();
    for (const std::string& ch : joint.channels) {
      if (c >= values.size()) throw InvalidInput("forward kinematics: fewer channel values than channels");
      const double v = values[c++];
      const int axis = ch.empty() ? -1 : ch[0] - 'X';
      if (axis < 0 || axis > 2) throw InvalidInput("forward kinematics: bad channel '" + ch + "'");
      if (ch.find("position") != std::string::npos) {
        t[axis] += v;
      } else {
        r = r * Eigen::Quaterniond(Eigen::AngleAxisd(v * kDeg, Eigen::Vector3d::Unit(axis)));
      }
    }
    if (joint.parent < 0) {
      pose.positions.col(static_cast<Eigen::Index>(j)) = t;
      pose.orientations[j] = r;
    } else {
      const auto p = static_cast<size_t>(joint.parent);
      pose.positions.col(static_cast<Eigen::Index>(j)) =
          pose.positions.col(static_cast<Eigen::Index>(p)) + pose.orientations[p] * t;
      pose.orientations[j] = (pose.orientations[p] * r).normalized();
    }
  }
  return pose;
}

// ---------------------------------------------------------------- the body

VirtualSigner::VirtualSigner(const SignerOptions& options) : options_(options) {
  if (std::string why = options.Check(); !why.empty()) throw InvalidInput("virtual signer options: " + why);
  const Names names = NamingOf(options.naming);
  const double b = options.body_scale, a = options.body_scale * options.arm_scale;
  auto add = [&](const std::string& name, int parent, double x, double y, double z, double scale, bool end) {
    SkeletonJoint j;
    j.name = name;
    j.parent = parent;
    j.offset_mm[0] = x * scale;
    j.offset_mm[1] = y * scale;
    j.offset_mm[2] = z * scale;
    j.end_site = end;
    if (!end) j.channels = kRotations;
    skeleton_.push_back(j);
    return static_cast<int>(skeleton_.size()) - 1;
  };
  const int hips = add(names.hips, -1, 0, 1000, 0, b, false);
  skeleton_[0].channels = {"Xposition", "Yposition", "Zposition", "Zrotation", "Xrotation", "Yrotation"};
  const int spine = add(names.spine, hips, 0, 120, 0, b, false);
  const int chest = add(names.chest, spine, 0, 250, 0, b, false);
  const int neck = add(names.neck, chest, 0, 200, 0, b, false);
  const int head = add(names.head, neck, 0, 100, 0, b, false);
  add(names.head + "_End", head, 0, 180, 0, b, true);
  for (const std::string side : {"Right", "Left"}) {
    const double s = side == "Right" ? -1.0 : 1.0;  // x = the signer's left
    std::vector<int>& arm = side == "Right" ? right_arm_ : left_arm_;
    const int collar = add(Sided(names.collar, side), chest, 40 * s, 170, 0, b, false);
    const int shoulder = add(Sided(names.shoulder, side), collar, 150 * s, 0, 0, a, false);
    const int elbow = add(Sided(names.elbow, side), shoulder, 280 * s, 0, 0, a, false);
    const int wrist = add(Sided(names.wrist, side), elbow, 250 * s, 0, 0, a, false);
    const int thumb = add(Sided(names.thumb1, side), wrist, 30 * s, -15, 35, a, false);
    add(skeleton_[static_cast<size_t>(thumb)].name + "_End", thumb, 45 * s, 0, 15, a, true);
    const int index1 = add(Sided(names.index1, side), wrist, 95 * s, 0, 25, a, false);
    const int index2 = add(Sided(names.index2, side), index1, 40 * s, 0, 0, a, false);
    add(skeleton_[static_cast<size_t>(index2)].name + "_End", index2, 30 * s, 0, 0, a, true);
    const int pinky = add(Sided(names.pinky1, side), wrist, 85 * s, 0, -30, a, false);
    add(skeleton_[static_cast<size_t>(pinky)].name + "_End", pinky, 55 * s, 0, 0, a, true);
    arm = {collar, shoulder, elbow, wrist, thumb, index1, index2, pinky};
    (side == "Right" ? right_wrist_ : left_wrist_) = wrist;
  }
}

std::vector<std::string> VirtualSigner::JointNames() const {
  std::vector<std::string> out;
  for (const SkeletonJoint& j : skeleton_) out.push_back(j.name);
  return out;
}

Eigen::VectorXd VirtualSigner::Channels(const ArmPosture& right, const ArmPosture& left) const {
  // Channel index of each joint's first channel.
  std::vector<Eigen::Index> first(skeleton_.size(), -1);
  Eigen::Index c = 0;
  for (size_t j = 0; j < skeleton_.size(); ++j) {
    first[j] = c;
    c += static_cast<Eigen::Index>(skeleton_[j].channels.size());
  }
  Eigen::VectorXd v = Eigen::VectorXd::Zero(c);
  for (int side = 0; side < 2; ++side) {
    const ArmPosture& p = side == 0 ? right : left;
    const std::vector<int>& arm = side == 0 ? right_arm_ : left_arm_;
    const double m = side == 0 ? 1.0 : -1.0;  // mirror: (Z, X, Y) -> (-Z, X, -Y)
    auto set = [&](int joint, double z, double x, double y) {
      const Eigen::Index f = first[static_cast<size_t>(joint)];
      v[f] = m * z;
      v[f + 1] = x;
      v[f + 2] = m * y;
    };
    set(arm[1], p[0], p[1], p[2]);  // shoulder
    set(arm[2], 0, 0, p[3]);        // elbow
    set(arm[3], p[4], p[5], p[6]);  // wrist
    set(arm[4], 0.5 * p[7], 0, 0);  // thumb
    set(arm[5], p[7], 0, 0);        // index 1
    set(arm[6], p[7], 0, 0);        // index 2
    set(arm[7], 1.2 * p[7], 0, 0);  // pinky
  }
  return v;
}

SkeletonPose VirtualSigner::Pose(const ArmPosture& right, const ArmPosture& left) const {
  return ForwardKinematics(skeleton_, Channels(right, left));
}

// ---------------------------------------------------------------- a take

namespace {

// Piecewise minimum-jerk motion of one arm: anchors at (possibly fractional)
// frame times; between two anchors the posture moves along s(τ).
struct ArmTrack {
  std::vector<double> frames;
  std::vector<ArmPosture> postures;
  void Add(double frame, const ArmPosture& p) {
    frames.push_back(frame);
    postures.push_back(p);
  }
  ArmPosture At(double frame) const {
    if (frame <= frames.front()) return postures.front();
    if (frame >= frames.back()) return postures.back();
    const size_t k = static_cast<size_t>(std::upper_bound(frames.begin(), frames.end(), frame) - frames.begin());
    const double f0 = frames[k - 1], f1 = frames[k];
    const double s = f1 > f0 ? MinimumJerk((frame - f0) / (f1 - f0)) : 1.0;
    ArmPosture out;
    for (size_t i = 0; i < out.size(); ++i) out[i] = postures[k - 1][i] + s * (postures[k][i] - postures[k - 1][i]);
    return out;
  }
};

// One interval label on a tier under construction (frames).
struct Span {
  int64_t start = 0, end = 0;
  std::string text;
};

void Push(std::vector<Span>* spans, int64_t start, int64_t end, const std::string& text) {
  if (end <= start) return;
  if (!spans->empty() && spans->back().text == text && spans->back().end == start) {
    spans->back().end = end;
    return;
  }
  spans->push_back({start, end, text});
}

LabelTier ToTier(const std::string& name, const std::vector<Span>& spans, double rate, double duration) {
  LabelTier t;
  t.name = name;
  t.kind = LabelTier::Kind::kInterval;
  t.start_s = 0.0;
  t.end_s = duration;
  for (size_t i = 0; i < spans.size(); ++i) {
    Label l;
    l.start_s = static_cast<double>(spans[i].start) / rate;
    l.end_s = i + 1 == spans.size() ? duration : static_cast<double>(spans[i].end) / rate;
    l.text = spans[i].text;
    t.labels.push_back(l);
  }
  return t;
}

}  // namespace

SignerTake VirtualSigner::SimulateTake(int index) const {
  std::ostringstream name;
  name << "signs" << std::setw(3) << std::setfill('0') << index;
  std::mt19937_64 rng = Stream(options_.seed, name.str(), 1);
  const int n = static_cast<int>(UniformInt(rng, options_.min_signs, options_.max_signs));
  const int lexicon = static_cast<int>(SignerLexicon().size());
  std::vector<int> signs;
  for (int i = 0; i < n; ++i) {
    int s = 0;
    do {
      s = static_cast<int>(UniformInt(rng, 0, lexicon - 1));
    } while (!signs.empty() && s == signs.back());
    signs.push_back(s);
  }
  return SimulateSequence(name.str(), signs);
}

SignerTake VirtualSigner::SimulateSequence(const std::string& name, const std::vector<int>& sequence) const {
  const auto& lex = SignerLexicon();
  if (sequence.empty()) throw InvalidInput("virtual signer: take '" + name + "' has no sign");
  for (int s : sequence)
    if (s < 0 || s >= static_cast<int>(lex.size()))
      throw InvalidInput("virtual signer: take '" + name + "': no sign " + std::to_string(s) + " in the lexicon");
  const SignerOptions& o = options_;
  const double rate = o.rate_hz;
  std::mt19937_64 var_rng = Stream(o.seed, name, 2), time_rng = Stream(o.seed, name, 3),
                  noise_rng = Stream(o.seed, name, 4);
  auto jitter = [&](ArmPosture p) {
    for (double& v : p) v += o.posture_sd_deg * std::clamp(Normal(var_rng), -2.5, 2.5);
    return p;
  };
  const int n = static_cast<int>(sequence.size());

  // Postures of every occurrence (start and end of its stroke, per arm).
  const ArmPosture rest_right = jitter(SignerRestPosture()), rest_left = jitter(SignerRestPosture());
  struct Occ {
    ArmPosture rs, re, ls, le;
    ArmPosture rf, lf;  // where the stroke ends: its end posture after an odd number of movements, else its start
    bool left_active = false;
  };
  std::vector<Occ> occ(static_cast<size_t>(n));
  SignerTake out;
  for (int k = 0; k < n; ++k) {
    const LexiconSign& s = lex[static_cast<size_t>(sequence[static_cast<size_t>(k)])];
    Occ& c = occ[static_cast<size_t>(k)];
    c.rs = jitter(s.right_start);
    c.re = jitter(s.right_end);
    if (s.type == SignType::kSymmetric) {
      c.ls = c.rs;
      c.le = c.re;
    } else if (s.type == SignType::kTwoHands) {
      c.ls = jitter(s.left_start);
      c.le = jitter(s.left_end);
    } else {
      c.ls = c.le = rest_left;
    }
    c.left_active = s.type != SignType::kOneHand;
    c.rf = s.movements % 2 == 1 ? c.re : c.rs;
    c.lf = s.movements % 2 == 1 ? c.le : c.ls;
    SignOccurrence so;
    so.lexicon = sequence[static_cast<size_t>(k)];
    so.gloss = s.gloss;
    so.type = s.type;
    out.signs.push_back(so);
  }

  // Stroke durations (frames).
  const int64_t max_offset = static_cast<int64_t>(std::floor(o.hand_offset_max_s * rate + 1e-9));
  std::vector<int64_t> stroke_frames(static_cast<size_t>(n));
  for (int k = 0; k < n; ++k) {
    const LexiconSign& s = lex[static_cast<size_t>(sequence[static_cast<size_t>(k)])];
    const double d = s.stroke_s * (1.0 + o.stroke_time_sd * std::clamp(Normal(time_rng), -2.0, 2.0));
    const int64_t min_frames = static_cast<int64_t>(std::ceil(0.1 * rate)) * s.movements + 2 * max_offset;
    stroke_frames[static_cast<size_t>(k)] = std::max(min_frames, static_cast<int64_t>(std::llround(d * rate)));
  }

  // Movements between strokes: n + 1 (preparation, transitions, retraction).
  // Mean linear and angular stroke speeds for SIMPLE.
  std::vector<double> stroke_v(static_cast<size_t>(n)), stroke_w(static_cast<size_t>(n));
  for (int k = 0; k < n; ++k) {
    const Occ& c = occ[static_cast<size_t>(k)];
    const LexiconSign& s = lex[static_cast<size_t>(sequence[static_cast<size_t>(k)])];
    const SkeletonPose a = Pose(c.rs, c.ls), b = Pose(c.re, c.le);
    const double dur = static_cast<double>(stroke_frames[static_cast<size_t>(k)]) / rate;
    stroke_v[static_cast<size_t>(k)] = MeanEuclideanDistance(a, b, o.distance_unit_mm) * s.movements / dur;
    stroke_w[static_cast<size_t>(k)] = MeanGeodesicDistance(a, b) * s.movements / dur;
  }
  std::vector<int64_t> move_frames(static_cast<size_t>(n + 1));
  for (int m = 0; m <= n; ++m) {
    TransitionTruth t;
    t.from_sign = m - 1;
    t.to_sign = m < n ? m : -1;
    t.kind = m == 0 ? "preparation" : (m == n ? "retraction" : "transition");
    const ArmPosture& r0 = m == 0 ? rest_right : occ[static_cast<size_t>(m - 1)].rf;
    const ArmPosture& l0 = m == 0 ? rest_left : occ[static_cast<size_t>(m - 1)].lf;
    const ArmPosture& r1 = m == n ? rest_right : occ[static_cast<size_t>(m)].rs;
    const ArmPosture& l1 = m == n ? rest_left : occ[static_cast<size_t>(m)].ls;
    const SkeletonPose a = Pose(r0, l0), b = Pose(r1, l1);
    t.geodesic = MeanGeodesicDistance(a, b);
    t.euclidean = MeanEuclideanDistance(a, b, o.distance_unit_mm);
    double d = 0.0;
    if (o.law == DurationLaw::kSurface) {
      d = o.theta[0] + o.theta[1] * t.geodesic + o.theta[2] * t.euclidean;
    } else {
      double v = 0, w = 0;
      int count = 0;
      for (int k : {m - 1, m})
        if (k >= 0 && k < n) {
          v += stroke_v[static_cast<size_t>(k)];
          w += stroke_w[static_cast<size_t>(k)];
          ++count;
        }
      v /= count;
      w /= count;
      const double lin = v > 0 ? t.euclidean / v : o.max_movement_s;
      const double ang = w > 0 ? t.geodesic / w : o.max_movement_s;
      d = o.simple_alpha * lin + (1.0 - o.simple_alpha) * ang;
    }
    if (o.duration_noise_sd_s > 0) d += o.duration_noise_sd_s * std::clamp(Normal(time_rng), -2.5, 2.5);
    t.law_s = d;
    const double clamped = std::clamp(d, o.min_movement_s, o.max_movement_s);
    move_frames[static_cast<size_t>(m)] = std::max<int64_t>(1, std::llround(clamped * rate));
    t.duration_s = static_cast<double>(move_frames[static_cast<size_t>(m)]) / rate;
    out.transitions.push_back(t);
  }

  // Nominal time line (frames): rest, movement 0, stroke 0, movement 1, ..., movement n, rest.
  const int64_t rest_frames = std::llround(o.rest_s * rate);
  std::vector<int64_t> move_start(static_cast<size_t>(n + 1)), move_end(static_cast<size_t>(n + 1));
  int64_t f = rest_frames;
  for (int m = 0; m <= n; ++m) {
    move_start[static_cast<size_t>(m)] = f;
    f += move_frames[static_cast<size_t>(m)];
    move_end[static_cast<size_t>(m)] = f;
    if (m < n) f += stroke_frames[static_cast<size_t>(m)];
  }
  const int64_t frames = f + rest_frames + 1;
  const double duration = static_cast<double>(frames) / rate;

  // Each hand's offset per movement.
  std::vector<int64_t> off_r(static_cast<size_t>(n + 1)), off_l(static_cast<size_t>(n + 1));
  for (int m = 0; m <= n; ++m) {
    off_r[static_cast<size_t>(m)] = UniformInt(time_rng, -max_offset, max_offset);
    off_l[static_cast<size_t>(m)] = UniformInt(time_rng, -max_offset, max_offset);
    out.transitions[static_cast<size_t>(m)].start_s = static_cast<double>(move_start[static_cast<size_t>(m)]) / rate;
    out.transitions[static_cast<size_t>(m)].end_s = static_cast<double>(move_end[static_cast<size_t>(m)]) / rate;
    out.transitions[static_cast<size_t>(m)].right_offset_s = static_cast<double>(off_r[static_cast<size_t>(m)]) / rate;
    out.transitions[static_cast<size_t>(m)].left_offset_s = static_cast<double>(off_l[static_cast<size_t>(m)]) / rate;
  }

  // Arm tracks and each hand's tier.
  ArmTrack right, left;
  std::vector<Span> right_spans, left_spans, sign_spans, type_spans;
  for (int side = 0; side < 2; ++side) {
    ArmTrack& track = side == 0 ? right : left;
    std::vector<Span>& spans = side == 0 ? right_spans : left_spans;
    const std::vector<int64_t>& off = side == 0 ? off_r : off_l;
    const ArmPosture& rest = side == 0 ? rest_right : rest_left;
    auto active = [&](int k) { return k >= 0 && k < n && (side == 0 || occ[static_cast<size_t>(k)].left_active); };
    track.Add(0, rest);
    int64_t cursor = 0;  // end of the labelled time so far
    for (int m = 0; m <= n; ++m) {
      const bool from = active(m - 1), to = active(m);
      const int64_t a = move_start[static_cast<size_t>(m)] + off[static_cast<size_t>(m)];
      const int64_t b = move_end[static_cast<size_t>(m)] + off[static_cast<size_t>(m)];
      // The phase before this movement: the previous stroke, or rest.
      const std::string before = from ? lex[static_cast<size_t>(sequence[static_cast<size_t>(m - 1)])].gloss : "rest";
      if (from || to) {
        Push(&spans, cursor, a, before);
        const Occ* prev = from ? &occ[static_cast<size_t>(m - 1)] : nullptr;
        const Occ* next = to ? &occ[static_cast<size_t>(m)] : nullptr;
        const ArmPosture p0 = prev ? (side == 0 ? prev->rf : prev->lf) : rest;
        const ArmPosture p1 = next ? (side == 0 ? next->rs : next->ls) : rest;
        track.Add(static_cast<double>(a), p0);
        track.Add(static_cast<double>(b), p1);
        Push(&spans, a, b, from && to ? "transition" : (to ? "preparation" : "retraction"));
        cursor = b;
      }
      // The stroke after this movement.
      if (m < n && to) {
        const Occ& c = occ[static_cast<size_t>(m)];
        const LexiconSign& s = lex[static_cast<size_t>(sequence[static_cast<size_t>(m)])];
        const double s0 = static_cast<double>(b);
        const double s1 = static_cast<double>(move_start[static_cast<size_t>(m + 1)] + off[static_cast<size_t>(m + 1)]);
        const ArmPosture& ps = side == 0 ? c.rs : c.ls;
        const ArmPosture& pe = side == 0 ? c.re : c.le;
        for (int i = 1; i <= s.movements; ++i) track.Add(s0 + (s1 - s0) * i / s.movements, i % 2 == 1 ? pe : ps);
        SignOccurrence& so = out.signs[static_cast<size_t>(m)];
        (side == 0 ? so.right_start_s : so.left_start_s) = s0 / rate;
        (side == 0 ? so.right_end_s : so.left_end_s) = s1 / rate;
      } else if (m < n && side == 1) {
        out.signs[static_cast<size_t>(m)].left_start_s = kNaN;
        out.signs[static_cast<size_t>(m)].left_end_s = kNaN;
      }
    }
    Push(&spans, cursor, frames, "rest");
    track.Add(static_cast<double>(frames), rest);
  }

  // The nominal tier and the sign types.
  Push(&sign_spans, 0, move_start[0], "rest");
  Push(&type_spans, 0, move_end[0], "");
  for (int m = 0; m <= n; ++m) {
    Push(&sign_spans, move_start[static_cast<size_t>(m)], move_end[static_cast<size_t>(m)],
         m == 0 ? "preparation" : (m == n ? "retraction" : "transition"));
    if (m < n) {
      const LexiconSign& s = lex[static_cast<size_t>(sequence[static_cast<size_t>(m)])];
      Push(&sign_spans, move_end[static_cast<size_t>(m)], move_start[static_cast<size_t>(m + 1)], s.gloss);
      if (m > 0) Push(&type_spans, move_start[static_cast<size_t>(m)], move_end[static_cast<size_t>(m)], "");
      type_spans.push_back(
          {move_end[static_cast<size_t>(m)], move_start[static_cast<size_t>(m + 1)], SignTypeName(s.type)});
      out.signs[static_cast<size_t>(m)].start_s = static_cast<double>(move_end[static_cast<size_t>(m)]) / rate;
      out.signs[static_cast<size_t>(m)].end_s = static_cast<double>(move_start[static_cast<size_t>(m + 1)]) / rate;
    }
  }
  Push(&sign_spans, move_end[static_cast<size_t>(n)], frames, "rest");
  Push(&type_spans, move_start[static_cast<size_t>(n)], frames, "");

  // Boundary truth: each interior boundary of the nominal tier.
  for (int m = 0; m <= n; ++m) {
    for (int edge = 0; edge < 2; ++edge) {
      BoundaryTruth bt;
      const int64_t nominal = edge == 0 ? move_start[static_cast<size_t>(m)] : move_end[static_cast<size_t>(m)];
      bt.nominal_s = static_cast<double>(nominal) / rate;
      bt.stroke = edge == 0 ? m > 0 : m < n;
      const bool right_from = m > 0, right_to = m < n;
      const bool left_from = m > 0 && occ[static_cast<size_t>(m - 1)].left_active;
      const bool left_to = m < n && occ[static_cast<size_t>(m)].left_active;
      bt.right_s = static_cast<double>(nominal + off_r[static_cast<size_t>(m)]) / rate;
      bt.left_s = (left_from || left_to) ? static_cast<double>(nominal + off_l[static_cast<size_t>(m)]) / rate : kNaN;
      bt.right_at_rest = edge == 0 ? !right_from : !right_to;
      bt.left_at_rest = edge == 0 ? !left_from : !left_to;
      out.boundaries.push_back(bt);
    }
  }

  // Motion: channels, forward kinematics, noise.
  Take& take = out.take;
  take.name = name;
  take.rate_hz = rate;
  take.first_frame = 1;
  take.skeleton = skeleton_;
  take.marker_names = JointNames();
  take.source_units = "mm";
  const auto joints = static_cast<int64_t>(skeleton_.size());
  take.markers = MarkerArray(frames, joints);
  out.clean = MarkerArray(frames, joints);
  take.orientations = OrientationArray(frames, joints);
  const Eigen::VectorXd first_channels = Channels(rest_right, rest_left);
  out.channels.resize(frames, first_channels.size());
  for (int64_t fr = 0; fr < frames; ++fr) {
    const Eigen::VectorXd ch = Channels(right.At(static_cast<double>(fr)), left.At(static_cast<double>(fr)));
    out.channels.row(fr) = ch.transpose();
    const SkeletonPose pose = ForwardKinematics(skeleton_, ch);
    for (int64_t j = 0; j < joints; ++j) {
      float* clean = out.clean.at(fr, j);
      float* noisy = take.markers.at(fr, j);
      for (int c = 0; c < 3; ++c) {
        clean[c] = static_cast<float>(pose.positions(c, j));
        noisy[c] = static_cast<float>(pose.positions(c, j) + o.noise_mm * Normal(noise_rng));
      }
      const Eigen::Quaterniond& q = pose.orientations[static_cast<size_t>(j)];
      float* w = take.orientations.at(fr, j);
      w[0] = static_cast<float>(q.w());
      w[1] = static_cast<float>(q.x());
      w[2] = static_cast<float>(q.y());
      w[3] = static_cast<float>(q.z());
    }
  }

  take.tiers.push_back(ToTier(kSignsTier, sign_spans, rate, duration));
  take.tiers.push_back(ToTier(kRightHandTier, right_spans, rate, duration));
  take.tiers.push_back(ToTier(kLeftHandTier, left_spans, rate, duration));
  take.tiers.push_back(ToTier(kSignTypesTier, type_spans, rate, duration));
  std::ostringstream what;
  what << "csw virtual signer: seed " << o.seed << ", " << n << " signs, law " << DurationLawName(o.law) << ", noise "
       << o.noise_mm << " mm";
  take.provenance.warnings.clear();
  take.provenance.csw_version = what.str();
  return out;
}

std::vector<SignerTake> SimulateSigner(const SignerOptions& options, int count, Progress& progress) {
  const VirtualSigner signer(options);
  std::vector<SignerTake> out;
  for (int i = 0; i < count; ++i) {
    progress.Update("virtual signer", static_cast<double>(i) / std::max(1, count));
    progress.CheckCancel();
    out.push_back(signer.SimulateTake(i));
  }
  return out;
}

LabelTier JitterBoundaries(const LabelTier& tier, const std::string& name, double max_offset_s, double rate_hz,
                           uint64_t seed, std::vector<double>* offsets) {
  LabelTier out = tier;
  out.name = name;
  if (offsets != nullptr) offsets->clear();
  std::mt19937_64 rng = Stream(seed, tier.name, 5);
  const double dt = 1.0 / rate_hz;
  const size_t n = out.labels.size();
  // Interior boundaries: label i's end == label i+1's start.
  std::vector<double> original;
  for (size_t i = 0; i + 1 < n; ++i) original.push_back(tier.labels[i].end_s);
  double previous = tier.labels.empty() ? 0.0 : tier.labels.front().start_s;
  for (size_t i = 0; i < original.size(); ++i) {
    const double next = i + 1 < original.size() ? original[i + 1] : tier.labels.back().end_s;
    const double lo = std::max(original[i] - max_offset_s, previous + dt);
    const double hi = std::min(original[i] + max_offset_s, next + max_offset_s - dt);
    const double t = hi > lo ? lo + (hi - lo) * Uniform(rng) : original[i];
    out.labels[i].end_s = t;
    out.labels[i + 1].start_s = t;
    previous = t;
    if (offsets != nullptr) offsets->push_back(t - original[i]);
  }
  return out;
}

std::string SignerTruthToJson(const SignerTake& t, const SignerOptions& o) {
  std::ostringstream j;
  auto num = [](double v, int d) { return std::isfinite(v) ? Fixed(v, d) : std::string("null"); };
  j << "{\n  \"take\": \"" << t.take.name << "\",\n  \"rate_hz\": " << num(o.rate_hz, 3) << ",\n  \"law\": \""
    << DurationLawName(o.law) << "\",\n  \"theta\": [" << num(o.theta[0], 6) << ", " << num(o.theta[1], 6) << ", "
    << num(o.theta[2], 6) << "],\n  \"simple_alpha\": " << num(o.simple_alpha, 4)
    << ",\n  \"distance_unit_mm\": " << num(o.distance_unit_mm, 3)
    << ",\n  \"duration_noise_sd_s\": " << num(o.duration_noise_sd_s, 4)
    << ",\n  \"hand_offset_max_s\": " << num(o.hand_offset_max_s, 4) << ",\n  \"noise_mm\": " << num(o.noise_mm, 3)
    << ",\n  \"seed\": " << o.seed << ",\n  \"signs\": [";
  for (size_t i = 0; i < t.signs.size(); ++i) {
    const SignOccurrence& s = t.signs[i];
    j << (i ? "," : "") << "\n    {\"gloss\": \"" << s.gloss << "\", \"type\": \"" << SignTypeName(s.type)
      << "\", \"start_s\": " << num(s.start_s, 4) << ", \"end_s\": " << num(s.end_s, 4)
      << ", \"right_start_s\": " << num(s.right_start_s, 4) << ", \"right_end_s\": " << num(s.right_end_s, 4)
      << ", \"left_start_s\": " << num(s.left_start_s, 4) << ", \"left_end_s\": " << num(s.left_end_s, 4) << "}";
  }
  j << "\n  ],\n  \"transitions\": [";
  for (size_t i = 0; i < t.transitions.size(); ++i) {
    const TransitionTruth& x = t.transitions[i];
    j << (i ? "," : "") << "\n    {\"kind\": \"" << x.kind << "\", \"from_sign\": " << x.from_sign
      << ", \"to_sign\": " << x.to_sign << ", \"start_s\": " << num(x.start_s, 4) << ", \"end_s\": " << num(x.end_s, 4)
      << ", \"right_offset_s\": " << num(x.right_offset_s, 4) << ", \"left_offset_s\": " << num(x.left_offset_s, 4)
      << ", \"geodesic\": " << num(x.geodesic, 6) << ", \"euclidean\": " << num(x.euclidean, 6)
      << ", \"law_s\": " << num(x.law_s, 6) << ", \"duration_s\": " << num(x.duration_s, 4) << "}";
  }
  j << "\n  ],\n  \"boundaries\": [";
  for (size_t i = 0; i < t.boundaries.size(); ++i) {
    const BoundaryTruth& b = t.boundaries[i];
    j << (i ? "," : "") << "\n    {\"nominal_s\": " << num(b.nominal_s, 4) << ", \"right_s\": " << num(b.right_s, 4)
      << ", \"left_s\": " << num(b.left_s, 4) << ", \"stroke\": " << (b.stroke ? "true" : "false")
      << ", \"right_at_rest\": " << (b.right_at_rest ? "true" : "false")
      << ", \"left_at_rest\": " << (b.left_at_rest ? "true" : "false") << "}";
  }
  j << "\n  ]\n}\n";
  return j.str();
}

}  // namespace csw
