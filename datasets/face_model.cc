#include "datasets/face_model.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <map>

#include "core/error.h"
#include "datasets/motion.h"
#include "synth/phonetics.h"

namespace csw {

namespace {

// One face marker: neutral position (right-side markers have x < 0) and its
// loadings on the articulatory parameters.
struct MarkerSpec {
  std::string name;
  char role;  // 'r' rigid head, 'f' face, 't' throat
  double x, y, z;
  double jaw;                        // weight of the jaw (opening rotation and advance)
  double protrude_y;                 // forward per mm of protrusion
  double protrude_x;                 // towards the midline per mm of protrusion
  double close_z;                    // up per mm of closure
  double raise_y;                    // forward per mm of lip raising
  double raise_z;                    // up per mm of lip raising
  double larynx_z;                   // up per mm of larynx
  double head_weight;                // 1 except on the throat: fraction of the head's rotation
  double translation_weight = -1.0;  // fraction of the head's translation (< 0: head_weight)
};

// Jaw rotation axis (temporomandibular joint), head frame.
const Eigen::Vector3d kJawCentre(0.0, 10.0, -15.0);
constexpr double kJawRadius = 100.0;  // mm of chin travel per radian / 100

std::vector<MarkerSpec> Specs() {
  std::vector<MarkerSpec> s = {
      // rigid head set: forehead, nasion, nose, temples, ears
      {"FHL", 'r', 35, 86, 74, 0, 0, 0, 0, 0, 0, 0, 1},
      {"FHR", 'r', -35, 86, 74, 0, 0, 0, 0, 0, 0, 0, 1},
      {"NAS", 'r', 0, 100, 42, 0, 0, 0, 0, 0, 0, 0, 1},
      {"NOST", 'r', 0, 122, 2, 0, 0, 0, 0, 0, 0, 0, 1},
      {"NOSL", 'r', 15, 108, -4, 0, 0, 0, 0, 0, 0, 0, 1},
      {"NOSR", 'r', -15, 108, -4, 0, 0, 0, 0, 0, 0, 0, 1},
      {"TMPL", 'r', 63, 62, 48, 0, 0, 0, 0, 0, 0, 0, 1},
      {"TMPR", 'r', -63, 62, 48, 0, 0, 0, 0, 0, 0, 0, 1},
      {"EARL", 'r', 76, 0, 12, 0, 0, 0, 0, 0, 0, 0, 1},
      {"EARR", 'r', -76, 0, 12, 0, 0, 0, 0, 0, 0, 0, 1},
      // eyebrows, under the eyes, cheekbones (static in this model)
      {"EBLI", 'f', 16, 97, 54, 0, 0, 0, 0, 0, 0, 0, 1},
      {"EBLO", 'f', 40, 88, 52, 0, 0, 0, 0, 0, 0, 0, 1},
      {"EBRI", 'f', -16, 97, 54, 0, 0, 0, 0, 0, 0, 0, 1},
      {"EBRO", 'f', -40, 88, 52, 0, 0, 0, 0, 0, 0, 0, 1},
      {"UEYL", 'f', 32, 92, 22, 0, 0, 0, 0, 0, 0, 0, 1},
      {"UEYR", 'f', -32, 92, 22, 0, 0, 0, 0, 0, 0, 0, 1},
      {"CHBL", 'f', 50, 80, 12, 0.02, 0, 0, 0, 0, 0, 0, 1},
      {"CHBR", 'f', -50, 80, 12, 0.02, 0, 0, 0, 0, 0, 0, 1},
      // cheeks
      {"CKL1", 'f', 48, 82, -12, 0.15, 0.1, 0.1, 0, 0, 0, 0, 1},
      {"CKR1", 'f', -48, 82, -12, 0.15, 0.1, 0.1, 0, 0, 0, 0, 1},
      {"CKL2", 'f', 54, 68, -32, 0.45, 0.05, 0.05, 0, 0, 0, 0, 1},
      {"CKR2", 'f', -54, 68, -32, 0.45, 0.05, 0.05, 0, 0, 0, 0, 1},
      {"CKL3", 'f', 42, 82, -46, 0.7, 0.1, 0.1, 0, 0, 0, 0, 1},
      {"CKR3", 'f', -42, 82, -46, 0.7, 0.1, 0.1, 0, 0, 0, 0, 1},
      // nasolabial folds, philtrum
      {"NSLL", 'f', 24, 102, -16, 0.1, 0.2, 0.15, 0, 0, 0, 0, 1},
      {"NSLR", 'f', -24, 102, -16, 0.1, 0.2, 0.15, 0, 0, 0, 0, 1},
      {"PHL", 'f', 6, 112, -20, 0.05, 0.5, 0.05, -0.2, 0, 0.15, 0, 1},
      {"PHR", 'f', -6, 112, -20, 0.05, 0.5, 0.05, -0.2, 0, 0.15, 0, 1},
      // lips
      {"ULM", 'f', 0, 113, -31, 0.12, 1.0, 0, -0.5, 0, 0.3, 0, 1},
      {"ULL", 'f', 12, 110, -32, 0.12, 0.8, 0.3, -0.45, 0, 0.25, 0, 1},
      {"ULR", 'f', -12, 110, -32, 0.12, 0.8, 0.3, -0.45, 0, 0.25, 0, 1},
      {"LCL", 'f', 25, 101, -35, 0.5, 0.4, 0.6, 0, 0, 0.2, 0, 1},
      {"LCR", 'f', -25, 101, -35, 0.5, 0.4, 0.6, 0, 0, 0.2, 0, 1},
      {"LLM", 'f', 0, 110, -39, 0.95, 1.0, 0, 0.55, -0.5, 0.7, 0, 1},
      {"LLL", 'f', 12, 107, -38, 0.9, 0.8, 0.3, 0.5, -0.45, 0.6, 0, 1},
      {"LLR", 'f', -12, 107, -38, 0.9, 0.8, 0.3, 0.5, -0.45, 0.6, 0, 1},
      // chin and jaw
      {"LCH", 'f', 0, 105, -52, 1.0, 0.4, 0, 0.2, -0.2, 0.3, 0, 1},
      {"CHIN", 'f', 0, 104, -66, 1.0, 0, 0, 0, 0, 0, 0, 1},
      {"CHNL", 'f', 18, 98, -63, 1.0, 0, 0, 0, 0, 0, 0, 1},
      {"CHNR", 'f', -18, 98, -63, 1.0, 0, 0, 0, 0, 0, 0, 1},
      {"MNT", 'f', 0, 86, -84, 1.0, 0, 0, 0, 0, 0, 0.1, 1},
      {"JWL1", 'f', 58, 45, -48, 1.0, 0, 0, 0, 0, 0, 0, 1},
      {"JWR1", 'f', -58, 45, -48, 1.0, 0, 0, 0, 0, 0, 0, 1},
      {"JWL2", 'f', 46, 72, -64, 1.0, 0, 0, 0, 0, 0, 0, 1},
      {"JWR2", 'f', -46, 72, -64, 1.0, 0, 0, 0, 0, 0, 0, 1},
  };
  // Throat: 6 rows × 3 columns, THR01 top right ... THR18 bottom left.
  const double row_weight[6] = {0.85, 0.7, 0.55, 0.42, 0.32, 0.22};
  const double larynx_row[6] = {0.5, 1.0, 1.0, 0.9, 0.6, 0.3};
  const double jaw_row[6] = {0.3, 0.1, 0, 0, 0, 0};
  int k = 0;
  for (int r = 0; r < 6; ++r)
    for (int c = 0; c < 3; ++c, ++k) {
      double x = (c - 1) * 22.0;
      double y = 60.0 - 3.0 * r - (c == 1 ? 0.0 : 8.0);
      double z = -100.0 - 18.0 * r;
      double lat = c == 1 ? 1.0 : 0.5;
      char name[16];
      std::snprintf(name, sizeof name, "THR%02d", k + 1);
      s.push_back({name, 't', x, y, z, jaw_row[r], 0, 0, 0, 0, 0, larynx_row[r] * lat, row_weight[r]});
    }
  return s;
}

// Layout "lab2": a subset of the default markers under other names, and three
// throat markers at the larynx that follow the head's translation fully and a
// fraction of its rotation.
const std::vector<std::pair<std::string, std::string>>& Lab2Names() {
  static const std::vector<std::pair<std::string, std::string>> kNames = {
      {"FHL", "HeadFrontL"},   {"FHR", "HeadFrontR"},   {"NAS", "Nasion"},     {"TMPL", "TempleL"},
      {"TMPR", "TempleR"},     {"EBLI", "BrowL"},       {"EBRI", "BrowR"},     {"CKL2", "CheekL"},
      {"CKR2", "CheekR"},      {"CKL3", "CheekLowL"},   {"CKR3", "CheekLowR"}, {"NSLL", "NasolabialL"},
      {"NSLR", "NasolabialR"}, {"ULM", "UpperLip"},     {"ULL", "UpperLipL"},  {"ULR", "UpperLipR"},
      {"LCL", "MouthCornerL"}, {"LCR", "MouthCornerR"}, {"LLM", "LowerLip"},   {"LLL", "LowerLipL"},
      {"LLR", "LowerLipR"},    {"CHIN", "Chin"},        {"MNT", "UnderChin"},  {"JWL2", "JawL"},
      {"JWR2", "JawR"}};
  return kNames;
}

std::vector<MarkerSpec> Lab2Specs() {
  const std::vector<MarkerSpec> all = Specs();
  std::vector<MarkerSpec> s;
  for (const auto& [from, to] : Lab2Names()) {
    for (const MarkerSpec& m : all) {
      if (m.name != from) continue;
      MarkerSpec copy = m;
      copy.name = to;
      s.push_back(copy);
    }
  }
  // Throat: a row over the larynx (between the default rows 2 and 3).
  const double w = kLab2ThroatRotationWeight;
  s.push_back({"LarynxR", 't', -20.0, 52.0, -126.0, 0.05, 0, 0, 0, 0, 0, 0.55, w, 1.0});
  s.push_back({"LarynxM", 't', 0.0, 60.0, -124.0, 0.05, 0, 0, 0, 0, 0, 1.0, w, 1.0});
  s.push_back({"LarynxL", 't', 20.0, 52.0, -126.0, 0.05, 0, 0, 0, 0, 0, 0.55, w, 1.0});
  return s;
}

}  // namespace

const std::vector<std::string>& SimulatorLayouts() {
  static const std::vector<std::string> kLayouts = {"default", "lab2"};
  return kLayouts;
}

bool IsSimulatorLayout(const std::string& name) {
  const auto& l = SimulatorLayouts();
  return std::find(l.begin(), l.end(), name) != l.end();
}

const char* ArticulatoryName(int parameter) {
  static const char* kNames[kNumArticulatory] = {"jaw_opening", "jaw_advance", "lip_protrusion",
                                                 "lip_closure", "lip_raising", "larynx"};
  return parameter >= 0 && parameter < kNumArticulatory ? kNames[parameter] : "";
}

Eigen::Isometry3d HeadMotion::Weighted(double weight) const {
  Eigen::Isometry3d x = Eigen::Isometry3d::Identity();
  Eigen::Vector3d r = rotation * weight;
  double angle = r.norm();
  if (angle > 0.0) x.linear() = Eigen::AngleAxisd(angle, r / angle).toRotationMatrix();
  x.translation() = translation * weight;
  return x;
}

Eigen::Isometry3d HeadMotion::Weighted(double rotation_weight, double translation_weight) const {
  Eigen::Isometry3d x = Weighted(rotation_weight);
  x.translation() = translation * translation_weight;
  return x;
}

VirtualFace::VirtualFace() : VirtualFace(std::string("default")) {}

VirtualFace::VirtualFace(const std::string& layout) : layout_(layout) {
  if (!IsSimulatorLayout(layout)) throw InvalidInput("unknown simulator layout \"" + layout + "\"");
  const bool lab2 = layout == "lab2";
  std::vector<MarkerSpec> specs = lab2 ? Lab2Specs() : Specs();
  const auto n = static_cast<Eigen::Index>(specs.size());
  neutral_.resize(3, n);
  basis_.assign(kNumArticulatory, Eigen::Matrix3Xd::Zero(3, n));
  head_weights_.resize(n);
  translation_weights_.resize(n);
  for (Eigen::Index i = 0; i < n; ++i) {
    const MarkerSpec& m = specs[static_cast<size_t>(i)];
    names_.emplace_back(m.name);
    if (m.role == 'r') rigid_.emplace_back(m.name);
    if (m.role == 'f') face_.emplace_back(m.name);
    if (m.role == 't') throat_.emplace_back(m.name);
    Eigen::Vector3d p(m.x, m.y, m.z);
    neutral_.col(i) = p;
    head_weights_[i] = m.head_weight;
    translation_weights_[i] = m.translation_weight < 0.0 ? m.head_weight : m.translation_weight;
    // Jaw opening: linearised rotation about the TMJ axis (chin goes down and back).
    basis_[kJawOpening].col(i) = m.jaw * (-Eigen::Vector3d::UnitX()).cross(p - kJawCentre) / kJawRadius;
    basis_[kJawAdvance].col(i) = m.jaw * Eigen::Vector3d::UnitY();
    double towards_midline = m.x > 0 ? -1.0 : (m.x < 0 ? 1.0 : 0.0);
    basis_[kLipProtrusion].col(i) = Eigen::Vector3d(towards_midline * m.protrude_x, m.protrude_y, 0.0);
    basis_[kLipClosure].col(i) = Eigen::Vector3d(0.0, 0.0, m.close_z);
    basis_[kLipRaising].col(i) = Eigen::Vector3d(0.0, m.raise_y, m.raise_z);
    basis_[kLarynx].col(i) = Eigen::Vector3d(0.0, 0.15 * m.larynx_z, m.larynx_z);
  }
  const std::vector<std::pair<std::string, std::string>> sticks = {
      {"FHL", "FHR"},   {"FHL", "TMPL"},  {"FHR", "TMPR"},  {"TMPL", "EARL"}, {"TMPR", "EARR"}, {"NAS", "NOST"},
      {"NOSL", "NOST"}, {"NOSR", "NOST"}, {"EBLI", "EBLO"}, {"EBRI", "EBRO"}, {"LCR", "ULR"},   {"ULR", "ULM"},
      {"ULM", "ULL"},   {"ULL", "LCL"},   {"LCR", "LLR"},   {"LLR", "LLM"},   {"LLM", "LLL"},   {"LLL", "LCL"},
      {"PHL", "PHR"},   {"LCH", "CHIN"},  {"CHNR", "CHIN"}, {"CHIN", "CHNL"}, {"CHNL", "JWL2"}, {"JWL2", "JWL1"},
      {"CHNR", "JWR2"}, {"JWR2", "JWR1"}, {"CHIN", "MNT"},  {"CHBL", "CKL1"}, {"CKL1", "CKL2"}, {"CKL2", "CKL3"},
      {"CHBR", "CKR1"}, {"CKR1", "CKR2"}, {"CKR2", "CKR3"}};
  if (lab2) {
    auto renamed = [](const std::string& a) {
      for (const auto& [from, to] : Lab2Names())
        if (from == a) return to;
      return std::string();
    };
    for (const auto& [a, b] : sticks) {
      const std::string ra = renamed(a), rb = renamed(b);
      if (!ra.empty() && !rb.empty()) sticks_.emplace_back(ra, rb);
    }
    sticks_.emplace_back("LarynxR", "LarynxM");
    sticks_.emplace_back("LarynxM", "LarynxL");
    return;
  }
  sticks_ = sticks;
  for (int r = 0; r < 6; ++r)
    for (int c = 0; c < 3; ++c) {
      int k = r * 3 + c;
      if (c < 2) sticks_.emplace_back(throat_[static_cast<size_t>(k)], throat_[static_cast<size_t>(k + 1)]);
      if (r < 5) sticks_.emplace_back(throat_[static_cast<size_t>(k)], throat_[static_cast<size_t>(k + 3)]);
    }
}

int VirtualFace::MarkerIndex(const std::string& name) const {
  for (size_t i = 0; i < names_.size(); ++i)
    if (names_[i] == name) return static_cast<int>(i);
  return -1;
}

Eigen::Matrix3Xd VirtualFace::MarkersInHead(const ArticulatoryVector& p) const {
  Eigen::Matrix3Xd out = neutral_;
  for (int k = 0; k < kNumArticulatory; ++k) out += p[k] * basis_[static_cast<size_t>(k)];
  return out;
}

Eigen::Matrix3Xd VirtualFace::MarkersMoved(const ArticulatoryVector& p, const HeadMotion& motion) const {
  Eigen::Matrix3Xd out = MarkersInHead(p);
  const Eigen::Isometry3d full = motion.Weighted(1.0);
  for (Eigen::Index i = 0; i < out.cols(); ++i) {
    const double w = head_weights_[i], wt = translation_weights_[i];
    out.col(i) = (w == 1.0 && wt == 1.0 ? full : motion.Weighted(w, wt)) * Eigen::Vector3d(out.col(i));
  }
  return out;
}

// ---------------------------------------------------------------- targets

PhonemeTarget ArticulatoryTarget(const std::string& ipa) {
  using V = ArticulatoryVector;
  auto vowel = [](double jo, double lp, double lc, double lx) {
    PhonemeTarget t;
    t.vowel = true;
    t.target << jo, 0.0, lp, lc, 0.0, lx;
    return t;
  };
  auto cons = [](V target, V resistance) {
    PhonemeTarget t;
    t.target = target;
    t.resistance = resistance;
    return t;
  };
  auto v6 = [](double a, double b, double c, double d, double e, double f) {
    V x;
    x << a, b, c, d, e, f;
    return x;
  };
  static const std::map<std::string, PhonemeTarget> kTable = [&] {
    std::map<std::string, PhonemeTarget> t;
    t["a"] = vowel(14, -1, 0, -2);
    t["ɑ"] = vowel(14, 0, 0, -3);
    t["ɛ"] = vowel(10, -2, 0, 0);
    t["e"] = vowel(7, -3, 0, 1);
    t["i"] = vowel(4, -4, 0, 2);
    t["ɔ"] = vowel(11, 3, 0, -1);
    t["o"] = vowel(8, 5, 0, -1);
    t["u"] = vowel(5, 7, 1, -2);
    t["y"] = vowel(4, 7, 1, 1);
    t["ø"] = vowel(6, 5, 0, 0);
    t["œ"] = vowel(9, 3, 0, 0);
    t["ə"] = vowel(7, 2, 0, 0);
    t["ɑ̃"] = vowel(13, 1, 0, -2);
    t["ɔ̃"] = vowel(8, 5, 0, -1);
    t["ɛ̃"] = vowel(10, -1, 0, 0);
    t["œ̃"] = vowel(9, 3, 0, 0);
    const V bilabial_t = v6(2, 0, 0, 8, 0, 0), bilabial_k = v6(0.4, 0, 0.2, 1, 0, 0);
    for (const char* c : {"p", "b", "m"}) t[c] = cons(bilabial_t, bilabial_k);
    for (const char* c : {"f", "v"}) t[c] = cons(v6(3, 0, 0, 0, 5, 0), v6(0.4, 0, 0.3, 0, 1, 0));
    for (const char* c : {"t", "d", "n"}) t[c] = cons(v6(3, 1, 0, 0, 0, 0), v6(0.6, 0.4, 0.1, 0, 0, 0));
    for (const char* c : {"s", "z"}) t[c] = cons(v6(2, 1, -1, 0, 0, 0), v6(0.8, 0.5, 0.3, 0, 0, 0));
    t["l"] = cons(v6(5, 0, 0, 0, 0, 0), v6(0.4, 0, 0, 0, 0, 0));
    for (const char* c : {"ʃ", "ʒ"}) t[c] = cons(v6(3, 1, 6, 0, 0, 0), v6(0.7, 0.4, 0.8, 0, 0, 0));
    for (const char* c : {"k", "g", "ɡ", "ŋ"}) t[c] = cons(v6(5, 0, 0, 0, 0, 1), v6(0.3, 0, 0, 0, 0, 0.3));
    t["ɲ"] = cons(v6(4, 0, 0, 0, 0, 0), v6(0.4, 0, 0, 0, 0, 0));
    for (const char* c : {"ʁ", "r", "R"}) t[c] = cons(v6(6, 0, 0, 0, 0, -2), v6(0.2, 0, 0, 0, 0, 0.5));
    t["j"] = cons(v6(4, 0, -3, 0, 0, 1), v6(0.5, 0, 0.5, 0, 0, 0.3));
    t["ɥ"] = cons(v6(4, 0, 6, 0, 0, 1), v6(0.5, 0, 0.8, 0, 0, 0.3));
    t["w"] = cons(v6(5, 0, 7, 1, 0, 0), v6(0.4, 0, 0.9, 0.3, 0, 0));
    return t;
  }();
  if (ipa.empty()) return PhonemeTarget{};  // pause: neutral, mouth closed, no resistance
  auto it = kTable.find(ipa);
  if (it != kTable.end()) return it->second;
  return vowel(7, 1, 0, 0);  // unknown: schwa-like
}

std::vector<ArticulatoryVector> Coarticulate(const std::vector<Phone>& phones, const std::vector<double>& times_s) {
  struct Anchor {
    double t;
    ArticulatoryVector v;
  };
  std::vector<Anchor> anchors;
  const ArticulatoryVector neutral = ArticulatoryVector::Zero();
  constexpr double kPauseInset = 0.06;
  for (const Phone& ph : phones) {
    if (ph.ipa.empty()) {
      double d = ph.end_s - ph.start_s;
      if (d > 2.0 * kPauseInset + 0.04) {
        anchors.push_back({ph.start_s + kPauseInset, neutral});
        anchors.push_back({ph.end_s - kPauseInset, neutral});
      } else {
        anchors.push_back({0.5 * (ph.start_s + ph.end_s), neutral});
      }
      continue;
    }
    PhonemeTarget t = ArticulatoryTarget(ph.ipa);
    if (t.vowel) anchors.push_back({0.5 * (ph.start_s + ph.end_s), t.target});
  }
  if (!phones.empty()) {
    if (anchors.empty() || anchors.front().t > phones.front().start_s)
      anchors.insert(anchors.begin(), {phones.front().start_s - 0.1, neutral});
    if (anchors.back().t < phones.back().end_s) anchors.push_back({phones.back().end_s + 0.1, neutral});
  }
  std::stable_sort(anchors.begin(), anchors.end(), [](const Anchor& a, const Anchor& b) { return a.t < b.t; });

  struct ConsonantWindow {
    double start, end;  // plateau
    ArticulatoryVector target, resistance;
  };
  std::vector<ConsonantWindow> consonants;
  for (const Phone& ph : phones) {
    if (ph.ipa.empty()) continue;
    PhonemeTarget t = ArticulatoryTarget(ph.ipa);
    if (t.vowel) continue;
    double a = ph.start_s + 0.01, b = ph.end_s - 0.01;
    if (b < a) a = b = 0.5 * (ph.start_s + ph.end_s);
    consonants.push_back({a, b, t.target, t.resistance});
  }
  constexpr double kRamp = 0.07;

  std::vector<ArticulatoryVector> out;
  out.reserve(times_s.size());
  size_t k = 0;
  for (double t : times_s) {
    ArticulatoryVector v = neutral;
    if (!anchors.empty()) {
      while (k + 1 < anchors.size() && anchors[k + 1].t <= t) ++k;
      while (k > 0 && anchors[k].t > t) --k;
      if (t <= anchors.front().t) {
        v = anchors.front().v;
      } else if (k + 1 >= anchors.size()) {
        v = anchors.back().v;
      } else {
        const Anchor& a = anchors[k];
        const Anchor& b = anchors[k + 1];
        double span = b.t - a.t;
        double s = span > 0 ? MinimumJerk((t - a.t) / span) : 1.0;
        v = a.v + (b.v - a.v) * s;
      }
    }
    ArticulatoryVector sum_weight = ArticulatoryVector::Zero();
    ArticulatoryVector pull = ArticulatoryVector::Zero();
    for (const ConsonantWindow& c : consonants) {
      if (t < c.start - kRamp || t > c.end + kRamp) continue;
      double w = 1.0;
      if (t < c.start) w = MinimumJerk((t - (c.start - kRamp)) / kRamp);
      if (t > c.end) w = MinimumJerk(((c.end + kRamp) - t) / kRamp);
      ArticulatoryVector kw = c.resistance * w;
      sum_weight += kw;
      pull += kw.cwiseProduct(c.target - v);
    }
    for (int j = 0; j < kNumArticulatory; ++j)
      if (sum_weight[j] > 1.0) pull[j] /= sum_weight[j];
    out.push_back(v + pull);
  }
  return out;
}

}  // namespace csw
