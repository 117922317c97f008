#include "workbench/jobs/dict_job.h"

#include <cmath>
#include <cstdio>
#include <limits>
#include <map>
#include <memory>
#include <sstream>

#include "core/error.h"
#include "core/labels.h"
#include "io/corpus/corpus.h"
#include "io/dictionary/dictionary_file.h"
#include "io/models/model_file.h"
#include "synth/phone_symbols.h"
#include "workbench/jobs/job_util.h"
#include "workbench/jobs/model_config.h"
#include "workbench/jobs/parallel_for.h"
#include "workbench/jobs/take_data.h"
#include "workbench/jobs/tier_util.h"

namespace csw::jobs {

using nlohmann::json;

std::string DictBuildOptions::Check() const {
  if (corpus.empty()) return "no corpus given";
  if (models.empty()) return "no model file given (--models)";
  if (output.empty()) return "no output file given (-o)";
  if (tier.empty()) return "--tier must name a key tier";
  if (threads < 0) return "--threads must be >= 0";
  if (output == corpus || output == models || (!keys.empty() && output == keys)) {
    return "the output file must not be an input file";
  }
  if (const std::string why = dikeys.Check(); !why.empty()) return why;
  if (inversion.max_iterations < 1) return "--max-iterations must be >= 1";
  return "";
}

namespace {

struct TakeWork {
  TakeRange range;
  double rate_hz = 0;
  MarkerArray face_input, hand_input;
  dict::TakeSeries series;
  bool phasing = false;    // syllable onsets found
  int placement_lags = 0;  // keys whose placement target was found
  std::vector<dict::DikeyUnit> units;
  dict::ExtractionStats stats;
  std::vector<dict::DiphoneUnit> diphones;
  dict::ExtractionStats diphone_stats;
  std::vector<double> jumps;  // frame-to-frame jumps of the reconstructed model markers (mm)
};

// The phones of the phone tier (IPA, pauses "_"), on the range's clock: those
// entirely within [offset, last].
std::vector<Label> RangePhones(const Take& take, const std::string& phones, double offset, double last,
                               const std::string& where) {
  if (phones.empty()) return {};
  const LabelTier* tier = FindTier(take.tiers, phones);
  if (!tier || tier->kind != LabelTier::Kind::kInterval) return {};
  const MappedPhones mapped = MapPhoneTier(*tier, PhoneSymbols::kAuto, where + ": tier '" + phones + "'");
  std::vector<Label> out;
  for (const Phone& p : mapped.phones) {
    if (p.start_s < offset - 1e-9 || p.end_s > last + 1e-9) continue;
    out.push_back({p.start_s - offset, p.end_s - offset, p.ipa.empty() ? "_" : p.ipa});
  }
  return out;
}

std::vector<std::string> ModelNames(const std::vector<std::string>& a, const std::vector<std::string>& b,
                                    const std::vector<std::string>& c = {}) {
  std::vector<std::string> out = a;
  out.insert(out.end(), b.begin(), b.end());
  out.insert(out.end(), c.begin(), c.end());
  return out;
}

// The placement target of every mark (NaN when unknown). A placement tier
// with one mark per key, the same placements in the same order, is matched
// mark by mark (the placement may arrive before or after the shape target).
// Otherwise each key takes the placement mark with its placement nearest to
// it, strictly between the neighbouring keys' times, when no other key with
// that placement is nearer to that mark (repeated placements are ambiguous).
std::vector<double> PlacementTargets(const Take& take, const std::vector<KeyMark>& marks, const std::string& tier_name,
                                     const std::string& where) {
  std::vector<double> out(marks.size(), std::numeric_limits<double>::quiet_NaN());
  const LabelTier* tier = tier_name.empty() ? nullptr : FindTier(take.tiers, tier_name);
  if (!tier) return out;
  const std::vector<KeyMark> targets = ReadKeyTier(*tier, where + ", tier '" + tier_name + "'");
  bool in_order = targets.size() == marks.size();
  for (size_t k = 0; in_order && k < marks.size(); ++k) in_order = targets[k].code.placement == marks[k].code.placement;
  if (in_order) {
    for (size_t k = 0; k < marks.size(); ++k) out[k] = targets[k].time_s;
    return out;
  }
  auto nearest_key = [&](const KeyMark& t) {
    size_t best = marks.size();
    for (size_t k = 0; k < marks.size(); ++k) {
      if (marks[k].code.placement != t.code.placement) continue;
      if (best == marks.size() || std::abs(marks[k].time_s - t.time_s) < std::abs(marks[best].time_s - t.time_s))
        best = k;
    }
    return best;
  };
  for (size_t k = 0; k < marks.size(); ++k) {
    const double lo = k > 0 ? marks[k - 1].time_s : -std::numeric_limits<double>::infinity();
    const double hi = k + 1 < marks.size() ? marks[k + 1].time_s : std::numeric_limits<double>::infinity();
    double best = std::numeric_limits<double>::infinity();
    for (const KeyMark& t : targets) {
      if (t.code.placement != marks[k].code.placement || !(t.time_s > lo && t.time_s < hi) || nearest_key(t) != k)
        continue;
      if (std::abs(t.time_s - marks[k].time_s) < best) {
        best = std::abs(t.time_s - marks[k].time_s);
        out[k] = t.time_s;
      }
    }
  }
  return out;
}

// The syllable onset of every mark when the phone tier's cued keys (rests
// left out) have the marks' codes in order; empty otherwise.
// Each mark's syllable onset (A1) and key type, from the LfPC keys of the
// phone tier; both empty when the tier is absent or its keys are not the
// marks' codes in order.
struct Syllables {
  std::vector<double> onset_s;
  std::vector<KeyType> type;
};

Syllables SyllablesOfMarks(const Take& take, const std::vector<KeyMark>& marks, const std::string& phones,
                           const std::string& where) {
  if (phones.empty()) return {};
  const LabelTier* tier = FindTier(take.tiers, phones);
  if (!tier || tier->kind != LabelTier::Kind::kInterval) return {};
  const CuedTier cued = CuePhoneTier(*tier, PhoneSymbols::kAuto, where + ": tier '" + phones + "'");
  std::vector<const Key*> keys;
  for (const Key& k : cued.keys)
    if (!(k.placement == 0 && k.shape == 0)) keys.push_back(&k);
  Syllables out;
  out.onset_s.assign(marks.size(), std::numeric_limits<double>::quiet_NaN());
  out.type.assign(marks.size(), KeyType::kRest);
  size_t next = 0;
  for (size_t i = 0; i < marks.size(); ++i) {
    if (marks[i].code.IsRest()) continue;
    if (next >= keys.size() || keys[next]->placement != marks[i].code.placement ||
        keys[next]->shape != marks[i].code.shape) {
      return {};
    }
    out.type[i] = keys[next]->type;
    out.onset_s[i] = keys[next++]->a1_s;
  }
  if (next != keys.size()) return {};
  return out;
}

json Pairs(const std::vector<std::pair<int, int>>& pairs) {
  json a = json::array();
  for (const auto& [x, y] : pairs) a.push_back({x, y});
  return a;
}

json Counts(const Eigen::MatrixXi& m) {
  json rows = json::array();
  for (int r = 0; r < m.rows(); ++r) {
    json row = json::array();
    for (int c = 0; c < m.cols(); ++c) row.push_back(m(r, c));
    rows.push_back(row);
  }
  return rows;
}

int Present(const Eigen::MatrixXi& m) { return static_cast<int>((m.array() > 0).count()); }

}  // namespace

json CoverageJson(const dict::Coverage& c) {
  json d = json::object();
  for (const auto& [code, n] : c.dikeys) d[code] = n;
  return {
      {"units", c.units},
      {"placement",
       {{"counts", Counts(c.placement)}, {"present", Present(c.placement)}, {"missing", Pairs(c.MissingPlacements())}}},
      {"shape", {{"counts", Counts(c.shape)}, {"present", Present(c.shape)}, {"missing", Pairs(c.MissingShapes())}}},
      {"dikeys", d}};
}

json DictBuild(const DictBuildOptions& options, Progress& progress) {
  if (const std::string why = options.Check(); !why.empty()) throw UsageError(why);
  const ModelFile models = LoadModelFile(options.models);
  if (!models.face || !models.hand) {
    throw InvalidInput(options.models +
                       ": a dictionary needs a face model and a hand model (csw fit face, csw fit "
                       "hand); the file has " +
                       std::string(models.face   ? "a face model only"
                                   : models.hand ? "a hand model only"
                                                 : "neither"));
  }
  if (!options.keys.empty()) {
    const ModelFile keys = LoadModelFile(options.keys);
    if (!keys.keys) throw InvalidInput(options.keys + ": no key model (/keys) in the file (csw keys train)");
  }
  const FaceModel& face = *models.face;
  const HandModel& hand = *models.hand;
  const MarkerSet face_set = MarkerSetOfModel(face.info, options.models);
  const MarkerSet hand_set = MarkerSetOfModel(hand.info, options.models);
  const std::vector<std::string> face_names = ModelNames(face.layout.head, face.layout.face, face.layout.throat);
  const std::vector<std::string> hand_names = ModelNames(hand.layout.forearm, hand.layout.hand);
  const Corpus corpus = Corpus::Open(options.corpus);
  const std::vector<TakeRange> ranges = SelectCorpusTakes(corpus, options.takes);

  // Load every take and check its key tier before any inversion.
  std::vector<std::unique_ptr<TakeWork>> work;
  for (size_t i = 0; i < ranges.size(); ++i) {
    progress.Update("loading takes", static_cast<double>(i) / static_cast<double>(ranges.size()));
    const TakeRange& range = ranges[i];
    const Take take = corpus.LoadTake(range.take);
    const std::string where = corpus.path() + ": take '" + range.take + "'";
    const LabelTier* tier = FindTier(take.tiers, options.tier);
    if (!tier) {
      throw InvalidInput(where + ": no key tier '" + options.tier + "' (tiers: " + TierNames(take.tiers) +
                         "); run csw keys score for keys_aligned, or give --tier");
    }
    auto w = std::make_unique<TakeWork>();
    w->range = range;
    w->rate_hz = take.rate_hz;
    w->face_input =
        Extract(take.markers, BindNames(face_set, take.marker_names, face_names, where), range.first, range.count);
    w->hand_input =
        Extract(take.markers, BindNames(hand_set, take.marker_names, hand_names, where), range.first, range.count);
    // Marks within the range, on the range's clock.
    const std::vector<KeyMark> all = ReadKeyTier(*tier, where);
    const Syllables syllables = SyllablesOfMarks(take, all, options.phones, where);
    const std::vector<double> placements = PlacementTargets(take, all, options.placement_tier, where);
    const double offset = static_cast<double>(range.first) / take.rate_hz;
    const double last = static_cast<double>(range.first + range.count - 1) / take.rate_hz;
    w->series.take = range.spec;
    w->series.rate_hz = take.rate_hz;
    for (size_t k = 0; k < all.size(); ++k) {
      if (all[k].time_s < offset || all[k].time_s > last) continue;
      w->series.keys.push_back({all[k].time_s - offset, all[k].code});
      if (!syllables.onset_s.empty()) {
        w->series.syllable_onset_s.push_back(syllables.onset_s[k] - offset);
        w->series.key_type.push_back(syllables.type[k]);
      }
      w->series.placement_target_s.push_back(placements[k] - offset);
      if (std::isfinite(placements[k])) ++w->placement_lags;
    }
    w->phasing = !syllables.onset_s.empty();
    w->series.phones = RangePhones(take, options.phones, offset, last, where);
    w->series.audio_path = take.audio_path;
    work.push_back(std::move(w));
  }

  ParallelFor(work.size(), options.threads, "inverting and cutting", progress, [&](size_t i, Progress& item) {
    TakeWork& w = *work[i];
    InversionResult f = InvertFace(face, w.face_input, options.inversion, &item);
    InversionResult h = InvertHand(hand, w.hand_input, options.inversion, &item);
    w.series.hand_params = std::move(h.params);
    w.series.forearm_pose = std::move(h.pose);
    w.series.head_pose = std::move(f.pose);
    w.series.face_params = std::move(f.params);
    dict::AppendMarkerJumps(f.reconstructed, &w.jumps);
    dict::AppendMarkerJumps(h.reconstructed, &w.jumps);
    w.units = dict::ExtractDikeys(w.series, options.dikeys, &w.stats);
    w.diphones = dict::ExtractDiphones(w.series, options.dikeys, &w.diphone_stats);
    w.face_input = MarkerArray();
    w.hand_input = MarkerArray();
  });

  dict::Dictionary d;
  d.models_fingerprint = dict::ModelsFingerprint(&face, &hand);
  d.corpus = options.corpus;
  d.models_file = options.models;
  d.keys_file = options.keys;
  d.key_tier = options.tier;
  for (int p = 0; p < hand.num_parameters(); ++p) d.hand_parameter_names.push_back("hand_p" + std::to_string(p + 1));
  d.face_parameter_names = face.shape.parameter_names;
  if (static_cast<int>(d.face_parameter_names.size()) != face.num_parameters()) {
    d.face_parameter_names.clear();
    for (int p = 0; p < face.num_parameters(); ++p) d.face_parameter_names.push_back("face_p" + std::to_string(p + 1));
  }
  std::vector<double> jumps;
  for (const auto& wp : work) {
    jumps.insert(jumps.end(), wp->jumps.begin(), wp->jumps.end());
    wp->jumps = {};
  }
  if (!work.empty()) d.corpus_rate_hz = work.front()->rate_hz;
  d.corpus_p99_jump_mm = dict::Quantile(jumps, 0.99);
  d.corpus_max_jump_mm = jumps.empty() ? std::numeric_limits<double>::quiet_NaN() : jumps.back();
  dict::ExtractionStats diphone_total;
  int64_t diphone_frames = 0;
  json takes = json::array();
  dict::ExtractionStats total;
  std::vector<std::vector<KeyMark>> key_lists;
  std::vector<double> last_times;
  int64_t frames = 0;
  for (const auto& wp : work) {
    TakeWork& w = *wp;
    takes.push_back({{"take", w.range.spec},
                     {"frames", w.range.count},
                     {"keys", w.series.keys.size()},
                     {"dikeys", w.stats.kept},
                     {"rejected_unsolved", w.stats.rejected_unsolved},
                     {"rejected_outside", w.stats.rejected_outside},
                     {"phasing", w.phasing},
                     {"placement_lags", w.placement_lags},
                     {"phones", w.series.phones.size()},
                     {"diphones", w.diphone_stats.kept}});
    diphone_total.successions += w.diphone_stats.successions;
    diphone_total.kept += w.diphone_stats.kept;
    diphone_total.rejected_unsolved += w.diphone_stats.rejected_unsolved;
    diphone_total.rejected_outside += w.diphone_stats.rejected_outside;
    for (dict::DiphoneUnit& u : w.diphones) {
      diphone_frames += u.frames();
      d.diphones.push_back(std::move(u));
    }
    total.successions += w.stats.successions;
    total.kept += w.stats.kept;
    total.rejected_unsolved += w.stats.rejected_unsolved;
    total.rejected_outside += w.stats.rejected_outside;
    key_lists.push_back(w.series.keys);
    last_times.push_back(static_cast<double>(w.range.count - 1) / w.rate_hz);
    for (dict::DikeyUnit& u : w.units) {
      frames += u.frames();
      d.dikeys.push_back(std::move(u));
    }
  }
  progress.Update("writing the dictionary", 0.0);
  SaveDictionaryFile(options.output, d);

  const dict::Coverage in_corpus = dict::CoverageOfKeys(key_lists, last_times, options.dikeys);
  const dict::Coverage in_dict = dict::CoverageOfUnits(d.dikeys);
  json missing = json::array();
  std::map<std::string, int> have(in_dict.dikeys.begin(), in_dict.dikeys.end());
  for (const auto& [code, n] : in_corpus.dikeys)
    if (!have.count(code)) missing.push_back(code);
  json r;
  r["corpus"] = options.corpus;
  r["models"] = options.models;
  r["keys"] = options.keys;
  r["output"] = options.output;
  r["tier"] = options.tier;
  r["models_fingerprint"] = d.models_fingerprint;
  r["continuity"] = {
      {"rate_hz", d.corpus_rate_hz}, {"p99_jump_mm", d.corpus_p99_jump_mm}, {"max_jump_mm", d.corpus_max_jump_mm}};
  r["takes"] = takes;
  r["dikeys"] = {{"successions", total.successions},
                 {"kept", total.kept},
                 {"rejected_unsolved", total.rejected_unsolved},
                 {"rejected_outside", total.rejected_outside},
                 {"frames", frames}};
  json diphones = json::object();
  for (const auto& [code, n] : dict::DiphoneCoverage(d.diphones)) diphones[code] = n;
  r["diphones"] = {{"successions", diphone_total.successions},
                   {"kept", diphone_total.kept},
                   {"rejected_unsolved", diphone_total.rejected_unsolved},
                   {"rejected_outside", diphone_total.rejected_outside},
                   {"frames", diphone_frames},
                   {"distinct", diphones.size()},
                   {"coverage", diphones}};
  r["coverage"] = {{"corpus", CoverageJson(in_corpus)},
                   {"dictionary", CoverageJson(in_dict)},
                   {"complete", missing.empty()},
                   {"missing_dikeys", missing}};
  return r;
}

std::string DictBuildText(const json& r) {
  std::ostringstream o;
  const json& k = r["dikeys"];
  o << "dictionary " << r["output"].get<std::string>() << ": " << k["kept"].get<int>() << " dikeys of "
    << k["successions"].get<int>() << " key successions in " << r["takes"].size() << " takes ("
    << k["rejected_unsolved"].get<int>() << " left out for unsolved frames, " << k["rejected_outside"].get<int>()
    << " outside the takes), " << k["frames"].get<int64_t>() << " frames\n";
  o << "models fingerprint " << r["models_fingerprint"].get<std::string>() << "\n";
  if (r.contains("continuity") && r["continuity"]["p99_jump_mm"].is_number()) {
    const json& c = r["continuity"];
    char line[160];
    std::snprintf(line, sizeof line,
                  "corpus continuity: frame-to-frame marker jumps p99 %.3f mm, max %.3f mm at %.1f Hz\n",
                  c["p99_jump_mm"].get<double>(), c["max_jump_mm"].get<double>(), c["rate_hz"].get<double>());
    o << line;
  }
  const json& c = r["coverage"];
  auto line = [&](const char* what, const char* key, int possible) {
    o << what << " successions: corpus " << c["corpus"][key]["present"].get<int>() << ", dictionary "
      << c["dictionary"][key]["present"].get<int>() << " of " << possible << " possible\n";
  };
  line("placement", "placement", (kMaxPlacement + 1) * (kMaxPlacement + 1) - 1);
  line("shape", "shape", (kMaxShape + 1) * (kMaxShape + 1) - 1);
  o << "key successions: corpus " << c["corpus"]["dikeys"].size() << ", dictionary "
    << c["dictionary"]["dikeys"].size();
  if (c["complete"].get<bool>()) {
    o << " (every succession of the corpus is in the dictionary)\n";
  } else {
    o << "; missing:";
    for (const json& m : c["missing_dikeys"]) o << " " << m.get<std::string>();
    o << "\n";
  }
  if (r.contains("diphones")) {
    const json& p = r["diphones"];
    o << "diphones: " << p["kept"].get<int>() << " of " << p["successions"].get<int>() << " phone successions ("
      << p["rejected_unsolved"].get<int>() << " left out for unsolved frames), " << p["distinct"].get<int>()
      << " distinct, " << p["frames"].get<int64_t>() << " frames\n";
  }
  return o.str();
}

}  // namespace csw::jobs
