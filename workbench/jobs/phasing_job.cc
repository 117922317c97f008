#include "workbench/jobs/phasing_job.h"

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <map>
#include <optional>
#include <sstream>

#include "analysis/keys/hand_features.h"
#include "analysis/keys/key_decoding.h"
#include "analysis/keys/key_model.h"
#include "analysis/keys/key_timing.h"
#include "analysis/phasing/movement_timing.h"
#include "analysis/phasing/phasing_stats.h"
#include "analysis/phasing/posterior_landmarks.h"
#include "core/error.h"
#include "core/markerset.h"
#include "io/corpus/corpus.h"
#include "io/models/model_file.h"
#include "synth/phasing.h"
#include "synth/phone_symbols.h"
#include "workbench/jobs/figures.h"
#include "workbench/jobs/job_util.h"
#include "workbench/jobs/take_data.h"
#include "workbench/jobs/take_selection.h"
#include "workbench/jobs/tier_util.h"

namespace csw::jobs {

namespace fs = std::filesystem;
using nlohmann::json;

std::string PhasingOptions::Check() const {
  if (corpus.empty()) return "no corpus given";
  if (keys.empty()) return "--keys must name a model file with a key model (csw keys train)";
  PhoneSymbols s;
  if (!ParsePhoneSymbols(symbols, &s))
    return "--symbols must be auto, ipa, mfa, xsampa or sppas, not '" + symbols + "'";
  if (phones.empty()) return "--phones must name the phone tier";
  if (targets != "auto" && targets != "labels" && targets != "aligned")
    return "--targets must be auto, labels or aligned, not '" + targets + "'";
  return "";
}

namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
// Changes whose rough target is within this of a neighbouring key's are left
// out of the kinematic statistics (the key is only approached).
constexpr double kApproachedS = 0.05;
constexpr double kMaxPlacementTimeSdS = 0.008;

// The true gesture times of a simulated take (<dir>/<take>.truth.json), matched
// to the cued keys by position when both sequences have the same codes; else
// nullopt with the reason in *why.
std::optional<std::vector<KeyTiming>> ReadTruth(const std::string& dir, const std::string& take,
                                                const std::vector<Key>& keys, std::string* why) {
  // A take version made by csw clean or csw invert --fill ("<take>.filled")
  // shares the truth of the take it was made from.
  fs::path path = fs::path(dir) / (take + ".truth.json");
  if (const size_t dot = take.find(".filled"); !fs::exists(path) && dot != std::string::npos)
    path = fs::path(dir) / (take.substr(0, dot) + ".truth.json");
  std::ifstream in(path);
  if (!in) {
    *why = path.string() + ": not found";
    return std::nullopt;
  }
  json j;
  try {
    in >> j;
  } catch (const json::exception& e) {
    throw ParseError(Location{path.string(), std::nullopt, std::nullopt}, std::string("not JSON: ") + e.what());
  }
  if (!j.contains("keys") || !j["keys"].is_array())
    throw ParseError(Location{path.string(), std::nullopt, std::nullopt}, "no \"keys\" array");
  const json& tk = j["keys"];
  if (tk.size() != keys.size()) {
    *why =
        path.string() + ": " + std::to_string(tk.size()) + " keys, the phone tier cues " + std::to_string(keys.size());
    return std::nullopt;
  }
  std::vector<KeyTiming> out(keys.size());
  for (size_t i = 0; i < keys.size(); ++i) {
    const json& k = tk[i];
    if (k.value("code", std::string()) != keys[i].Code()) {
      *why = path.string() + ": key " + std::to_string(i) + " is " + k.value("code", std::string("?")) +
             ", the phone tier cues " + keys[i].Code();
      return std::nullopt;
    }
    try {
      out[i].placement_start_s = k.at("placement_start_s").get<double>();
      out[i].placement_target_s = k.at("placement_target_s").get<double>();
      out[i].shape_start_s = k.at("shape_start_s").get<double>();
      out[i].shape_target_s = k.at("shape_target_s").get<double>();
    } catch (const json::exception& e) {
      throw ParseError(Location{path.string(), std::nullopt, std::nullopt},
                       "key " + std::to_string(i) + ": " + e.what());
    }
  }
  return out;
}

double Time(int64_t frame, double rate) { return static_cast<double>(frame) / rate; }

// Rough target frames from a point tier of key codes whose sequence is the cued
// keys' (all of them, or all but the leading rest): label i -> key i (+1).
// Returns false (and leaves `frames` alone) when the sequences differ.
bool TargetsFromLabels(const LabelTier* tier, const std::vector<Key>& keys, double rate, std::vector<int64_t>* frames) {
  if (tier == nullptr || tier->labels.empty()) return false;
  std::vector<std::string> codes;
  for (const Key& k : keys) codes.push_back(k.Code());
  for (size_t offset : {size_t{0}, size_t{1}}) {
    if (tier->labels.size() + offset != codes.size()) continue;
    bool same = true;
    for (size_t i = 0; i < tier->labels.size() && same; ++i) same = tier->labels[i].text == codes[i + offset];
    if (!same) continue;
    for (size_t i = 0; i < tier->labels.size(); ++i)
      (*frames)[i + offset] =
          static_cast<int64_t>(std::llround(0.5 * (tier->labels[i].start_s + tier->labels[i].end_s) * rate));
    return true;
  }
  return false;
}

// Mean and sd (ms) of estimate − truth over the rows of one type, component and landmark.
json ErrorSummary(const std::vector<phasing::PhasingKeyRow>& rows, phasing::PhasingMethod method) {
  json out;
  for (KeyType type : {KeyType::kCV, KeyType::kVowelAlone, KeyType::kConsonantAlone}) {
    json tj;
    for (int c = 0; c < 2; ++c)
      for (int l = 0; l < 2; ++l) {
        std::vector<double> e;
        for (const auto& r : rows) {
          if (r.type != type) continue;
          const KeyTiming& m = method == phasing::PhasingMethod::kKinematic ? r.kinematic : r.posterior;
          const double est = c == 0 ? (l == 0 ? m.placement_start_s : m.placement_target_s)
                                    : (l == 0 ? m.shape_start_s : m.shape_target_s);
          const double tru = c == 0 ? (l == 0 ? r.truth.placement_start_s : r.truth.placement_target_s)
                                    : (l == 0 ? r.truth.shape_start_s : r.truth.shape_target_s);
          if (std::isfinite(est) && std::isfinite(tru)) e.push_back(1000 * (est - tru));
        }
        const phasing::TimeSummary s = phasing::SummariseTimes(e);
        tj[c == 0 ? "placement" : "shape"][l == 0 ? "onset" : "target"] = {
            {"mean_ms", s.mean_ms}, {"sd_ms", s.sd_ms}, {"ci95_ms", s.ci95_ms}, {"count", s.count}};
      }
    out[phasing::KeyTypeLabel(type)] = tj;
  }
  return out;
}

}  // namespace

