#include "synth/dictionary.h"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>
#include <map>

#include "core/error.h"
#include "core/sha256.h"
#include "models/face_model.h"
#include "models/hand_model.h"
#include "models/rigid_motion.h"

namespace csw::dict {

namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

bool RowFinite(const Eigen::MatrixXd& m, int64_t row) { return m.row(row).allFinite(); }

}  // namespace

std::string DikeyOptions::Check() const {
  if (!(max_unsolved_fraction >= 0 && max_unsolved_fraction <= 1)) return "max_unsolved_fraction must be in [0, 1]";
  return "";
}

std::vector<KeyMark> KeysWithRests(const std::vector<KeyMark>& keys, double last_time_s, const DikeyOptions& options) {
  std::vector<KeyMark> out;
  if (options.add_rests && (keys.empty() || !keys.front().code.IsRest())) out.push_back({0.0, KeyCode{}});
  out.insert(out.end(), keys.begin(), keys.end());
  if (options.add_rests && !keys.empty() && !keys.back().code.IsRest()) out.push_back({last_time_s, KeyCode{}});
  return out;
}

Eigen::Matrix<double, 6, 1> RelativePose(const Eigen::Matrix<double, 6, 1>& a, const Eigen::Matrix<double, 6, 1>& b) {
  if (!a.allFinite() || !b.allFinite()) return Eigen::Matrix<double, 6, 1>::Constant(kNaN);
  const RigidTransform ta = RigidTransform::FromParameters(a);
  const RigidTransform tb = RigidTransform::FromParameters(b);
  RigidTransform rel;
  rel.rotation = ta.rotation.transpose() * tb.rotation;
  rel.translation = ta.rotation.transpose() * (tb.translation - ta.translation);
  return rel.Parameters();
}

