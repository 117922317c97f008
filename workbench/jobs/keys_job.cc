#include "workbench/jobs/keys_job.h"

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <optional>
#include <sstream>

#include "analysis/keys/hand_features.h"
#include "analysis/keys/key_timing.h"
#include "core/error.h"
#include "core/file_util.h"
#include "core/json_util.h"
#include "core/labels.h"
#include "core/markerset.h"
#include "io/corpus/corpus.h"
#include "io/models/model_file.h"
#include "synth/phone_symbols.h"
#include "workbench/jobs/figures.h"
#include "workbench/jobs/job_util.h"
#include "workbench/jobs/take_data.h"
#include "workbench/jobs/take_selection.h"
#include "workbench/jobs/tier_util.h"

#ifndef CSW_VERSION
#define CSW_VERSION "unknown"
#endif

namespace csw::jobs {

using nlohmann::json;
using namespace csw::keys;

namespace {

// The marker set for a take: given, or remembered by the corpus; nullopt when neither.
std::optional<MarkerSet> TakeSet(const Corpus& corpus, const std::string& take, const std::optional<MarkerSet>& given,
                                 const std::string& where) {
  if (given) return given;
  const std::string text = corpus.TakeMarkerSet(take);
  if (text.empty()) return std::nullopt;
  return ParseMarkerSet(text, where);
}

// Canonical names -> take columns: through the marker set, or by exact label.
MarkerBinding Bind(const std::optional<MarkerSet>& set, const Take& take, const std::string& where) {
  if (set) return BindMarkerSet(*set, take.marker_names, false, where);
  MarkerBinding b;
  for (size_t i = 0; i < take.marker_names.size(); ++i) b.index[take.marker_names[i]] = static_cast<int>(i);
  return b;
}

// Keeps the labels whose frames fall inside the range.
KeyLabels InRange(const KeyLabels& l, int64_t first, int64_t count) {
  KeyLabels out;
  for (size_t i = 0; i < l.shape_frames.size(); ++i)
    if (l.shape_frames[i] >= first && l.shape_frames[i] < first + count) {
      out.shape_frames.push_back(l.shape_frames[i]);
      out.shapes.push_back(l.shapes[i]);
    }
  for (size_t i = 0; i < l.placement_frames.size(); ++i)
    if (l.placement_frames[i] >= first && l.placement_frames[i] < first + count) {
      out.placement_frames.push_back(l.placement_frames[i]);
      out.placements.push_back(l.placements[i]);
      out.placement_shapes.push_back(l.placement_shapes[i]);
    }
  return out;
}

json ClassesJson(const GaussianClassifier& g) {
  json a = json::array();
  for (const auto& c : g.classes()) a.push_back({{"label", c.label}, {"count", c.count}, {"prior", c.prior}});
  return a;
}

json OptionsJson(const KeysTrainOptions& o) {
  auto gaussian = [](const GaussianOptions& g) {
    return json{{"shrinkage_samples", g.shrinkage_samples},
                {"ridge_fraction", g.ridge_fraction},
                {"min_variance", g.min_variance},
                {"priors", PriorKindName(g.priors)}};
  };
  return {{"tier", o.tier},
          {"placement_tier", o.placement_tier},
          {"markerset", o.markerset},
          {"layout", o.layout},
          {"shape", gaussian(o.model.shape)},
          {"placement", gaussian(o.model.placement)},
          {"index_shapes", o.model.index_shapes},
          {"target_window_frames", o.model.target_window_frames}};
}

LabelTier PointTier(const std::string& name, double end_s) {
  LabelTier t;
  t.name = name;
  t.kind = LabelTier::Kind::kPoint;
  t.start_s = 0;
  t.end_s = end_s;
  return t;
}

LabelTier IntervalTier(const std::string& name, double end_s) {
  LabelTier t = PointTier(name, end_s);
  t.kind = LabelTier::Kind::kInterval;
  return t;
}

// A posterior matrix as a corpus score matrix, columns named by class.
ScoreMatrix ScoreMatrixOf(const std::string& name, const Eigen::MatrixXd& p) {
  ScoreMatrix m;
  m.name = name;
  m.rows = p.rows();
  m.cols = p.cols();
  m.values.resize(static_cast<size_t>(p.size()));
  Eigen::Map<Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>>(m.values.data(), p.rows(),
                                                                                     p.cols()) = p;
  for (Eigen::Index c = 0; c < p.cols(); ++c) m.column_names.push_back(std::to_string(c));
  return m;
}

std::vector<std::vector<int>> Counts(const Confusion& c) {
  std::vector<std::vector<int>> out(static_cast<size_t>(c.counts.rows()));
  for (Eigen::Index i = 0; i < c.counts.rows(); ++i)
    for (Eigen::Index j = 0; j < c.counts.cols(); ++j) out[i].push_back(static_cast<int>(c.counts(i, j)));
  return out;
}

std::string Fixed(double v, int digits) {
  std::ostringstream o;
  o.setf(std::ios::fixed);
  o.precision(digits);
  o << v;
  return o.str();
}

}  // namespace

json ConfusionJson(const Confusion& c) {
  json rows = json::array();
  for (Eigen::Index i = 0; i < c.counts.rows(); ++i) {
    json r = json::array();
    for (Eigen::Index j = 0; j < c.counts.cols(); ++j) r.push_back(c.counts(i, j));
    rows.push_back(r);
  }
  return rows;
}

std::string KeysTrainOptions::Check() const {
  if (corpus.empty()) return "no corpus given";
  if (takes.empty()) return "--takes: name the training takes";
  if (output.empty()) return "-o: no output model file";
  if (tier.empty()) return "--tier must not be empty";
  if (const std::string r = model.Check(); !r.empty()) return r;
  return "";
}

std::string KeysScoreOptions::Check() const {
  if (corpus.empty()) return "no corpus given";
  if (keys.empty()) return "--keys: no key model file";
  if (const std::string r = decode.Check(); !r.empty()) return r;
  if (!(fit_sd_factor >= 0)) return "--fit-sd-factor must be >= 0";
  return "";
}

json KeysTrain(const KeysTrainOptions& options, Progress& progress) {
  if (const std::string why = options.Check(); !why.empty()) throw UsageError(why);
  const Corpus corpus = Corpus::Open(options.corpus);
  const std::vector<TakeRange> ranges = SelectCorpusTakes(corpus, options.takes);
  std::optional<MarkerSet> given;
  if (!options.markerset.empty()) given = LoadMarkerSet(options.markerset);
  std::optional<keys::HandLayout> layout;
  json layout_section;
  if (!options.layout.empty()) {
    const json doc = ParseJsonText(ReadTextFile(options.layout), options.layout);
    if (!doc.is_object() || !doc.contains("hand_layout"))
      throw UsageError(options.layout + ": no \"hand_layout\" section");
    layout_section = doc["hand_layout"];
  }
  Eigen::Matrix3Xd head;
  KeyTrainingSet set;
  json result = {{"corpus", options.corpus}, {"output", options.output}, {"takes", json::array()}};
  std::vector<std::string> specs;
  for (size_t i = 0; i < ranges.size(); ++i) {
    const TakeRange& range = ranges[i];
    progress.Update("keys train: " + range.take, static_cast<double>(i) / static_cast<double>(ranges.size()));
    const Take take = corpus.LoadTake(range.take);
    const std::string where = corpus.path() + ": take '" + range.take + "'";
    if (!(take.rate_hz > 0)) throw InvalidInput(where + ": no frame rate");
    const std::optional<MarkerSet> ms = TakeSet(corpus, range.take, given, where);
    if (!layout && !layout_section.is_null())  // the head cluster defaults to the marker set's
      layout = ParseHandLayout(layout_section, ms.value_or(MarkerSet{}), options.layout + ": hand_layout");
    if (!ms && !layout)
      throw UsageError(where + " was imported without --markerset: give --markerset SET.json or --layout FILE.json");
    const MarkerBinding binding = Bind(ms, take, where);
    if (!layout) {
      layout = DeriveHandLayout(*ms, take.markers, binding, where);
      if (layout->head.empty()) layout->head = ms->head_cluster;
    }
    if (head.cols() == 0) head = HeadReference(take.markers, binding, *layout);
    const KeyTargets targets = ReadKeyTargets(take, where, {options.tier, options.placement_tier});
    const KeyLabels labels =
        InRange(LabelsFromTargets(targets, take.rate_hz, take.frames(), where), range.first, range.count);
    const HandFeatures features = ComputeHandFeatures(take.markers, binding, *layout, head);
    set.Add(features, labels, options.model);
    specs.push_back(range.spec);
    result["takes"].push_back(
        {{"take", range.spec},
         {"shape_targets", labels.shape_frames.size()},
         {"placement_targets", labels.placement_frames.size()},
         {"placement_tier", targets.placement_from_own_tier ? options.placement_tier : options.tier}});
  }
  progress.Update("keys train: fit", 1.0);
  KeyModel model = TrainKeyModel(set, *layout, head, options.model);
  model.info.corpus = options.corpus;
  model.info.training_takes = specs;
  model.info.config_json = OptionsJson(options).dump();
  model.info.created_utc = UtcNow();
  model.info.csw_version = CSW_VERSION;
  model.info.training_frames = static_cast<int64_t>(set.shape_labels.size());
  model.info.selected_frames = static_cast<int64_t>(set.shape_labels.size());
  ModelFile update;
  update.keys = model;
  UpdateModelFile(options.output, update);
  result["layout"] = HandLayoutToJson(model.layout);
  result["shape"] = {{"classes", ClassesJson(model.shape)}};
  result["placement"] = {{"classes", ClassesJson(model.placement)}};
  return result;
}

std::string KeysTrainText(const json& r) {
  std::ostringstream o;
  for (const json& t : r["takes"])
    o << "take " << t["take"].get<std::string>() << ": " << t["shape_targets"].get<int64_t>() << " shape targets, "
      << t["placement_targets"].get<int64_t>() << " placement targets\n";
  auto classes = [&](const char* what) {
    o << what << " classes:";
    for (const json& c : r[what]["classes"])
      o << " " << c["label"].get<int>() << " (" << c["count"].get<int64_t>() << ")";
    o << "\n";
  };
  classes("shape");
  classes("placement");
  o << "key model written to " << r["output"].get<std::string>() << "\n";
  return o.str();
}

namespace {

// The keys of the take's phone tier (LfPC, rests first and last) give the
// labelled keys their A1 when the two code sequences are the same; false (no
// anchors) when the tier is absent or empty or its keys differ from the labels.
// A phone tier that cannot be read throws, naming it.
bool AttachSpeechAnchors(const Take& take, const std::string& tier_name, const std::string& where,
                         std::vector<keys::ExpectedKey>& expected) {
  if (tier_name.empty()) return false;
  const LabelTier* tier = FindTier(take.tiers, tier_name);
  if (tier == nullptr || tier->labels.empty()) return false;
  const CuedTier cued = CuePhoneTier(*tier, PhoneSymbols::kAuto, where + ": tier '" + tier_name + "'");
  if (cued.keys.size() != expected.size()) return false;
  for (size_t k = 0; k < expected.size(); ++k)
    if (cued.keys[k].placement != expected[k].placement || cued.keys[k].shape != expected[k].shape) return false;
  for (size_t k = 0; k < expected.size(); ++k) {
    const Key& key = cued.keys[k];
    if (key.type == KeyType::kRest) continue;
    expected[k].anchor_s = key.a1_s;
    expected[k].vowel_anchor = key.type == KeyType::kVowelAlone;
  }
  return true;
}

}  // namespace

json KeysScore(const KeysScoreOptions& options, Progress& progress) {
  if (const std::string why = options.Check(); !why.empty()) throw UsageError(why);
  const ModelFile mf = LoadModelFile(options.keys);
  if (!mf.keys) throw InvalidInput(options.keys + ": no key model (/keys) in this model file (csw keys train)");
  const KeyModel& model = *mf.keys;
  const Corpus corpus = Corpus::Open(options.corpus);
  const std::vector<TakeRange> ranges = SelectCorpusTakes(corpus, options.takes);
  std::optional<MarkerSet> given;
  if (!options.markerset.empty()) given = LoadMarkerSet(options.markerset);
  if (!options.figures.empty()) {
    figures::Require();
    std::filesystem::create_directories(options.figures);
  }

  json result = {{"corpus", options.corpus},
                 {"keys", options.keys},
                 {"takes", json::array()},
                 {"decoding",
                  {{"min_key_ms", options.decode.min_key_ms},
                   {"aligned_floor", options.decode.aligned_floor},
                   {"anchor_nearest", options.anchor_nearest},
                   {"fit_sd_factor", options.fit_sd_factor},
                   {"keep_in_class", options.keep_in_class}}}};
  Confusion shape(kNumShapes), placement(kNumPlacements);
  int free_correct = 0, free_expected = 0, free_ins = 0, free_del = 0, free_sub = 0;
  int aligned_correct = 0, aligned_expected = 0;
  std::vector<double> errors_ms;
  bool scored = false;
  std::vector<std::pair<std::string, std::vector<LabelTier>>> writes;
  std::vector<std::pair<std::string, TakeScores>> score_writes;
  for (size_t i = 0; i < ranges.size(); ++i) {
    const TakeRange& range = ranges[i];
    progress.Update("keys score: " + range.take, static_cast<double>(i) / static_cast<double>(ranges.size()));
    const Take take = corpus.LoadTake(range.take);
    const std::string where = corpus.path() + ": take '" + range.take + "'";
    if (range.first != 0 || range.count != take.frames())
      throw UsageError("csw keys score works on whole takes: '" + range.spec + "' selects frames of take '" +
                       range.take + "'");
    if (!(take.rate_hz > 0)) throw InvalidInput(where + ": no frame rate");
    const double rate = take.rate_hz;
    const MarkerBinding binding = Bind(TakeSet(corpus, range.take, given, where), take, where);
    const HandFeatures features = ComputeHandFeatures(take.markers, binding, model.layout, model.head_reference);
    const KeyPosteriors post = ScoreFrames(model, features);
    const std::vector<DecodedKey> decoded = DecodeFree(post, rate, options.decode);
    json tj = {{"take", range.spec}, {"frames", take.frames()}, {"decoded_keys", decoded.size()}};

    const double end_s = take.duration_s();
    LabelTier free_tier = IntervalTier("keys_decoded", end_s), free_targets = PointTier("keys_decoded_targets", end_s);
    for (const auto& k : decoded) {
      free_tier.labels.push_back({k.start_frame / rate, k.end_frame / rate, k.Code()});
      free_targets.labels.push_back({k.target_frame / rate, k.target_frame / rate, k.Code()});
    }
    std::vector<LabelTier> new_tiers = {free_tier, free_targets};
    auto extents_tier = [&](const std::string& name, const Eigen::MatrixXd& p) {
      LabelTier t = IntervalTier(name, end_s);
      for (const auto& x : GestureExtents(p))
        t.labels.push_back(
            {x.start_frame / rate, x.end_frame / rate, std::to_string(x.label) + " p=" + Fixed(x.peak, 2)});
      return t;
    };
    new_tiers.push_back(extents_tier("shape_extents", post.shape));
    new_tiers.push_back(extents_tier("placement_extents", post.placement));

    if (const LabelTier* tier = FindTier(take.tiers, options.tier); tier != nullptr && !tier->labels.empty()) {
      scored = true;
      const KeyTargets targets = ReadKeyTargets(take, where, {options.tier, options.placement_tier});
      const KeyLabels labels = LabelsFromTargets(targets, rate, take.frames(), where);
      Confusion ts(kNumShapes), tp(kNumPlacements);
      std::vector<std::string> expected;
      std::vector<keys::ExpectedKey> expected_keys;
      for (size_t k = 0; k < labels.shape_frames.size(); ++k) {
        ts.Add(labels.shapes[k], ArgMax(post.shape, labels.shape_frames[k]));
        // The expected sequence: the label tier's codes in time order.
        const ::csw::KeyCode& code = targets.shape[k].code;
        expected.push_back(code.Text());
        expected_keys.push_back({code.placement, code.shape});
      }
      tj["speech_anchors"] = AttachSpeechAnchors(take, options.phones, where, expected_keys);
      for (size_t k = 0; k < labels.placement_frames.size(); ++k)
        tp.Add(labels.placements[k], ArgMax(post.placement, labels.placement_frames[k]));
      shape.Add(ts);
      placement.Add(tp);
      std::vector<std::string> codes;
      for (const auto& k : decoded) codes.push_back(k.Code());
      const EditAlignment a = AlignSequences(codes, expected);
      free_correct += a.matches;
      free_expected += static_cast<int>(expected.size());
      free_ins += a.insertions;
      free_del += a.deletions;
      free_sub += a.substitutions;
      // Aligned decoding with kinematic target times (analysis/keys/key_timing.h).
      KeyTimingOptions timing;
      timing.decode = options.decode;
      timing.anchor_nearest = options.anchor_nearest;
      timing.anchor_fit_sd_factor = options.fit_sd_factor;
      timing.anchor_keep_in_class = options.keep_in_class;
      const std::vector<TimedKey> aligned = DecodeAlignedTimed(model, features, post, expected_keys, rate, timing);
      LabelTier aligned_tier = PointTier("keys_aligned", end_s);
      LabelTier aligned_places = PointTier("placement_aligned", end_s);
      int take_correct = 0;
      for (size_t k = 0; k < aligned.size(); ++k) {
        const double err = 1000.0 * std::abs(aligned[k].target_s - labels.shape_frames[k] / rate);
        errors_ms.push_back(err);
        if (err <= 40.0) ++take_correct;
        const std::string code = aligned[k].key.Code();
        aligned_tier.labels.push_back({aligned[k].target_s, aligned[k].target_s, code});
        if (aligned[k].placement.changes)
          aligned_places.labels.push_back({aligned[k].placement.target_s, aligned[k].placement.target_s, code});
      }
      new_tiers.push_back(aligned_places);
      aligned_correct += take_correct;
      aligned_expected += static_cast<int>(aligned.size());
      new_tiers.push_back(aligned_tier);
      tj["shape_accuracy"] = ts.Accuracy();
      tj["placement_accuracy"] = tp.Accuracy();
      tj["free_keys_correct"] = a.matches;
      tj["aligned_keys_correct"] = take_correct;
      tj["keys_expected"] = expected.size();
    }
    // The take's tiers with ours replaced or added.
    std::vector<LabelTier> tiers;
    for (const auto& t : take.tiers) {
      const bool ours =
          std::any_of(new_tiers.begin(), new_tiers.end(), [&](const LabelTier& n) { return n.name == t.name; });
      if (!ours) tiers.push_back(t);
    }
    std::vector<std::string> names;
    for (auto& t : new_tiers) {
      names.push_back(t.name);
      tiers.push_back(std::move(t));
    }
    tj["tiers_written"] = options.dry_run ? json::array() : json(names);
    tj["scores_written"] = options.dry_run ? json() : json("keys");
    writes.push_back({range.take, std::move(tiers)});
    TakeScores scores;
    scores.name = "keys";
    scores.rate_hz = rate;
    scores.start_s = 0.0;
    scores.source = options.keys;
    scores.matrices = {ScoreMatrixOf("shape", post.shape), ScoreMatrixOf("placement", post.placement)};
    score_writes.push_back({range.take, std::move(scores)});
    result["takes"].push_back(std::move(tj));
  }
  if (!options.dry_run && !writes.empty()) {
    progress.Update("keys score: writing tiers", 0.0);
    CorpusTransaction tx(options.corpus);
    for (const auto& [take, tiers] : writes) tx.WriteTiers(take, tiers);
    for (const auto& [take, scores] : score_writes) tx.WriteScores(take, scores);
    tx.Commit();
  }
  if (scored && !options.figures.empty()) {
    progress.Update("keys score: figures", 1.0);
    auto labels = [](int n) {
      std::vector<std::string> l;
      for (int i = 0; i < n; ++i) l.push_back(std::to_string(i));
      return l;
    };
    const std::string sp = (std::filesystem::path(options.figures) / "shape_confusion.png").string();
    const std::string pp = (std::filesystem::path(options.figures) / "placement_confusion.png").string();
    figures::SaveConfusionMatrix(sp, "Hand shapes at the labelled frames", labels(kNumShapes), Counts(shape),
                                 "labelled shape", "posterior argmax");
    figures::SaveConfusionMatrix(pp, "Placements at the labelled frames", labels(kNumPlacements), Counts(placement),
                                 "labelled placement", "posterior argmax");
    result["figures"] = {sp, pp};
  }
  if (scored) {
    double mean = 0, sd = 0;
    for (double e : errors_ms) mean += e;
    if (!errors_ms.empty()) mean /= static_cast<double>(errors_ms.size());
    for (double e : errors_ms) sd += (e - mean) * (e - mean);
    if (errors_ms.size() > 1) sd = std::sqrt(sd / static_cast<double>(errors_ms.size() - 1));
    result["shape"] = {{"accuracy", shape.Accuracy()}, {"count", shape.Total()}, {"confusion", ConfusionJson(shape)}};
    result["placement"] = {
        {"accuracy", placement.Accuracy()}, {"count", placement.Total()}, {"confusion", ConfusionJson(placement)}};
    result["sequence"] = {{"free",
                           {{"keys_correct", free_correct},
                            {"keys_expected", free_expected},
                            {"insertions", free_ins},
                            {"deletions", free_del},
                            {"substitutions", free_sub}}},
                          {"aligned",
                           {{"keys_correct", aligned_correct},
                            {"keys_expected", aligned_expected},
                            {"target_error_ms", {{"mean", mean}, {"sd", sd}}}}}};
  }
  return result;
}

std::string KeysScoreText(const json& r) {
  std::ostringstream o;
  for (const json& t : r["takes"]) {
    o << "take " << t["take"].get<std::string>() << ": " << t["frames"].get<int64_t>() << " frames, "
      << t["decoded_keys"].get<int64_t>() << " keys decoded";
    if (t.contains("shape_accuracy"))
      o << "; shape " << Fixed(100 * t["shape_accuracy"].get<double>(), 1) << " %, placement "
        << Fixed(100 * t["placement_accuracy"].get<double>(), 1) << " %, free " << t["free_keys_correct"].get<int>()
        << "/" << t["keys_expected"].get<int64_t>() << ", aligned " << t["aligned_keys_correct"].get<int>() << "/"
        << t["keys_expected"].get<int64_t>();
    o << "\n";
  }
  if (r.contains("shape")) {
    const json& f = r["sequence"]["free"];
    const json& a = r["sequence"]["aligned"];
    o << "shape accuracy " << Fixed(100 * r["shape"]["accuracy"].get<double>(), 1) << " % of "
      << r["shape"]["count"].get<int64_t>() << " labelled frames; placement "
      << Fixed(100 * r["placement"]["accuracy"].get<double>(), 1) << " % of " << r["placement"]["count"].get<int64_t>()
      << "\n";
    o << "free decoding: " << f["keys_correct"].get<int>() << " of " << f["keys_expected"].get<int>() << " keys, "
      << f["insertions"].get<int>() << " insertions, " << f["deletions"].get<int>() << " deletions, "
      << f["substitutions"].get<int>() << " substitutions\n";
    o << "aligned decoding: " << a["keys_correct"].get<int>() << " of " << a["keys_expected"].get<int>()
      << " keys within 40 ms; target error " << Fixed(a["target_error_ms"]["mean"].get<double>(), 1) << " ms (sd "
      << Fixed(a["target_error_ms"]["sd"].get<double>(), 1) << ")\n";
    if (r.contains("decoding")) {
      const json& d = r["decoding"];
      o << "decoding options: shortest free key " << Fixed(d["min_key_ms"].get<double>(), 0) << " ms, aligned floor "
        << d["aligned_floor"].get<double>() << ", targets nearer a neighbour's A1 + lag "
        << (d["anchor_nearest"].get<bool>() ? "replaced" : "kept") << ", fit sd factor "
        << d["fit_sd_factor"].get<double>();
      if (d.contains("keep_in_class"))
        o << ", fits in the key's class " << (d["keep_in_class"].get<bool>() ? "kept" : "not kept");
      o << "\n";
    }
  }
  if (r.contains("figures"))
    for (const json& f : r["figures"]) o << "figure: " << f.get<std::string>() << "\n";
  return o.str();
}

}  // namespace csw::jobs