json Phasing(const PhasingOptions& options, Progress& progress) {
  if (const std::string why = options.Check(); !why.empty()) throw UsageError(why);
  PhoneSymbols symbols = PhoneSymbols::kAuto;
  ParsePhoneSymbols(options.symbols, &symbols);
  const ModelFile mf = LoadModelFile(options.keys);
  if (!mf.keys) throw InvalidInput(options.keys + ": no key model (/keys) in this model file (csw keys train)");
  const keys::KeyModel& model = *mf.keys;
  const PhasingModel reference = options.reference.empty() ? PhasingModel{} : LoadPhasingModel(options.reference);
  std::optional<MarkerSet> given;
  if (!options.markerset.empty()) given = LoadMarkerSet(options.markerset);
  if (!options.figures.empty()) {
    figures::Require();
    fs::create_directories(options.figures);
  }

  const Corpus corpus = Corpus::Open(options.corpus);
  const std::vector<TakeRange> ranges = SelectCorpusTakes(corpus, options.takes);
  json result = {{"corpus", options.corpus}, {"keys", options.keys}, {"takes", json::array()}};
  std::vector<phasing::PhasingKeyRow> rows;
  json figure_files = json::array();
  bool any_truth = false;
  phasing::MovementFitOptions placement_fit, shape_fit;
  shape_fit.path_terms = 3;  // distances are nonlinear in the joint angles: curved paths (docs/analysis-phasing.md)
  // Placement onsets of overlapping keys are often not determined by the data
  // (neighbouring gestures trade parts of their movements with the same
  // residual): those whose onset or target standard error exceeds 8 ms are
  // left out and counted ("undetermined"; docs/analysis-phasing.md).
  placement_fit.max_time_sd_s = kMaxPlacementTimeSdS;
  // The limit in effect per capture rate (tightened above the reference rate).
  std::map<double, double> gate_by_rate;
  json left_out = {{"placement", json::object()}, {"shape", json::object()}};
  for (size_t i = 0; i < ranges.size(); ++i) {
    const TakeRange& range = ranges[i];
    progress.Update("phasing: " + range.take, static_cast<double>(i) / static_cast<double>(ranges.size()));
    progress.CheckCancel();
    const std::string where = corpus.path() + ": take '" + range.take + "'";
    const Take take = corpus.LoadTake(range.take);
    if (range.first != 0 || range.count != take.frames())
      throw UsageError("csw phasing works on whole takes: '" + range.spec + "' selects frames of take '" + range.take +
                       "'");
    if (!(take.rate_hz > 0)) throw InvalidInput(where + ": no frame rate");
    const double rate = take.rate_hz;
    const double gate_s = phasing::EffectiveTimeSdLimit(placement_fit, rate);
    gate_by_rate[rate] = gate_s;
    const LabelTier* phone_tier = FindTier(take.tiers, options.phones);
    if (phone_tier == nullptr)
      throw InvalidInput(where + ": no phone tier '" + options.phones + "' (tiers: " + TierNames(take.tiers) +
                         "); name it with --phones");
    const CuedTier cued = CuePhoneTier(*phone_tier, symbols, where + ": tier '" + options.phones + "'");
    const std::vector<Key>& cue_keys = cued.keys;

    std::optional<MarkerSet> set = given;
    if (!set) {
      const std::string text = corpus.TakeMarkerSet(range.take);
      if (!text.empty()) set = ParseMarkerSet(text, where + " (its marker set)");
    }
    MarkerBinding binding;
    if (set) {
      binding = BindMarkerSet(*set, take.marker_names, false, where);
    } else {
      for (size_t m = 0; m < take.marker_names.size(); ++m) binding.index[take.marker_names[m]] = static_cast<int>(m);
    }
    const keys::HandFeatures features =
        keys::ComputeHandFeatures(take.markers, binding, model.layout, model.head_reference);
    const keys::KeyPosteriors post = keys::ScoreFrames(model, features);
    std::vector<keys::ExpectedKey> expected;
    for (const Key& k : cue_keys) expected.push_back({k.placement, k.shape});
    // Rough targets without labels: the aligned decoding's kinematic target
    // times (analysis/keys/key_timing.h) for the components that change; a
    // held component keeps its arrival in the key's own segment (the timed
    // decoding repeats the previous change's time there, which the movement
    // fits below would read as an approached key). On six virtual-cuer
    // sentences: CV shape target +0.9 ms, placement target -6.4 ms, against
    // -4.7 / -13.5 ms from the segment arrivals alone.
    std::vector<keys::DecodedKey> aligned = keys::DecodeAligned(post, expected, rate);
    {
      const std::vector<keys::TimedKey> timed = keys::DecodeAlignedTimed(model, features, post, expected, rate);
      for (size_t k = 0; k < aligned.size(); ++k) {
        if (timed[k].shape.changes) aligned[k].shape_target_frame = timed[k].key.shape_target_frame;
        if (timed[k].placement.changes) aligned[k].placement_target_frame = timed[k].key.placement_target_frame;
      }
    }
    if (aligned.size() != cue_keys.size())
      throw InvalidInput(where + ": the aligned decoding gave " + std::to_string(aligned.size()) + " keys for " +
                         std::to_string(cue_keys.size()) + " expected");

    // Rough target times: the take's labelled targets when their codes follow
    // the cued keys (csw keys train's label tiers), else the aligned decoding's.
    std::vector<int64_t> shape_frames, placement_frames;
    for (const auto& a : aligned) {
      shape_frames.push_back(a.shape_target_frame);
      placement_frames.push_back(a.placement_target_frame);
    }
    std::string targets = "aligned decoding";
    bool placement_labelled = false;  // the placement seeds are a placement tier's
    if (options.targets != "aligned") {
      const bool shape_ok = TargetsFromLabels(FindTier(take.tiers, options.labels), cue_keys, rate, &shape_frames);
      const LabelTier* pt = FindTier(take.tiers, options.label_placement);
      const bool placement_ok = TargetsFromLabels(pt != nullptr ? pt : FindTier(take.tiers, options.labels), cue_keys,
                                                  rate, &placement_frames);
      placement_labelled = placement_ok && pt != nullptr;
      if (shape_ok && placement_ok)
        targets = "labels";
      else if (shape_ok || placement_ok)
        targets = "labels (one component) and aligned decoding";
      else if (options.targets == "labels")
        throw InvalidInput(where + ": the label tiers '" + options.labels + "' / '" + options.label_placement +
                           "' do not follow the cued keys; use --targets aligned");
    }

    std::string truth_why;
    std::optional<std::vector<KeyTiming>> truth;
    if (!options.truth.empty()) truth = ReadTruth(options.truth, range.take, cue_keys, &truth_why);
    any_truth = any_truth || truth.has_value();

    // Kinematic landmarks, over the whole take at once (EstimateMovements: each
    // movement fitted with its neighbours, then refitted with the neighbours
    // started from their own estimates). Rough target times must increase:
    // a key whose rough target is not 30 ms after the previous key's is moved
    // there (overlapping keys can reverse their targets), and changes whose
    // rough target is within kApproachedS of a neighbour's (keys only
    // approached when syllables follow fast) are left out of the statistics.
    const size_t nk = cue_keys.size();
    auto increasing = [&](const std::vector<int64_t>& frames) {
      std::vector<double> t(nk);
      for (size_t k = 0; k < nk; ++k) {
        t[k] = Time(frames[k], rate);
        if (k > 0) t[k] = std::max(t[k], t[k - 1] + 0.03);
      }
      return t;
    };
    const std::vector<double> shape_rough = increasing(shape_frames);
    std::vector<double> placement_rough = increasing(placement_frames);
    json reseeded = nullptr;
    auto approached = [&](const std::vector<double>& rough, size_t k) {
      return rough[k] < rough[k - 1] + kApproachedS || (k + 1 < nk && rough[k + 1] < rough[k] + kApproachedS);
    };
    std::vector<phasing::MovementEstimate> shape_est(nk), placement_est(nk);
    if (nk >= 2) {
      const phasing::SampledTrajectory shape_traj{&features.distances, rate, 0.0};
      shape_est = phasing::EstimateMovements(shape_traj, shape_rough, shape_fit);
      // Placement point: the tip of the longest extended finger (the key model's
      // layout says which finger each shape extends furthest), blended from one
      // finger to the other over each measured shape movement that changes it
      // (minimum-jerk weight from its onset to its target): without the blend
      // the switch of finger is a shape-timed jump of the placement path.
      const Eigen::MatrixXd& index_tip = features.index_tip;
      const Eigen::MatrixXd& middle_tip = features.middle_tip;
      Eigen::MatrixXd placement_point = middle_tip;
      for (int64_t f = 0; f < placement_point.rows(); ++f) {
        const double t = Time(f, rate);
        double w = model.IndexFinger(cue_keys[0].shape) ? 1.0 : 0.0;
        for (size_t k = 1; k < nk; ++k) {
          const double dw = (model.IndexFinger(cue_keys[k].shape) ? 1.0 : 0.0) -
                            (model.IndexFinger(cue_keys[k - 1].shape) ? 1.0 : 0.0);
          if (dw == 0.0) continue;
          const bool ok = shape_est[k].fitted;
          const double on = ok ? shape_est[k].onset_s : shape_rough[k - 1];
          const double tg = ok ? shape_est[k].target_s : shape_rough[k];
          const double tau = std::clamp((t - on) / std::max(tg - on, 1e-3), 0.0, 1.0);
          w += dw * tau * tau * tau * (10.0 - 15.0 * tau + 6.0 * tau * tau);
        }
        if (w >= 1.0)
          placement_point.row(f) = index_tip.row(f);
        else if (w > 0.0)
          placement_point.row(f) = (1.0 - w) * middle_tip.row(f) + w * index_tip.row(f);
      }
      const phasing::SampledTrajectory placement_traj{&placement_point, rate, 0.0};
      placement_est = phasing::EstimateMovements(placement_traj, placement_rough, placement_fit);
      // Placement seeds that are not a placement tier's (the shape targets, or
      // the aligned decoding's) are off by the placement's own lag, and the
      // fits stay near their seeds (target_tolerance_s): refit once from the
      // first fit's targets, the keys it left unusable moved by the median
      // shift of the others (docs/analysis-phasing.md: on 81 simulated takes
      // the CV placement target is 26.8 ms after A1 seeded at the shape
      // targets, 38.1 ms refitted, 40.4 ms from the placement tier).
      if (!placement_labelled) {
        std::vector<double> shifts;
        for (size_t k = 1; k < nk; ++k)
          if (placement_est[k].Usable()) shifts.push_back(placement_est[k].target_s - placement_rough[k]);
        if (!shifts.empty()) {
          std::nth_element(shifts.begin(), shifts.begin() + static_cast<std::ptrdiff_t>(shifts.size() / 2),
                           shifts.end());
          const double median = shifts[shifts.size() / 2];
          std::vector<double> again(nk);
          for (size_t k = 0; k < nk; ++k) {
            again[k] = k > 0 && placement_est[k].Usable() ? placement_est[k].target_s : placement_rough[k] + median;
            if (k > 0) again[k] = std::max(again[k], again[k - 1] + 0.03);
          }
          placement_rough = std::move(again);
          placement_est = phasing::EstimateMovements(placement_traj, placement_rough, placement_fit);
          reseeded = {{"median_shift_ms", 1000.0 * median}, {"refitted_from", static_cast<int64_t>(shifts.size())}};
        }
      }
    }
    // Why changed components got no kinematic landmarks.
    auto tally = [&](const char* component, const char* why) {
      left_out[component][why] = left_out[component].value(why, 0) + 1;
    };
    auto use = [&](const phasing::MovementEstimate& m, const std::vector<double>& rough, size_t k,
                   const char* component) {
      if (approached(rough, k)) {
        tally(component, "approached");
        return false;
      }
      if (!m.fitted) {
        tally(component, "not_fitted");
        return false;
      }
      if (!m.moved) {
        tally(component, "no_change");
        return false;
      }
      if (!m.determined) {
        tally(component, "undetermined");
        return false;
      }
      tally(component, "measured");
      return true;
    };
    int measured = 0;
    for (size_t k = 1; k < nk; ++k) {
      const Key& key = cue_keys[k];
      if (key.type == KeyType::kRest) continue;
      phasing::PhasingKeyRow row;
      row.take = range.take;
      row.key_index = static_cast<int>(k);
      row.code = key.Code();
      row.type = key.type;
      row.a1_s = key.a1_s;
      row.vowel_onset_s = phasing::VowelOnset(key, cued.mapped.phones);
      if (truth) row.truth = (*truth)[k];
      const size_t kn = k + 1 < nk ? k + 1 : k;
      const double end_s = take.duration_s();
      auto next_time = [&](int64_t frame, double cur_s) {
        const double t = Time(frame, rate);
        return t > cur_s + 1e-6 ? t : std::min(end_s, cur_s + 0.3);
      };
      if (cue_keys[k - 1].placement != key.placement) {
        if (use(placement_est[k], placement_rough, k, "placement")) {
          row.kinematic.placement_start_s = placement_est[k].onset_s;
          row.kinematic.placement_target_s = placement_est[k].target_s;
        }
        const double p0 = Time(placement_frames[k - 1], rate), p1 = Time(placement_frames[k], rate);
        const double p2 = next_time(placement_frames[kn], p1);
        const phasing::PosteriorLandmarks pl =
            p0 < p1 && p1 < p2 ? phasing::FindPosteriorLandmarks(post.placement, rate, 0.0, key.placement, p0, p2)
                               : phasing::PosteriorLandmarks{};
        if (pl.found) {
          row.posterior.placement_start_s = pl.onset_s;
          row.posterior.placement_target_s = pl.target_s;
        }
      } else {
        row.truth.placement_start_s = row.truth.placement_target_s = kNaN;
      }
      if (cue_keys[k - 1].shape != key.shape) {
        if (use(shape_est[k], shape_rough, k, "shape")) {
          row.kinematic.shape_start_s = shape_est[k].onset_s;
          row.kinematic.shape_target_s = shape_est[k].target_s;
        }
        const double s0 = Time(shape_frames[k - 1], rate), s1 = Time(shape_frames[k], rate);
        const double s2 = next_time(shape_frames[kn], s1);
        const phasing::PosteriorLandmarks pl =
            s0 < s1 && s1 < s2 ? phasing::FindPosteriorLandmarks(post.shape, rate, 0.0, key.shape, s0, s2)
                               : phasing::PosteriorLandmarks{};
        if (pl.found) {
          row.posterior.shape_start_s = pl.onset_s;
          row.posterior.shape_target_s = pl.target_s;
        }
      } else {
        row.truth.shape_start_s = row.truth.shape_target_s = kNaN;
      }
      ++measured;
      rows.push_back(row);
    }
    json tj = {{"take", range.spec},
               {"keys", measured},
               {"rough_targets", targets},
               {"placement_reseeded", reseeded},
               {"placement_time_sd_limit_ms", 1000.0 * gate_s},
               {"phone_warnings", cued.mapped.warnings}};
    if (!options.truth.empty()) tj["truth"] = truth ? "matched" : truth_why;
    result["takes"].push_back(tj);

    if (!options.figures.empty()) {
      std::vector<LabelTier> tiers{*phone_tier, cued.tier};
      std::vector<float> audio;
      if (!take.audio.samples.empty()) {
        audio.resize(static_cast<size_t>(take.audio.frames()));
        for (size_t s = 0; s < audio.size(); ++s)
          audio[s] = take.audio.samples[s * static_cast<size_t>(take.audio.channels)];
      }
      report::PosteriorLane shape_lane{"hand shape", {}, post.shape};
      for (int c = 0; c < post.shape.cols(); ++c) shape_lane.classes.push_back(std::to_string(c));
      report::PosteriorLane placement_lane{"hand placement", {}, post.placement};
      for (int c = 0; c < post.placement.cols(); ++c) placement_lane.classes.push_back(std::to_string(c));
      const std::string path = (fs::path(options.figures) / ("gestural_score_" + range.take + ".png")).string();
      figures::SaveGesturalScore(path, "Gestural score: " + range.take, audio, take.audio.rate_hz, 0.0,
                                 {shape_lane, placement_lane}, rate, tiers, 0.0, take.duration_s());
      figure_files.push_back(path);
    }
  }

  using phasing::PhasingMethod;
  using phasing::PhasingReference;
  result["kinematic"] =
      phasing::PhasingSummaryToJson(phasing::SummarisePhasing(rows, PhasingMethod::kKinematic, PhasingReference::kA1));
  result["posterior"] =
      phasing::PhasingSummaryToJson(phasing::SummarisePhasing(rows, PhasingMethod::kPosterior, PhasingReference::kA1));
  result["relative_to_vowel_onset"] = {
      {"kinematic", phasing::PhasingSummaryToJson(
                        phasing::SummarisePhasing(rows, PhasingMethod::kKinematic, PhasingReference::kVowelOnset))},
      {"posterior", phasing::PhasingSummaryToJson(
                        phasing::SummarisePhasing(rows, PhasingMethod::kPosterior, PhasingReference::kVowelOnset))}};
  if (any_truth) {
    result["truth"] =
        phasing::PhasingSummaryToJson(phasing::SummarisePhasing(rows, PhasingMethod::kTruth, PhasingReference::kA1));
    result["errors_vs_truth"] = {{"kinematic", ErrorSummary(rows, PhasingMethod::kKinematic)},
                                 {"posterior", ErrorSummary(rows, PhasingMethod::kPosterior)}};
  }
  if (!options.csv.empty()) {
    std::string text = phasing::PhasingCsvHeader() + "\n";
    for (const auto& r : rows) text += phasing::PhasingCsvRow(r) + "\n";
    std::ofstream out(options.csv);
    if (!out) throw IoError(options.csv, "cannot open for writing");
    out << text;
    out.close();
    if (!out) throw IoError(options.csv, "write failed");
    result["csv"] = options.csv;
  }
  if (!options.figures.empty()) {
    for (PhasingMethod method : {PhasingMethod::kKinematic, PhasingMethod::kPosterior}) {
      std::vector<report::HistogramPanel> panels;
      for (KeyType type : {KeyType::kCV, KeyType::kVowelAlone, KeyType::kConsonantAlone})
        for (phasing::Component c : {phasing::Component::kPlacement, phasing::Component::kShape})
          for (phasing::Landmark l : {phasing::Landmark::kOnset, phasing::Landmark::kTarget}) {
            report::HistogramPanel p;
            const bool placement = c == phasing::Component::kPlacement, onset = l == phasing::Landmark::kOnset;
            p.title = std::string(phasing::KeyTypeLabel(type)) + (placement ? " placement " : " shape ") +
                      (onset ? "onset" : "target");
            p.values_ms = phasing::RelativeTimesMs(rows, method, PhasingReference::kA1, type, c, l);
            const MovementTiming& law = placement ? PlacementTiming(reference, type) : ShapeTiming(reference, type);
            p.reference_ms = 1000 * (onset ? law.start_mean_s : law.target_mean_s);
            p.reference_name = options.reference.empty() ? "Attina 2005 (mean)" : "reference model (mean)";
            panels.push_back(std::move(p));
          }
      const bool kin = method == PhasingMethod::kKinematic;
      const std::string path =
          (fs::path(options.figures) / (kin ? "phasing_kinematic.png" : "phasing_posterior.png")).string();
      figures::SaveHistograms(path,
                              kin ? "Phasing, kinematic landmarks (minimum-jerk fit)"
                                  : "Phasing, posterior landmarks (dominance onset, peak)",
                              panels, 20.0, "time from A1 (ms)");
      figure_files.push_back(path);
    }
    result["figures"] = figure_files;
  }
  result["kinematic_changes"] = left_out;
  json by_rate = json::array();
  for (const auto& [rate_hz, limit_s] : gate_by_rate)
    by_rate.push_back({{"rate_hz", rate_hz}, {"limit_ms", 1000.0 * limit_s}});
  result["placement_time_sd_gate"] = {{"limit_ms", 1000.0 * placement_fit.max_time_sd_s},
                                      {"reference_rate_hz", placement_fit.time_sd_reference_rate_hz},
                                      {"by_rate", by_rate}};
  result["keys_measured"] = rows.size();
  return result;
}