std::vector<DikeyUnit> ExtractDikeys(const TakeSeries& s, const DikeyOptions& options, ExtractionStats* stats) {
  if (const std::string why = options.Check(); !why.empty()) throw InvalidInput(why);
  const std::string where = "take '" + s.take + "'";
  if (!(s.rate_hz > 0) || !std::isfinite(s.rate_hz)) throw InvalidInput(where + ": frame rate must be positive");
  const int64_t n = s.frames();
  if (s.forearm_pose.rows() != n || s.head_pose.rows() != n || s.forearm_pose.cols() != 6 || s.head_pose.cols() != 6) {
    throw InvalidInput(where + ": per-frame series disagree (hand parameters " + std::to_string(n) +
                       " frames, forearm pose " + std::to_string(s.forearm_pose.rows()) + "×" +
                       std::to_string(s.forearm_pose.cols()) + ", head pose " + std::to_string(s.head_pose.rows()) +
                       "×" + std::to_string(s.head_pose.cols()) + "; poses need 6 columns)");
  }
  if (!s.syllable_onset_s.empty() && s.syllable_onset_s.size() != s.keys.size()) {
    throw InvalidInput(where + ": " + std::to_string(s.syllable_onset_s.size()) + " syllable onsets for " +
                       std::to_string(s.keys.size()) + " keys");
  }
  if (!s.key_type.empty() && s.key_type.size() != s.keys.size()) {
    throw InvalidInput(where + ": " + std::to_string(s.key_type.size()) + " key types for " +
                       std::to_string(s.keys.size()) + " keys");
  }
  if (!s.placement_target_s.empty() && s.placement_target_s.size() != s.keys.size()) {
    throw InvalidInput(where + ": " + std::to_string(s.placement_target_s.size()) + " placement targets for " +
                       std::to_string(s.keys.size()) + " keys");
  }
  for (size_t i = 0; i < s.keys.size(); ++i) {
    if (!std::isfinite(s.keys[i].time_s)) {
      throw InvalidInput(where + ": key " + std::to_string(i + 1) + " has a time that is not finite");
    }
  }
  const double last_time = n > 0 ? static_cast<double>(n - 1) / s.rate_hz : 0.0;
  // Onsets travel with their marks when rests are added.
  std::vector<KeyMark> keys = KeysWithRests(s.keys, last_time, options);
  std::vector<double> onsets(keys.size(), kNaN);
  const size_t shift = (options.add_rests && (s.keys.empty() || !s.keys.front().code.IsRest())) ? 1 : 0;
  for (size_t i = 0; i < s.syllable_onset_s.size(); ++i) onsets[i + shift] = s.syllable_onset_s[i];
  std::vector<std::optional<KeyType>> types(keys.size());
  for (size_t i = 0; i < s.key_type.size(); ++i) types[i + shift] = s.key_type[i];
  for (size_t i = 0; i < keys.size(); ++i)
    if (keys[i].code.IsRest()) types[i] = KeyType::kRest;
  std::vector<double> lags(keys.size(), kNaN);
  for (size_t i = 0; i < s.placement_target_s.size(); ++i)
    if (std::isfinite(s.placement_target_s[i])) lags[i + shift] = s.placement_target_s[i] - s.keys[i].time_s;

  ExtractionStats local;
  std::vector<DikeyUnit> out;
  for (size_t i = 0; i + 1 < keys.size(); ++i) {
    ++local.successions;
    const int64_t f0 = static_cast<int64_t>(std::llround(keys[i].time_s * s.rate_hz));
    const int64_t f1 = static_cast<int64_t>(std::llround(keys[i + 1].time_s * s.rate_hz));
    if (f0 < 0 || f1 >= n || f1 < f0) {
      ++local.rejected_outside;
      continue;
    }
    const int64_t count = f1 - f0 + 1;
    int64_t unsolved = 0;
    for (int64_t f = f0; f <= f1; ++f) {
      if (!RowFinite(s.hand_params, f) || !RowFinite(s.forearm_pose, f) || !RowFinite(s.head_pose, f)) ++unsolved;
    }
    if (static_cast<double>(unsolved) > options.max_unsolved_fraction * static_cast<double>(count)) {
      ++local.rejected_unsolved;
      continue;
    }
    DikeyUnit u;
    u.take = s.take;
    u.index = static_cast<int>(i);
    u.from = keys[i].code;
    u.to = keys[i + 1].code;
    u.start_s = keys[i].time_s;
    u.end_s = keys[i + 1].time_s;
    u.first_frame = f0;
    u.rate_hz = s.rate_hz;
    u.hand_params = s.hand_params.middleRows(f0, count);
    u.head_pose = s.head_pose.middleRows(f0, count);
    u.forearm_in_head.resize(count, 6);
    for (int64_t r = 0; r < count; ++r) {
      u.forearm_in_head.row(r) =
          RelativePose(s.head_pose.row(f0 + r).transpose(), s.forearm_pose.row(f0 + r).transpose()).transpose();
    }
    u.phasing_s = keys[i + 1].time_s - onsets[i + 1];  // NaN when the onset is unknown
    u.to_type = types[i + 1];
    u.from_placement_lag_s = lags[i];
    u.to_placement_lag_s = lags[i + 1];
    out.push_back(std::move(u));
    ++local.kept;
  }
  if (stats) {
    stats->successions += local.successions;
    stats->kept += local.kept;
    stats->rejected_unsolved += local.rejected_unsolved;
    stats->rejected_outside += local.rejected_outside;
  }
  return out;
}

