#include "workbench/jobs/keys_suggest_job.h"

#include <algorithm>
#include <cmath>
#include <fstream>
#include <optional>
#include <sstream>
#include <string>
#include <vector>

#include "analysis/keys/hand_features.h"
#include "core/error.h"
#include "core/labels.h"
#include "core/markerset.h"
#include "io/corpus/corpus.h"
#include "synth/phasing.h"
#include "synth/phone_symbols.h"
#include "workbench/jobs/job_util.h"
#include "workbench/jobs/take_data.h"
#include "workbench/jobs/take_selection.h"
#include "workbench/jobs/tier_util.h"

namespace csw::jobs {

using nlohmann::json;

std::string KeysSuggestOptions::Check() const {
  if (corpus.empty()) return "no corpus given";
  PhoneSymbols s;
  if (!ParsePhoneSymbols(symbols, &s))
    return "--symbols must be auto, ipa, mfa, xsampa or sppas, not '" + symbols + "'";
  if (phones.empty()) return "--phones must name the phone tier";
  if (tier.empty() || placement_tier.empty()) return "the suggestion tiers need names";
  if (tier == placement_tier) return "the shape and placement suggestion tiers must differ";
  for (const std::string* t : {&tier, &placement_tier})
    if (*t == phones || *t == labels || *t == label_placement)
      return "the suggestion tier '" + *t + "' would replace the phone or label tier of that name";
  if (const std::string why = suggest.Check(); !why.empty()) return why;
  return "";
}

namespace {

double Round(double v, double step) { return std::isfinite(v) ? std::round(v / step) * step : v; }

// Mean and max of |values| (ms), {null, null} when empty.
json MeanMaxMs(const std::vector<double>& seconds) {
  if (seconds.empty()) return {{"mean", nullptr}, {"max", nullptr}, {"count", 0}};
  double sum = 0, max = 0;
  for (double s : seconds) {
    sum += std::abs(s);
    max = std::max(max, std::abs(s));
  }
  return {{"mean", Round(1000 * sum / static_cast<double>(seconds.size()), 0.1)},
          {"max", Round(1000 * max, 0.1)},
          {"count", seconds.size()}};
}

// Each suggestion against the label of the same code nearest to it (within 0.3 s).
json CompareWithLabels(const std::vector<std::pair<double, std::string>>& suggested, const LabelTier& labels) {
  std::vector<double> errors;
  int within = 0;
  for (const auto& [time, code] : suggested) {
    double best = 0.3;
    bool found = false;
    for (const Label& l : labels.labels) {
      if (l.text != code) continue;
      const double t = 0.5 * (l.start_s + l.end_s);
      if (std::abs(t - time) <= best) {
        best = std::abs(t - time);
        found = true;
      }
    }
    if (!found) continue;
    errors.push_back(best);
    if (best <= 0.040 + 1e-9) ++within;
  }
  json j = MeanMaxMs(errors);
  j["matched"] = errors.size();
  j["suggested"] = suggested.size();
  j["within_40ms"] = within;
  return j;
}

}  // namespace

json KeysSuggest(const KeysSuggestOptions& options, Progress& progress) {
  if (const std::string why = options.Check(); !why.empty()) throw UsageError(why);
  PhoneSymbols symbols = PhoneSymbols::kAuto;
  ParsePhoneSymbols(options.symbols, &symbols);
  const PhasingModel phasing = options.phasing.empty() ? PhasingModel{} : LoadPhasingModel(options.phasing);
  std::optional<MarkerSet> given;
  if (!options.markerset.empty()) given = LoadMarkerSet(options.markerset);
  nlohmann::json layout_section;
  if (!options.layout.empty()) {
    std::ifstream in(options.layout);
    if (!in) throw IoError(options.layout, "cannot open the hand-layout file");
    try {
      in >> layout_section;
    } catch (const nlohmann::json::exception& e) {
      throw ParseError(Location{options.layout, std::nullopt, std::nullopt}, std::string("not JSON: ") + e.what());
    }
    if (layout_section.contains("hand_layout")) layout_section = layout_section["hand_layout"];
  }

  const Corpus corpus = Corpus::Open(options.corpus);
  const std::vector<TakeRange> ranges = SelectCorpusTakes(corpus, options.takes);
  json result = {{"corpus", options.corpus},
                 {"tiers", {options.tier, options.placement_tier}},
                 {"dry_run", options.dry_run},
                 {"takes", json::array()}};
  std::vector<std::pair<std::string, std::vector<LabelTier>>> writes;
  int64_t all_keys = 0, all_suggested = 0;
  for (size_t i = 0; i < ranges.size(); ++i) {
    const TakeRange& range = ranges[i];
    progress.Update("keys suggest: " + range.take, static_cast<double>(i) / static_cast<double>(ranges.size()));
    progress.CheckCancel();
    const std::string where = corpus.path() + ": take '" + range.take + "'";
    Take take = corpus.LoadTake(range.take);
    if (range.first != 0 || range.count != take.frames())
      throw UsageError("csw keys suggest works on whole takes: '" + range.spec + "' selects frames of take '" +
                       range.take + "'");
    if (!(take.rate_hz > 0)) throw InvalidInput(where + ": no frame rate");
    const LabelTier* phone_tier = FindTier(take.tiers, options.phones);
    if (phone_tier == nullptr)
      throw InvalidInput(where + ": no phone tier '" + options.phones + "' (tiers: " + TierNames(take.tiers) +
                         "); name it with --phones");
    const CuedTier cued = CuePhoneTier(*phone_tier, symbols, where + ": tier '" + options.phones + "'");
    const std::vector<KeyTiming> timing = MeanTiming(cued.keys, phasing);

    // The marker set: given, or the one the corpus remembers.
    std::optional<MarkerSet> set = given;
    if (!set) {
      const std::string text = corpus.TakeMarkerSet(range.take);
      if (text.empty())
        throw InvalidInput(where + ": the corpus remembers no marker set for this take; give one with --markerset");
      set = ParseMarkerSet(text, where + " (its marker set)");
    }
    const MarkerBinding binding = BindMarkerSet(*set, take.marker_names, false, where);
    const keys::HandLayout layout = options.layout.empty()
                                        ? keys::DeriveHandLayout(*set, take.markers, binding, range.take)
                                        : keys::ParseHandLayout(layout_section, *set, options.layout);
    const Eigen::Matrix3Xd head = keys::HeadReference(take.markers, binding, layout);
    const keys::HandFeatures features = keys::ComputeHandFeatures(take.markers, binding, layout, head);

    const double rate = take.rate_hz;
    const Eigen::VectorXd shape_speed = analysis::FeatureSpeed(features.distances, rate, options.suggest.cutoff_hz);
    const Eigen::VectorXd index_speed = analysis::FeatureSpeed(features.index_tip, rate, options.suggest.cutoff_hz);
    const Eigen::VectorXd middle_speed = analysis::FeatureSpeed(features.middle_tip, rate, options.suggest.cutoff_hz);

    LabelTier shape_tier{options.tier, LabelTier::Kind::kPoint, 0.0, take.duration_s(), {}};
    LabelTier placement_tier{options.placement_tier, LabelTier::Kind::kPoint, 0.0, take.duration_s(), {}};
    json shape_missing = json::array(), placement_missing = json::array();
    std::vector<double> shape_offsets, placement_offsets;
    std::vector<std::pair<double, std::string>> shape_points, placement_points;
    // The keys asked for (the leading rest is not: the hand rests from the
    // start). A component that changes from the previous key moves to a new
    // target: those are suggested together, one call per speed series, so
    // that two successive changes never get the same speed minimum
    // (analysis/target_suggestion.h). A held component (same shape, or same
    // placement, as the previous key) has no movement of its own; it is
    // suggested alone, as before. Shape targets on the shape speed; placement
    // targets on the index tip's speed for shapes 1 and 6, else the middle tip's.
    std::vector<size_t> asked;
    bool cued_seen = false;
    for (size_t k = 0; k < cued.keys.size(); ++k) {
      if (cued.keys[k].type != KeyType::kRest) cued_seen = true;
      if (cued_seen) asked.push_back(k);
    }
    const int64_t n_keys = static_cast<int64_t>(asked.size());
    enum Series { kShape, kIndex, kMiddle };
    std::vector<double> moved_times[3];
    std::vector<std::pair<int, long>> shape_slot(asked.size()),
        placement_slot(asked.size());  // (series, position or -1)
    for (size_t i = 0; i < asked.size(); ++i) {
      const size_t k = asked[i];
      const Key& key = cued.keys[k];
      const bool shape_moves = k == 0 || key.shape != cued.keys[k - 1].shape;
      const bool placement_moves = k == 0 || key.placement != cued.keys[k - 1].placement;
      const int finger = key.shape == 1 || key.shape == 6 ? kIndex : kMiddle;
      shape_slot[i] = {kShape, shape_moves ? static_cast<long>(moved_times[kShape].size()) : -1L};
      if (shape_moves) moved_times[kShape].push_back(timing[k].shape_target_s);
      placement_slot[i] = {finger, placement_moves ? static_cast<long>(moved_times[finger].size()) : -1L};
      if (placement_moves) moved_times[finger].push_back(timing[k].placement_target_s);
    }
    const Eigen::VectorXd* speeds[3] = {&shape_speed, &index_speed, &middle_speed};
    std::vector<analysis::SuggestedTarget> moved[3];
    for (int series = 0; series < 3; ++series)
      moved[series] = analysis::SuggestTargetsFromSpeed(*speeds[series], rate, moved_times[series], options.suggest);
    auto suggestion = [&](const std::pair<int, long>& slot, double expected_s) {
      if (slot.second >= 0) return moved[slot.first][static_cast<size_t>(slot.second)];
      return analysis::SuggestTargetsFromSpeed(*speeds[slot.first], rate, {expected_s}, options.suggest)[0];
    };
    for (size_t i = 0; i < asked.size(); ++i) {
      const size_t k = asked[i];
      const Key& key = cued.keys[k];
      const std::string code = key.Code();
      const analysis::SuggestedTarget s = suggestion(shape_slot[i], timing[k].shape_target_s);
      const analysis::SuggestedTarget p = suggestion(placement_slot[i], timing[k].placement_target_s);
      if (s.frame >= 0) {
        shape_tier.labels.push_back({s.time_s, s.time_s, code});
        shape_offsets.push_back(s.offset_s);
        shape_points.emplace_back(s.time_s, code);
      } else {
        shape_missing.push_back(
            {{"key", k}, {"code", code}, {"expected_s", Round(s.expected_s, 1e-3)}, {"why", s.why}});
      }
      if (p.frame >= 0) {
        placement_tier.labels.push_back({p.time_s, p.time_s, code});
        placement_offsets.push_back(p.offset_s);
        placement_points.emplace_back(p.time_s, code);
      } else {
        placement_missing.push_back(
            {{"key", k}, {"code", code}, {"expected_s", Round(p.expected_s, 1e-3)}, {"why", p.why}});
      }
    }
    all_keys += n_keys;
    all_suggested += static_cast<int64_t>(shape_points.size());
    json tj = {{"take", range.spec},
               {"keys", n_keys},
               {"phone_warnings", cued.mapped.warnings},
               {"shape",
                {{"suggested", shape_points.size()},
                 {"missing", shape_missing},
                 {"offset_from_expected_ms", MeanMaxMs(shape_offsets)}}},
               {"placement",
                {{"suggested", placement_points.size()},
                 {"missing", placement_missing},
                 {"offset_from_expected_ms", MeanMaxMs(placement_offsets)}}}};
    if (const LabelTier* labels = FindTier(take.tiers, options.labels); labels != nullptr && !labels->labels.empty()) {
      const LabelTier* placement_labels = FindTier(take.tiers, options.label_placement);
      tj["labels"] = {{"shape", CompareWithLabels(shape_points, *labels)},
                      {"placement",
                       CompareWithLabels(placement_points, placement_labels != nullptr ? *placement_labels : *labels)}};
    }
    result["takes"].push_back(tj);
    std::vector<LabelTier> tiers;
    for (LabelTier& t : take.tiers)
      if (t.name != options.tier && t.name != options.placement_tier) tiers.push_back(std::move(t));
    tiers.push_back(std::move(shape_tier));
    tiers.push_back(std::move(placement_tier));
    writes.emplace_back(range.take, std::move(tiers));
  }
  result["keys"] = all_keys;
  result["suggested"] = all_suggested;
  result["tiers_written"] = !options.dry_run && !writes.empty();
  if (!options.dry_run && !writes.empty()) {
    progress.Update("writing tiers", 1.0);
    CorpusTransaction tx(options.corpus, progress);
    for (const auto& [name, tiers] : writes) tx.WriteTiers(name, tiers);
    tx.Commit();
  }
  return result;
}

std::string KeysSuggestText(const json& r) {
  std::ostringstream o;
  auto ms = [](const json& j) {
    std::ostringstream s;
    if (j["mean"].is_null()) return std::string("-");
    s << j["mean"].get<double>() << " ms mean, " << j["max"].get<double>() << " ms max";
    return s.str();
  };
  for (const json& t : r["takes"]) {
    o << "take " << t["take"].get<std::string>() << ": " << t["keys"].get<int64_t>() << " keys; shape targets "
      << t["shape"]["suggested"].get<int64_t>() << ", placement targets " << t["placement"]["suggested"].get<int64_t>()
      << " suggested\n";
    for (const char* c : {"shape", "placement"})
      for (const json& m : t[c]["missing"])
        o << "  no " << c << " target for key " << m["key"].get<int64_t>() << " (" << m["code"].get<std::string>()
          << ", expected at " << m["expected_s"].get<double>() << " s): " << m["why"].get<std::string>() << "\n";
    if (t.contains("labels"))
      for (const char* c : {"shape", "placement"}) {
        const json& l = t["labels"][c];
        o << "  " << c << " vs labels: " << l["matched"].get<int64_t>() << " of " << l["suggested"].get<int64_t>()
          << " matched, " << l["within_40ms"].get<int64_t>() << " within 40 ms, error " << ms(l) << "\n";
      }
  }
  o << r["suggested"].get<int64_t>() << " of " << r["keys"].get<int64_t>() << " keys have a suggested shape target";
  if (r["tiers_written"].get<bool>())
    o << "; tiers '" << r["tiers"][0].get<std::string>() << "' and '" << r["tiers"][1].get<std::string>()
      << "' written";
  o << "\n";
  return o.str();
}

}  // namespace csw::jobs