std::string PhasingText(const json& r) {
  std::ostringstream o;
  o << "phasing of " << r["keys_measured"].get<int64_t>() << " keys in " << r["takes"].size()
    << " takes (ms from A1: mean ± sd [95 % CI half-width], n)\n";
  auto line = [&](const json& s) {
    std::ostringstream l;
    if (s["count"].get<int>() == 0) return std::string("-");
    l.setf(std::ios::fixed);
    l.precision(1);
    l << s["mean_ms"].get<double>() << " ± " << s["sd_ms"].get<double>() << " [" << s["ci95_ms"].get<double>()
      << "] n=" << s["count"].get<int>();
    return l.str();
  };
  for (const char* method : {"kinematic", "posterior", "truth"}) {
    if (!r.contains(method)) continue;
    o << method << ":\n";
    for (const char* type : {"CV", "V", "C"})
      for (const char* c : {"placement", "shape"}) {
        const json& s = r[method][type][c];
        o << "  " << type << " " << c << ": onset " << line(s["onset"]) << "; target " << line(s["target"]) << "\n";
      }
  }
  if (r.contains("errors_vs_truth")) {
    o << "estimate - truth:\n";
    for (const char* method : {"kinematic", "posterior"})
      for (const char* type : {"CV", "V", "C"})
        for (const char* c : {"placement", "shape"}) {
          const json& s = r["errors_vs_truth"][method][type][c];
          o << "  " << method << " " << type << " " << c << ": onset " << line(s["onset"]) << "; target "
            << line(s["target"]) << "\n";
        }
  }
  if (r.contains("kinematic_changes")) {
    o << "kinematic landmarks of the changed components:";
    for (const char* c : {"placement", "shape"}) {
      o << " " << c;
      const json& t = r["kinematic_changes"][c];
      if (t.empty()) o << " none";
      for (const auto& [why, n] : t.items()) o << " " << why << " " << n.get<int64_t>();
      o << (std::string(c) == "placement" ? ";" : "\n");
    }
  }
  if (r.contains("placement_time_sd_gate")) {
    const json& g = r["placement_time_sd_gate"];
    std::ostringstream l;
    l.setf(std::ios::fixed);
    l.precision(1);
    l << "undetermined: placement onset or target standard error over " << g["limit_ms"].get<double>() << " ms";
    if (g["reference_rate_hz"].get<double>() > 0)
      l << " (× √(" << g["reference_rate_hz"].get<double>() << " Hz / rate) above "
        << g["reference_rate_hz"].get<double>() << " Hz)";
    for (const json& b : g["by_rate"])
      if (b["limit_ms"].get<double>() != g["limit_ms"].get<double>())
        l << "; " << b["limit_ms"].get<double>() << " ms at " << b["rate_hz"].get<double>() << " Hz";
    o << l.str() << "\n";
  }
  if (r.contains("csv")) o << "per-key CSV: " << r["csv"].get<std::string>() << "\n";
  if (r.contains("figures"))
    for (const json& f : r["figures"]) o << "figure: " << f.get<std::string>() << "\n";
  return o.str();
}

}  // namespace csw::jobs