std::vector<DiphoneUnit> ExtractDiphones(const TakeSeries& s, const DikeyOptions& options, ExtractionStats* stats) {
  if (const std::string why = options.Check(); !why.empty()) throw InvalidInput(why);
  const std::string where = "take '" + s.take + "'";
  if (!(s.rate_hz > 0) || !std::isfinite(s.rate_hz)) throw InvalidInput(where + ": frame rate must be positive");
  const int64_t n = s.face_params.rows();
  if (s.hand_params.rows() != 0 && n != s.hand_params.rows()) {
    throw InvalidInput(where + ": face parameters have " + std::to_string(n) + " frames, hand parameters " +
                       std::to_string(s.hand_params.rows()));
  }
  for (size_t i = 0; i < s.phones.size(); ++i) {
    const Label& p = s.phones[i];
    if (!std::isfinite(p.start_s) || !std::isfinite(p.end_s) || p.end_s < p.start_s ||
        (i > 0 && p.start_s < s.phones[i - 1].end_s - 1e-9)) {
      throw InvalidInput(where + ": phone " + std::to_string(i + 1) + " ('" + p.text +
                         "') overlaps the previous one, is out of order or has a bad time");
    }
  }
  ExtractionStats local;
  std::vector<DiphoneUnit> out;
  for (size_t i = 0; i + 1 < s.phones.size(); ++i) {
    ++local.successions;
    const Label &a = s.phones[i], &b = s.phones[i + 1];
    const double t0 = 0.5 * (a.start_s + a.end_s), t1 = 0.5 * (b.start_s + b.end_s);
    const int64_t f0 = static_cast<int64_t>(std::llround(t0 * s.rate_hz));
    const int64_t f1 = static_cast<int64_t>(std::llround(t1 * s.rate_hz));
    if (f0 < 0 || f1 >= n || f1 < f0) {
      ++local.rejected_outside;
      continue;
    }
    const int64_t count = f1 - f0 + 1;
    int64_t unsolved = 0;
    for (int64_t f = f0; f <= f1; ++f)
      if (!RowFinite(s.face_params, f)) ++unsolved;
    if (static_cast<double>(unsolved) > options.max_unsolved_fraction * static_cast<double>(count)) {
      ++local.rejected_unsolved;
      continue;
    }
    DiphoneUnit u;
    u.take = s.take;
    u.index = static_cast<int>(i);
    u.phone1 = a.text.empty() ? "_" : a.text;
    u.phone2 = b.text.empty() ? "_" : b.text;
    u.phone1_start_s = a.start_s;
    u.phone1_end_s = a.end_s;
    u.phone2_start_s = b.start_s;
    u.phone2_end_s = b.end_s;
    u.start_s = t0;
    u.end_s = t1;
    u.first_frame = f0;
    u.rate_hz = s.rate_hz;
    u.audio_path = s.audio_path;
    u.face_params = s.face_params.middleRows(f0, count);
    out.push_back(std::move(u));
    ++local.kept;
  }
  if (stats) {
    stats->successions += local.successions;
    stats->kept += local.kept;
    stats->rejected_unsolved += local.rejected_unsolved;
    stats->rejected_outside += local.rejected_outside;
  }
  return out;
}

std::vector<std::pair<std::string, int>> DiphoneCoverage(const std::vector<DiphoneUnit>& units) {
  std::map<std::string, int> codes;
  for (const DiphoneUnit& u : units) codes[u.phone1 + "+" + u.phone2] += 1;
  return {codes.begin(), codes.end()};
}

std::string SuccessionCode(const KeyCode& from, const KeyCode& to) { return from.Text() + "-" + to.Text(); }

namespace {

void Add(Coverage* c, const KeyCode& from, const KeyCode& to, std::map<std::string, int>* codes) {
  c->placement(from.placement, to.placement) += 1;
  c->shape(from.shape, to.shape) += 1;
  (*codes)[SuccessionCode(from, to)] += 1;
  ++c->units;
}

void Finish(Coverage* c, const std::map<std::string, int>& codes) { c->dikeys.assign(codes.begin(), codes.end()); }

std::vector<std::pair<int, int>> Missing(const Eigen::MatrixXi& m) {
  std::vector<std::pair<int, int>> out;
  for (int a = 0; a < m.rows(); ++a)
    for (int b = 0; b < m.cols(); ++b)
      if (!(a == 0 && b == 0) && m(a, b) == 0) out.emplace_back(a, b);
  return out;
}

}  // namespace

std::vector<std::pair<int, int>> Coverage::MissingPlacements() const { return Missing(placement); }
std::vector<std::pair<int, int>> Coverage::MissingShapes() const { return Missing(shape); }

