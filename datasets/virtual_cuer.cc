#include "datasets/virtual_cuer.h"

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <map>
#include <nlohmann/json.hpp>
#include <sstream>

#include "core/error.h"
#include "datasets/capture.h"
#include "datasets/motion.h"

namespace csw {

namespace {

constexpr double kDeg = M_PI / 180.0;

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

// Independent generator per take and per purpose, from the corpus seed.
std::mt19937_64 Stream(uint64_t seed, const std::string& take, uint64_t purpose) {
  return std::mt19937_64(SplitMix(SplitMix(seed ^ Fnv1a(take)) + purpose));
}

double Uniform(std::mt19937_64& rng) { return static_cast<double>(rng() >> 11) * 0x1.0p-53; }

Eigen::Matrix<double, 6, 1> PoseVector(const Eigen::Isometry3d& x) {
  Eigen::AngleAxisd aa(x.linear());
  Eigen::Matrix<double, 6, 1> v;
  v.head<3>() = aa.axis() * aa.angle();
  if (!std::isfinite(v[0])) v.head<3>().setZero();
  v.tail<3>() = x.translation();
  return v;
}

void ShiftUtterance(Utterance* u, double dt) {
  for (Phone& p : u->phones) {
    p.start_s += dt;
    p.end_s += dt;
  }
  for (Word& w : u->words) {
    w.start_s += dt;
    w.end_s += dt;
  }
}

// Placement parameters of a key: reference point (3), frontal, pitch, twist, contact.
Eigen::VectorXd PlacementVector(const PlacementDef& d, const VirtualFace& face) {
  Eigen::VectorXd z(7);
  z.head<3>() = PlacementTarget(d, face);  // face: the default layout's (placement anchors)
  z[3] = d.frontal_rad;
  z[4] = d.pitch_rad;
  z[5] = d.twist_rad;
  z[6] = d.contact;
  return z;
}

}  // namespace

const char* CorpusKindName(CorpusKind kind) {
  switch (kind) {
    case CorpusKind::kShapes:
      return "shapes";
    case CorpusKind::kVisemes:
      return "visemes";
    case CorpusKind::kSentences:
      return "sentences";
  }
  return "";
}

bool ParseCorpusKind(const std::string& name, CorpusKind* kind) {
  for (CorpusKind k : {CorpusKind::kShapes, CorpusKind::kVisemes, CorpusKind::kSentences})
    if (name == CorpusKindName(k)) {
      *kind = k;
      return true;
    }
  return false;
}

std::string SimulateOptions::Check() const {
  if (!IsSimulatorLayout(layout)) {
    std::string known;
    for (const auto& l : SimulatorLayouts()) known += (known.empty() ? "" : ", ") + l;
    return "unknown layout \"" + layout + "\" (known: " + known + ")";
  }
  if (!(rate_hz >= 10.0 && rate_hz <= 2000.0)) return "rate_hz must be in [10, 2000]";
  if (!(hand_scale >= 0.5 && hand_scale <= 2.0)) return "hand_scale must be in [0.5, 2]";
  if (!(noise_mm >= 0.0 && noise_mm <= 50.0)) return "noise_mm must be in [0, 50]";
  if (cameras < 1 || cameras > 64) return "cameras must be in [1, 64]";
  if (min_cameras < 1 || min_cameras > cameras) return "min_cameras must be in [1, cameras]";
  if (!(dropouts_per_s >= 0.0 && dropouts_per_s <= 10.0)) return "dropouts_per_s must be in [0, 10]";
  if (count < 0) return "count must be >= 0";
  if (speech_rate_wpm < 80 || speech_rate_wpm > 450) return "speech_rate_wpm must be in [80, 450]";
  if (viseme_rate_wpm < 80 || viseme_rate_wpm > 450) return "viseme_rate_wpm must be in [80, 450]";
  if (!(lead_in_s >= 0.3 && lead_in_s <= 10.0)) return "lead_in_s must be in [0.3, 10] s";
  if (!(posture_sd_deg >= 0.0 && posture_sd_deg <= 20.0)) return "posture_sd_deg must be in [0, 20]";
  if (!(placement_sd_mm >= 0.0 && placement_sd_mm <= 30.0)) return "placement_sd_mm must be in [0, 30]";
  if (!(orientation_sd_deg >= 0.0 && orientation_sd_deg <= 20.0)) return "orientation_sd_deg must be in [0, 20]";
  if (std::string why = phasing.Check(); !why.empty()) return "phasing: " + why;
  if (!(max_tip_speed_mm_s >= 0.0 && max_turn_speed_deg_s >= 0.0 && max_joint_speed_deg_s >= 0.0))
    return "speed limits must be >= 0 (0 = no limit)";
  if (int16_c3d && !(c3d_scale_mm > 0.0 && c3d_scale_mm <= 10.0)) return "c3d_scale_mm must be in (0, 10]";
  for (const auto& s : sentences)
    if (s.find_first_not_of(" \t\r\n") == std::string::npos) return "a sentence is empty";
  return "";
}

// ---------------------------------------------------------------- body

VirtualCuer::VirtualCuer(const SimulateOptions& options)
    : options_(options),
      hand_(options.hand_config_path.empty() ? DefaultHandConfig() : LoadHandConfig(options.hand_config_path),
            IsSimulatorLayout(options.layout) ? options.layout : std::string("default"),
            options.hand_scale >= 0.5 && options.hand_scale <= 2.0 ? options.hand_scale : 1.0) {
  if (std::string why = options.Check(); !why.empty()) throw InvalidInput("simulate options: " + why);
  face_ = VirtualFace(options.layout);
  placements_ = options.placement_config_path.empty()
                    ? DefaultPlacementConfig()
                    : LoadPlacementConfig(options.placement_config_path, &anchor_face_);
}

std::vector<std::string> VirtualCuer::AllMarkerNames() const {
  std::vector<std::string> out = face_.marker_names();
  out.insert(out.end(), hand_.marker_names().begin(), hand_.marker_names().end());
  return out;
}

MarkerSet VirtualCuer::MakeMarkerSet(CorpusKind kind) const {
  const bool face = kind != CorpusKind::kShapes, hand = kind != CorpusKind::kVisemes;
  MarkerSet set;
  const bool lab2 = options_.layout == "lab2";
  set.name = lab2 ? "csw-virtual-cuer-lab2" : "csw-virtual-cuer";
  set.description = "Virtual cuer (csw datasets): " + std::to_string(face_.num_markers()) +
                    " face, head and throat markers and " + std::to_string(hand_.num_markers()) +
                    " right hand and forearm markers";
  set.head_cluster = face_.rigid_markers();
  if (face) set.face = face_.face_markers();
  for (const auto& t : face ? face_.throat_markers() : std::vector<std::string>{}) {
    ThroatMarker tm;
    tm.marker = t;
    // The default layout's throat markers follow a fraction of the head's
    // motion (a head weight); lab2's do not (full translation, part of the
    // rotation): no weight is written, as for another lab's marker set.
    if (!lab2) tm.head_weight = face_.head_weights()[face_.MarkerIndex(t)];
    set.throat.push_back(tm);
  }
  if (hand) {
    set.forearm_cluster = hand_.forearm_markers();
    for (const auto& s : hand_.segments()) set.hand_segments.push_back({s.name, s.parent, s.markers});
    set.fingertips = hand_.fingertip_markers();
    set.palm = hand_.palm_markers();
    set.sticks.insert(set.sticks.end(), hand_.sticks().begin(), hand_.sticks().end());
  }
  const auto& rigid = face_.rigid_markers();
  for (const auto& [a, b] : face_.sticks()) {
    bool rigid_pair = std::find(rigid.begin(), rigid.end(), a) != rigid.end() &&
                      std::find(rigid.begin(), rigid.end(), b) != rigid.end();
    if (face || rigid_pair) set.sticks.emplace_back(a, b);
  }
  return set;
}

Eigen::Matrix3Xd VirtualCuer::HandMarkersInLab(const Eigen::VectorXd& angles,
                                               const Eigen::Isometry3d& forearm_in_lab) const {
  Eigen::Matrix3Xd m = hand_.MarkersInForearm(angles);
  for (Eigen::Index i = 0; i < m.cols(); ++i) m.col(i) = forearm_in_lab * Eigen::Vector3d(m.col(i));
  return m;
}

Eigen::Isometry3d VirtualCuer::HeadReference() {
  Eigen::Isometry3d x = Eigen::Isometry3d::Identity();
  x.translation() = Eigen::Vector3d(0.0, 0.0, 1250.0);
  return x;
}

Eigen::Isometry3d VirtualCuer::ForearmInHead(int placement, int shape) const {
  const PlacementDef& d = placements_.At(placement);
  const HandPosture& posture = hand_.config().Posture(shape);
  Eigen::Matrix3d rot = ForearmOrientation(d.frontal_rad, d.pitch_rad, d.twist_rad);
  Eigen::Vector3d tip = hand_.TipInForearm(
      posture.angles, posture.reference_finger == "index" ? VirtualHand::kIndex : VirtualHand::kMiddle);
  Eigen::Isometry3d x = Eigen::Isometry3d::Identity();
  x.linear() = rot;
  x.translation() = PlacementTarget(d, anchor_face_) - rot * tip;
  return x;
}

Eigen::Matrix3Xd VirtualCuer::KeyFrame(int placement, int shape, const ArticulatoryVector& p) const {
  const Eigen::Isometry3d head = HeadReference();
  Eigen::Matrix3Xd out(3, face_.num_markers() + hand_.num_markers());
  Eigen::Matrix3Xd f = face_.MarkersInHead(p);
  for (int i = 0; i < face_.num_markers(); ++i) out.col(i) = head * Eigen::Vector3d(f.col(i));
  out.rightCols(hand_.num_markers()) =
      HandMarkersInLab(hand_.config().Posture(shape).angles, head * ForearmInHead(placement, shape));
  return out;
}

std::vector<KeyTiming> VirtualCuer::DrawTiming(const std::vector<Key>& keys, std::mt19937_64& rng) const {
  return SampleTiming(keys, options_.phasing, rng,
                      options_.overlap_gestures ? TimingMode::kOverlapping : TimingMode::kSequential);
}

// ---------------------------------------------------------------- scripts

struct VirtualCuer::Script {
  Utterance utterance;    // capture clock
  bool hand = true;       // hand markers captured
  std::vector<Key> keys;  // capture clock
  std::vector<KeyTiming> timing;
  std::vector<int> pose_placement;  // placement definition used for each key's pose
  bool rigid_head_only = false;     // capture only the rigid head markers of the face
  double duration_s = 0.0;
};

SimulationResult VirtualCuer::SimulateSentence(const std::string& name, const std::string& text, bool cued) const {
  PhonetiseOptions po;
  po.rate_wpm = cued ? options_.speech_rate_wpm : options_.viseme_rate_wpm;
  po.synthesize_audio = options_.audio;
  Utterance u = Phonetise(text, po);
  return SimulateUtterance(name, u, cued);
}

SimulationResult VirtualCuer::SimulateUtterance(const std::string& name, const Utterance& utterance, bool cued) const {
  Script s;
  s.utterance = utterance;
  const double lead = options_.lead_in_s;
  ShiftUtterance(&s.utterance, lead);
  if (!s.utterance.audio.samples.empty()) {
    const auto pad = static_cast<size_t>(std::llround(lead * s.utterance.audio.rate_hz)) *
                     static_cast<size_t>(std::max(1, s.utterance.audio.channels));
    s.utterance.audio.samples.insert(s.utterance.audio.samples.begin(), pad, 0.0f);
  }
  double end = lead + std::max(utterance.duration_s(), utterance.audio.duration_s());
  s.hand = cued;
  if (cued) {
    s.keys = CueKeys(s.utterance.phones);
    std::mt19937_64 rng = Stream(options_.seed, name, 1);
    s.timing = DrawTiming(s.keys, rng);
    for (const Key& k : s.keys) s.pose_placement.push_back(k.placement);
    for (const KeyTiming& t : s.timing) end = std::max({end, t.placement_target_s, t.shape_target_s});
  }
  s.duration_s = end + 0.5 * lead;
  return Run(name, s);
}

SimulationResult VirtualCuer::SimulateShapes(const std::string& name, const std::vector<int>& shapes) const {
  for (int sh : shapes)
    if (sh < 1 || sh > 8) throw InvalidInput("hand shape " + std::to_string(sh) + " is not in 1-8");
  Script s;
  s.hand = true;
  std::mt19937_64 rng = Stream(options_.seed, name, 1);
  const double lead = options_.lead_in_s;
  Key rest;
  s.keys.push_back(rest);
  s.timing.push_back({lead, lead, lead, lead});
  s.pose_placement.push_back(0);
  double t = lead;
  for (size_t i = 0; i < shapes.size(); ++i) {
    Key k;
    k.placement = 0;
    k.shape = shapes[i];
    k.type = KeyType::kConsonantAlone;
    KeyTiming kt;
    if (i == 0) {
      kt.placement_start_s = t;
      kt.placement_target_s = t + 0.55 + 0.1 * Uniform(rng);
      kt.shape_start_s = t + 0.15;
      kt.shape_target_s = kt.placement_target_s - 0.05;
    } else {
      kt.shape_start_s = t + 0.2 + 0.1 * Uniform(rng);
      kt.shape_target_s = kt.shape_start_s + 0.22 + 0.08 * Uniform(rng);
      kt.placement_start_s = kt.shape_start_s;  // no placement change in free space
      kt.placement_target_s = kt.shape_target_s;
    }
    k.a1_s = kt.shape_target_s;
    k.end_s = kt.shape_target_s;
    t = std::max(kt.shape_target_s, kt.placement_target_s);
    s.keys.push_back(k);
    s.timing.push_back(kt);
    s.pose_placement.push_back(kFreeSpacePlacement);
  }
  KeyTiming back;
  back.placement_start_s = back.shape_start_s = t + 0.3;
  back.placement_target_s = back.shape_target_s = t + 0.95;
  Key last;
  last.a1_s = last.end_s = back.shape_target_s;
  s.keys.push_back(last);
  s.timing.push_back(back);
  s.pose_placement.push_back(0);
  s.duration_s = back.shape_target_s + 0.5 * lead;
  s.rigid_head_only = true;
  return Run(name, s);
}

// ---------------------------------------------------------------- simulation

SimulationResult VirtualCuer::Run(const std::string& name, const Script& script) const {
  SimulationResult r;
  const double rate = options_.rate_hz;
  const auto frames = static_cast<int64_t>(std::ceil(script.duration_s * rate));
  std::vector<int> face_idx;
  for (int i = 0; i < face_.num_markers(); ++i) {
    const std::string& n = face_.marker_names()[static_cast<size_t>(i)];
    if (!script.rigid_head_only ||
        std::find(face_.rigid_markers().begin(), face_.rigid_markers().end(), n) != face_.rigid_markers().end())
      face_idx.push_back(i);
  }
  const int nf = static_cast<int>(face_idx.size());
  const int nh = script.hand ? hand_.num_markers() : 0;
  const int nj = hand_.num_joints();
  r.utterance = script.utterance;
  r.phasing = options_.phasing;
  for (size_t i = 0; i < script.keys.size(); ++i)
    r.keys.push_back({script.keys[i], script.timing[i], Eigen::VectorXd(), Eigen::Vector3d::Zero()});
  for (const auto& j : hand_.config().joints) r.joint_names.push_back(j.name);
  r.joint_angles = Eigen::MatrixXd::Zero(frames, script.hand ? nj : 0);
  r.articulation = Eigen::MatrixXd::Zero(frames, kNumArticulatory);
  r.head_motion = Eigen::MatrixXd::Zero(frames, 6);
  r.forearm_pose = Eigen::MatrixXd::Zero(frames, script.hand ? 6 : 0);
  r.head_reference = HeadReference();
  for (int i = 0; i < nf; ++i) r.face_columns.push_back(i);
  r.face_markers = face_idx;
  for (int i = 0; i < nh; ++i) r.hand_columns.push_back(nf + i);

  Take& take = r.take;
  take.name = name;
  take.rate_hz = rate;
  take.first_frame = 1;
  for (int i : face_idx) take.marker_names.push_back(face_.marker_names()[static_cast<size_t>(i)]);
  if (script.hand)
    take.marker_names.insert(take.marker_names.end(), hand_.marker_names().begin(), hand_.marker_names().end());
  take.audio = script.utterance.audio;
  take.provenance.csw_version = CSW_VERSION;
  r.clean = MarkerArray(frames, nf + nh);

  std::vector<double> times(static_cast<size_t>(frames));
  for (int64_t f = 0; f < frames; ++f) times[static_cast<size_t>(f)] = static_cast<double>(f) / rate;

  // Face: articulatory parameters by coarticulation of the phones.
  std::vector<ArticulatoryVector> art;
  if (!script.utterance.phones.empty()) {
    art = Coarticulate(script.utterance.phones, times);
  } else {
    art.assign(times.size(), ArticulatoryVector::Zero());
  }

  // Hand gestures (superposed minimum-jerk movements).
  const size_t nk = script.keys.size();
  std::vector<Gesture> shape_g, place_g;
  Eigen::VectorXd shape0, place0;
  if (script.hand && nk > 0) {
    // Each key's actual targets: the configured posture and placement with a
    // little per-key variability (a cuer never makes the same key twice).
    std::mt19937_64 var_rng = Stream(options_.seed, name, 4);
    auto normal = [&](double sd) { return sd * std::clamp(StandardNormal(var_rng), -2.5, 2.5); };
    std::vector<Eigen::VectorXd> shape_t(nk), place_t(nk);
    for (size_t i = 0; i < nk; ++i) {
      const HandPosture& p = hand_.config().Posture(script.keys[i].shape);
      Eigen::VectorXd q = p.angles;
      for (int j = 0; j < nj; ++j) q[j] += normal(options_.posture_sd_deg * kDeg);
      q = hand_.config().Clamp(q);
      shape_t[i].resize(nj + 1);
      shape_t[i].head(nj) = q;
      shape_t[i][nj] = p.reference_finger == "index" ? 1.0 : 0.0;
      Eigen::VectorXd z = PlacementVector(placements_.At(script.pose_placement[i]), anchor_face_);
      for (int c = 0; c < 3; ++c) z[c] += normal(options_.placement_sd_mm);
      for (int c = 3; c < 6; ++c) z[c] += normal(options_.orientation_sd_deg * kDeg);
      place_t[i] = z;
      r.keys[i].posture = q;
      r.keys[i].placement_point = z.head<3>();
    }
    shape0 = shape_t[0];
    place0 = place_t[0];
    // Shortest duration of a movement under a peak-speed limit (minimum jerk:
    // peak = 1.875 × distance / duration).
    auto shortest = [](double distance, double limit) { return limit > 0.0 ? 1.875 * distance / limit : 0.0; };
    for (size_t i = 1; i < nk; ++i) {
      KeyTiming& kt = r.keys[i].timing;
      const Eigen::VectorXd ds = shape_t[i] - shape_t[i - 1], dz = place_t[i] - place_t[i - 1];
      const double shape_min = shortest(ds.head(nj).cwiseAbs().maxCoeff(), options_.max_joint_speed_deg_s * kDeg);
      const double place_min =
          std::max(shortest(dz.head<3>().norm(), options_.max_tip_speed_mm_s),
                   shortest(dz.segment<3>(3).cwiseAbs().maxCoeff(), options_.max_turn_speed_deg_s * kDeg));
      // Start earlier, but not before the previous target of the same movement
      // (unless the draw already did); then, if still too short, reach later.
      const KeyTiming& prev = r.keys[i - 1].timing;
      auto stretch = [](double previous_target, double min_s, double& start, double& target) {
        if (target - start >= min_s) return;
        start = std::max(target - min_s, std::min(start, previous_target));
        target = std::max(target, start + min_s);
      };
      stretch(i > 1 ? prev.shape_target_s : -1e9, shape_min, kt.shape_start_s, kt.shape_target_s);
      stretch(i > 1 ? prev.placement_target_s : -1e9, place_min, kt.placement_start_s, kt.placement_target_s);
      if (i == 1) {  // the first rest key's times are the instant the hand leaves rest
        KeyTiming& rest = r.keys[0].timing;
        const double leave = std::min({rest.placement_start_s, kt.placement_start_s, kt.shape_start_s});
        rest = {leave, leave, leave, leave};
      }
      shape_g.push_back({kt.shape_start_s, kt.shape_target_s, ds});
      place_g.push_back({kt.placement_start_s, kt.placement_target_s, dz});
    }
  }

  // Head motion: slow drift (two sinusoids per degree of freedom) plus a small
  // movement towards the hand when it touches the face.
  std::mt19937_64 head_rng = Stream(options_.seed, name, 2);
  double amp[6][2], freq[6][2], phase[6][2];
  for (int d = 0; d < 6; ++d)
    for (int k = 0; k < 2; ++k) {
      amp[d][k] = (d < 3 ? 0.7 * kDeg : 1.2) * (0.5 + 0.5 * Uniform(head_rng));
      freq[d][k] = 0.08 + 0.35 * Uniform(head_rng);
      phase[d][k] = 2.0 * M_PI * Uniform(head_rng);
    }
  const Eigen::Vector3d contact_rotation(-0.8 * kDeg, -1.2 * kDeg, -1.0 * kDeg);
  const Eigen::Vector3d contact_translation(-2.0, 1.5, -0.5);

  Eigen::Matrix3Xd hand_local;
  for (int64_t f = 0; f < frames; ++f) {
    const double t = times[static_cast<size_t>(f)];
    HeadMotion motion;
    for (int d = 0; d < 6; ++d) {
      double v = 0.0;
      for (int k = 0; k < 2; ++k) v += amp[d][k] * std::sin(2.0 * M_PI * freq[d][k] * t + phase[d][k]);
      if (d < 3)
        motion.rotation[d] = v;
      else
        motion.translation[d - 3] = v;
    }
    Eigen::Isometry3d forearm_in_head = Eigen::Isometry3d::Identity();
    Eigen::VectorXd q;
    if (script.hand && nk > 0) {
      Eigen::VectorXd sv = Superpose(shape0, shape_g, t);
      Eigen::VectorXd zv = Superpose(place0, place_g, t);
      q = hand_.config().Clamp(sv.head(nj));
      double lambda = std::clamp(sv[nj], 0.0, 1.0);
      double contact = std::clamp(zv[6], 0.0, 1.0);
      motion.rotation += contact * contact_rotation;
      motion.translation += contact * contact_translation;
      Eigen::Matrix3d rot = ForearmOrientation(zv[3], zv[4], zv[5]);
      Eigen::Vector3d tip = (1.0 - lambda) * hand_.TipInForearm(q, VirtualHand::kMiddle) +
                            lambda * hand_.TipInForearm(q, VirtualHand::kIndex);
      forearm_in_head.linear() = rot;
      forearm_in_head.translation() = zv.head<3>() - rot * tip;
      r.joint_angles.row(f) = q.transpose();
    }
    const ArticulatoryVector& p = art[static_cast<size_t>(f)];
    r.articulation.row(f) = p.transpose();
    r.head_motion.block<1, 3>(f, 0) = motion.rotation.transpose();
    r.head_motion.block<1, 3>(f, 3) = motion.translation.transpose();
    Eigen::Matrix3Xd face = face_.MarkersMoved(p, motion);
    for (int i = 0; i < nf; ++i) {
      Eigen::Vector3d x = r.head_reference * Eigen::Vector3d(face.col(face_idx[static_cast<size_t>(i)]));
      float* dst = r.clean.at(f, i);
      for (int c = 0; c < 3; ++c) dst[c] = static_cast<float>(x[c]);
    }
    if (script.hand) {
      Eigen::Isometry3d forearm_in_lab = r.head_reference * motion.Weighted(1.0) * forearm_in_head;
      r.forearm_pose.row(f) = PoseVector(forearm_in_lab).transpose();
      hand_local = HandMarkersInLab(q, forearm_in_lab);
      for (int i = 0; i < nh; ++i) {
        float* dst = r.clean.at(f, nf + i);
        for (int c = 0; c < 3; ++c) dst[c] = static_cast<float>(hand_local(c, i));
      }
    }
  }

  // Capture artefacts.
  CaptureSetup setup = MakeCaptureSetup(options_);
  ApplyCaptureArtefacts(*this, setup, Stream(options_.seed, name, 3), &r);
  r.take.tiers = SimulationTiers(r);
  return r;
}

}  // namespace csw