Coverage CoverageOfUnits(const std::vector<DikeyUnit>& units) {
  Coverage c;
  std::map<std::string, int> codes;
  for (const DikeyUnit& u : units) Add(&c, u.from, u.to, &codes);
  Finish(&c, codes);
  return c;
}

Coverage CoverageOfKeys(const std::vector<std::vector<KeyMark>>& key_lists, const std::vector<double>& last_times_s,
                        const DikeyOptions& options) {
  if (key_lists.size() != last_times_s.size()) throw InvalidInput("CoverageOfKeys: one last time per key list");
  Coverage c;
  std::map<std::string, int> codes;
  for (size_t t = 0; t < key_lists.size(); ++t) {
    const std::vector<KeyMark> keys = KeysWithRests(key_lists[t], last_times_s[t], options);
    for (size_t i = 0; i + 1 < keys.size(); ++i) Add(&c, keys[i].code, keys[i + 1].code, &codes);
  }
  Finish(&c, codes);
  return c;
}

namespace {

// Feeds tagged arrays (tag, sizes, doubles) into one byte string.
class Fingerprinter {
 public:
  void Add(const std::string& tag, const Eigen::MatrixXd& m) {
    bytes_ += tag;
    bytes_ += '\0';
    const int64_t dims[2] = {m.rows(), m.cols()};
    bytes_.append(reinterpret_cast<const char*>(dims), sizeof(dims));
    bytes_.append(reinterpret_cast<const char*>(m.data()), sizeof(double) * static_cast<size_t>(m.size()));
  }
  std::string Hex() const { return Sha256OfBytes(bytes_.data(), bytes_.size()); }

 private:
  std::string bytes_;
};

}  // namespace

std::string ModelsFingerprint(const FaceModel* face, const HandModel* hand) {
  Fingerprinter f;
  if (face) {
    f.Add("face/head/reference", face->head.reference);
    f.Add("face/head_weights", face->head_weights);
    f.Add("face/shape/mean", face->shape.mean);
    f.Add("face/shape/loadings", face->shape.loadings);
  }
  if (hand) {
    f.Add("hand/forearm/reference", hand->forearm.reference);
    f.Add("hand/angle_pca/mean", hand->shape.angle_pca.mean);
    f.Add("hand/angle_pca/components", hand->shape.angle_pca.components);
    f.Add("hand/regression/coefficients", hand->shape.regression.coefficients);
    f.Add("hand/param_scale", hand->param_scale);
  }
  return f.Hex();
}

void CheckModelsMatch(const Dictionary& dictionary, const std::string& fingerprint, const std::string& where) {
  if (dictionary.models_fingerprint == fingerprint) return;
  throw InvalidInput(where + ": the dictionary was built with models " + dictionary.models_fingerprint.substr(0, 16) +
                     "…, not with these models (" + fingerprint.substr(0, 16) +
                     "…): its parameters mean nothing under other models; rebuild it with csw dict build");
}

void AppendMarkerJumps(const MarkerArray& markers, std::vector<double>* jumps) {
  for (int64_t f = 1; f < markers.frames(); ++f) {
    for (int64_t m = 0; m < markers.markers(); ++m) {
      if (!markers.Visible(f - 1, m) || !markers.Visible(f, m)) continue;
      const float* a = markers.at(f - 1, m);
      const float* b = markers.at(f, m);
      const double dx = double(b[0]) - a[0], dy = double(b[1]) - a[1], dz = double(b[2]) - a[2];
      jumps->push_back(std::sqrt(dx * dx + dy * dy + dz * dz));
    }
  }
}

double Quantile(std::vector<double>& values, double q) {
  if (values.empty()) return kNaN;
  std::sort(values.begin(), values.end());
  const double pos = std::clamp(q, 0.0, 1.0) * static_cast<double>(values.size() - 1);
  const size_t i = static_cast<size_t>(std::floor(pos));
  const size_t j = std::min(i + 1, values.size() - 1);
  return values[i] + (pos - static_cast<double>(i)) * (values[j] - values[i]);
}

}  // namespace csw::dict
