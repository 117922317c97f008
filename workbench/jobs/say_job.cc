#include "workbench/jobs/say_job.h"

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <limits>
#include <optional>

#include "analysis/keys/hand_features.h"
#include "analysis/keys/key_decoding.h"
#include "analysis/keys/key_model.h"
#include "analysis/phasing/phasing_stats.h"
#include "core/error.h"
#include "core/markerset.h"
#include "io/c3d/c3d.h"
#include "io/corpus/corpus.h"
#include "io/dictionary/dictionary_file.h"
#include "io/formats/textgrid.h"
#include "io/formats/wav.h"
#include "io/models/model_file.h"
#include "synth/synthesizer.h"
#include "workbench/jobs/job_util.h"
#include "workbench/jobs/model_config.h"
#include "workbench/jobs/phasing_job.h"
#include "workbench/jobs/video_job.h"

namespace csw::jobs {

namespace fs = std::filesystem;
using nlohmann::json;

namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

json Number(double v) { return std::isfinite(v) ? json(v) : json(nullptr); }

const char* const kLevels[] = {"whole", "closest placement", "two streams", "interpolated"};

json LevelCounts(const std::vector<int>& counts) {
  json j = json::object();
  for (size_t i = 0; i < counts.size(); ++i) j[kLevels[i]] = counts[i];
  return j;
}

// A field ("mean_ms", "ci95_ms") of the kinematic phasing summary for a
// component's landmark ("placement" / "shape", "onset" / "target"), NaN when
// absent.
double SummaryValue(const json& summary, const std::string& type, const std::string& component,
                    const std::string& landmark, const std::string& field) {
  const json* j = &summary;
  for (const std::string& k : {type, component, landmark, field}) {
    if (!j->is_object() || !j->contains(k)) return kNaN;
    j = &(*j)[k];
  }
  return j->is_number() ? j->get<double>() : kNaN;
}

int SummaryCount(const json& summary, const std::string& type, const std::string& component) {
  const json* j = &summary;
  for (const std::string& k : {type, component, std::string("target"), std::string("count")}) {
    if (!j->is_object() || !j->contains(k)) return 0;
    j = &(*j)[k];
  }
  return j->is_number() ? j->get<int>() : 0;
}

json ReadJsonFile(const std::string& path) {
  std::ifstream in(path);
  if (!in) throw IoError(path, "cannot open");
  try {
    return json::parse(in);
  } catch (const json::parse_error& e) {
    throw ParseError(Location{path, static_cast<int64_t>(e.byte), std::nullopt}, std::string("not JSON: ") + e.what());
  }
}

}  // namespace

std::string SayOptions::Check() const {
  if (texts.empty() && text_file.empty()) return "no text given (a sentence, or --text-file)";
  for (const std::string& t : texts)
    if (t.find_first_not_of(" \t\r\n") == std::string::npos) return "an empty text was given";
  if (dict.empty()) return "no dictionary given (--dict)";
  if (models.empty()) return "no model file given (--models)";
  if (output.empty()) return "no output folder given (-o)";
  if (rate_wpm != 0 && (rate_wpm < 80 || rate_wpm > 450)) return "--rate must be in [80, 450] words per minute";
  if (phasing != "dikey" && phasing != "global") return "--phasing must be dikey or global";
  if (!(rate_hz == 0 || (rate_hz >= 10 && rate_hz <= 2000))) return "--frame-rate must be 0 or in [10, 2000] Hz";
  if (!(fps >= 1 && fps <= 240)) return "--fps must be in [1, 240]";
  if (!(selection_weight >= 0 && selection_weight < 1e6)) return "--selection-weight must be >= 0";
  if (!(concatenation_weight >= 0 && concatenation_weight < 1e6)) return "--concatenation-weight must be >= 0";
  if (!(target_weight >= 0 && target_weight < 1e6)) return "--target-weight must be >= 0";
  if (!(posture_radius >= 0 && posture_radius < 1e6)) return "--posture-radius must be >= 0";
  if (!(max_onset_overlap >= 0 && max_onset_overlap <= 1)) return "--max-overlap must be in [0, 1]";
  if (face_units != "diphones" && face_units != "fragments") return "--face-units must be diphones or fragments";
  if (dict::Resampling r; !dict::ParseResampling(resampling, &r)) return "--resampling must be rbf or linear";
  if (!(blend >= 0 && blend <= 1)) return "--blend must be in [0, 1]";
  if (!(rbf_shape > 0 && rbf_shape <= 100)) return "--rbf-shape must be in (0, 100]";
  if (check && keys.empty()) return "--check needs the key model (--keys)";
  if (!corpus_phasing.empty() && !check) return "--corpus-phasing applies with --check";
  return "";
}

json Say(const SayOptions& options, Progress& progress) {
  if (const std::string why = options.Check(); !why.empty()) throw UsageError(why);
  std::vector<std::string> sentences = options.texts;
  if (!options.text_file.empty()) {
    const std::vector<std::string> more = ReadSentences(options.text_file);
    sentences.insert(sentences.end(), more.begin(), more.end());
  }
  const ModelFile models = LoadModelFile(options.models);
  if (!models.face || !models.hand)
    throw InvalidInput(options.models + ": synthesis needs the face and the hand model the dictionary was built with");
  const FaceModel& face = *models.face;
  const HandModel& hand = *models.hand;
  const dict::Dictionary dictionary = LoadDictionaryFile(options.dict);
  dict::CheckModelsMatch(dictionary, dict::ModelsFingerprint(&face, &hand), options.dict);
  std::optional<keys::KeyModel> key_model;
  if (options.check) {
    ModelFile k = LoadModelFile(options.keys);
    if (!k.keys) throw InvalidInput(options.keys + ": no key model (/keys) in the file (csw keys train)");
    key_model = std::move(*k.keys);
  }
  json corpus_phasing;
  if (!options.corpus_phasing.empty()) corpus_phasing = ReadJsonFile(options.corpus_phasing);
  const MarkerSet set = MarkerSetOfModel(face.info, options.models);
  const std::string set_json = MarkerSetToJson(set);

  dict::SynthesisOptions so;
  ParsePhasingRule(options.phasing, &so.plan.rule);
  so.concat.rate_hz = options.rate_hz;
  so.concat.selection_weight = options.selection_weight;
  so.concat.concatenation_weight = options.concatenation_weight;
  so.concat.target_weight = options.target_weight;
  so.concat.trim_keeps_key_posture = options.keep_key_postures;
  so.concat.posture_radius = options.posture_radius;
  so.concat.keep_movement_duration = options.keep_movement_durations;
  // --keep-movement-durations sets where movements start in its own way: it replaces the onsets.
  so.concat.movement_onsets = options.movement_onsets && !options.keep_movement_durations;
  so.concat.max_onset_overlap = options.max_onset_overlap;
  so.face_fragments = options.face_units == "fragments";
  dict::ParseResampling(options.resampling, &so.fragments.resampling);
  so.fragments.blend_fraction = options.blend;
  so.fragments.align_phones = options.align_phones;
  so.fragments.rbf_shape = options.rbf_shape;
  const double mean_phone = dict::MeanPhoneDuration(dictionary);

  const fs::path out(options.output);
  fs::create_directories(out);
  const std::string corpus_path = (out / "synthesis.h5").string();
  std::error_code ec;
  fs::remove(corpus_path, ec);  // this command's own output, replaced
  CorpusTransaction tx(corpus_path);

  json result = {{"dict", options.dict},
                 {"models", options.models},
                 {"output", options.output},
                 {"phasing", options.phasing},
                 {"dikey_warp", so.concat.keep_movement_duration ? "movements kept"
                                : so.concat.movement_onsets      ? "movement onsets"
                                                                 : "linear"},
                 {"max_overlap", so.concat.movement_onsets ? json(so.concat.max_onset_overlap) : json(nullptr)},
                 {"corpus", corpus_path},
                 {"sentences", json::array()},
                 {"face_units", options.face_units}};
  if (so.face_fragments)
    result["fragments"] = {{"resampling", options.resampling},
                           {"rbf_shape", options.rbf_shape},
                           {"blend", options.blend},
                           {"align_phones", options.align_phones}};
  int fragments_n = 0, fragment_diphones = 0, fragments_interpolated = 0, longest_fragment = 0, fragments_linear = 0;
  std::vector<int> levels(4, 0);
  int intended = 0, correct = 0, shape_correct = 0, placement_correct = 0, at_targets_correct = 0;
  int substitutions = 0, insertions = 0, deletions = 0;
  std::vector<double> jumps;
  double out_rate = kNaN;
  const bool many = sentences.size() > 1;
  for (size_t i = 0; i < sentences.size(); ++i) {
    progress.Update("synthesising", static_cast<double>(i) / static_cast<double>(sentences.size()));
    char id[32];
    std::snprintf(id, sizeof id, "%03zu", i + 1);
    const fs::path folder = many ? out / id : out;
    fs::create_directories(folder);
    const std::string name = std::string("say_") + id;

    PhonetiseOptions po;
    po.rate_wpm = options.rate_wpm > 0 ? options.rate_wpm : dict::MatchSpeakingRate(sentences[i], mean_phone);
    const Utterance u = Phonetise(sentences[i], po);
    dict::Synthesis s = dict::Synthesize(u, dictionary, face, hand, so, name);
    out_rate = s.take.rate_hz;
    s.take.markerset_json = set_json;
    const double end_s = s.take.duration_s();

    json files = json::object();
    const std::string wav = (folder / "speech.wav").string();
    if (!s.audio.samples.empty()) {
      WriteWav(wav, s.audio);
      files["wav"] = wav;
    }
    const std::string grid = (folder / "cues.TextGrid").string();
    WriteTextGrid(grid, s.take.tiers, 0, end_s);
    files["textgrid"] = grid;
    const std::string c3d = (folder / "markers.c3d").string();
    WriteC3d(c3d, s.take);
    files["c3d"] = c3d;
    std::ofstream((folder / "markerset.json").string()) << set_json;
    if (options.video) {
      PointLightOptions vo;
      vo.fps = options.fps;
      const PointLightResult v = WriteTakeVideo(s.take, &set, (folder / "pointlight.mp4").string(), vo,
                                                s.audio.samples.empty() ? "" : wav, &progress);
      files["video"] = v.path;
      for (const std::string& w : v.warnings) s.warnings.push_back(w);
    }

    // Every key: its planned target, the rule that gave it, how its slot was
    // filled (fallback level, units used with their takes and durations).
    json key_list = json::array();
    for (size_t k = 0; k < s.plan.keys.size(); ++k) {
      const dict::PlannedKey& p = s.plan.keys[k];
      json kj = {{"code", p.code.Text()},
                 {"type", phasing::KeyTypeLabel(p.type)},
                 {"a1_s", Number(p.a1_s)},
                 {"target_s", p.target_s},
                 {"timing", p.source}};
      if (k < s.hand.postures.size()) {
        kj["posture_distance"] = Number(s.hand.postures[k].distance);
        kj["posture_pulled"] = s.hand.postures[k].pulled;
      }
      if (k > 0 && k - 1 < s.hand.keys.size()) {
        const dict::KeyReport& rep = s.hand.keys[k - 1];
        kj["slot_s"] = p.target_s - s.plan.keys[k - 1].target_s;
        kj["level"] = dict::FallbackLevelName(rep.level);
        json units = json::array();
        for (int u : rep.units) {
          const dict::DikeyUnit& unit = dictionary.dikeys[static_cast<size_t>(u)];
          units.push_back({{"take", unit.take},
                           {"from", unit.from.Text()},
                           {"to", unit.to.Text()},
                           {"start_s", unit.start_s},
                           {"duration_s", unit.duration_s()}});
        }
        kj["units"] = units;
      }
      key_list.push_back(kj);
    }
    std::vector<int> sentence_levels(4, 0);
    for (const dict::KeyReport& r : s.hand.keys) ++sentence_levels[static_cast<size_t>(r.level)];
    for (size_t l = 0; l < 4; ++l) levels[l] += sentence_levels[l];
    int keys_n = 0;
    for (const dict::PlannedKey& k : s.plan.keys) keys_n += k.code.IsRest() ? 0 : 1;
    json sj = {{"text", sentences[i]},
               {"take", name},
               {"folder", folder.string()},
               {"duration_s", end_s},
               {"lead_in_s", s.plan.lead_in_s},
               {"rate_wpm", po.rate_wpm},
               {"phones", u.phones.size()},
               {"keys", keys_n},
               {"fallback", LevelCounts(sentence_levels)},
               {"key_plan", key_list},
               {"files", files},
               {"speed_limit",
                {{"limit_mm", s.speed_limit_mm > 0 ? json(s.speed_limit_mm) : json()},
                 {"smoothed_frames", s.speed_limit.smoothings},
                 {"max_jump_before_mm", s.speed_limit.max_jump_before_mm},
                 {"max_jump_after_mm", s.speed_limit.max_jump_after_mm}}},
               {"warnings", s.warnings}};
    if (so.face_fragments) {
      json fl = json::array();
      for (const dict::FragmentReport& f : s.fragments.fragments) {
        fl.push_back({{"take", f.take},
                      {"phones", f.phones},
                      {"diphones", f.slots},
                      {"interpolated", f.interpolated},
                      {"context_matches", f.context_matches},
                      {"timing_rms_s", f.timing_rms_s},
                      {"linear_fallback", f.linear_fallback}});
        fragments_linear += f.linear_fallback ? 1 : 0;
        ++fragments_n;
        fragment_diphones += f.slots;
        fragments_interpolated += f.interpolated ? 1 : 0;
        longest_fragment = std::max(longest_fragment, f.slots);
      }
      sj["fragments"] = fl;
    }

    if (key_model) {
      MarkerBinding binding;
      for (size_t m = 0; m < s.take.marker_names.size(); ++m)
        binding.index[s.take.marker_names[m]] = static_cast<int>(m);
      const keys::HandFeatures features =
          keys::ComputeHandFeatures(s.take.markers, binding, key_model->layout, key_model->head_reference);
      const keys::KeyPosteriors post = keys::ScoreFrames(*key_model, features);
      // (a) At the targets: each intended key's shape and placement posteriors
      // at its planned target frame. (b) As read: the free decoding (rests
      // left out) aligned to the intended sequence by edit distance.
      json in = json::array(), at = json::array(), rec = json::array();
      std::vector<std::string> intended_codes, decoded_codes;
      int ok = 0, n = 0;
      for (const dict::PlannedKey& k : s.plan.keys) {
        if (k.code.IsRest()) continue;
        const auto frame = std::min<int64_t>(std::llround(k.target_s * s.take.rate_hz), post.frames() - 1);
        const int shape = keys::ArgMax(post.shape, frame), placement = keys::ArgMax(post.placement, frame);
        const KeyCode got{placement, shape};
        in.push_back(k.code.Text());
        intended_codes.push_back(k.code.Text());
        at.push_back(got.Text());
        ++n;
        shape_correct += shape == k.code.shape ? 1 : 0;
        placement_correct += placement == k.code.placement ? 1 : 0;
        if (shape == k.code.shape && placement == k.code.placement) ++ok;
      }
      for (const keys::DecodedKey& d : keys::DecodeFree(post, s.take.rate_hz))
        if (!(d.placement == 0 && d.shape == 0)) decoded_codes.push_back(d.Code());
      for (const std::string& c : decoded_codes) rec.push_back(c);
      const keys::EditAlignment a = keys::AlignSequences(decoded_codes, intended_codes);
      intended += n;
      correct += a.matches;
      at_targets_correct += ok;
      substitutions += a.substitutions;
      insertions += a.insertions;
      deletions += a.deletions;
      sj["check"] = {{"intended", in},       {"recognised", rec},
                     {"correct", a.matches}, {"accuracy", n ? double(a.matches) / n : kNaN},
                     {"at_targets", at},     {"at_targets_correct", ok}};
      dict::AppendMarkerJumps(s.take.markers, &jumps);
    }

    Take take = s.take;
    take.audio = s.audio;
    if (!s.audio.samples.empty()) take.audio_path = wav;
    tx.WriteTake(take);
    result["sentences"].push_back(sj);
  }
  progress.Update("synthesising", 1.0);
  tx.Commit();
  result["rate_hz"] = out_rate;
  if (so.face_fragments) {
    result["fragments"]["count"] = fragments_n;
    result["fragments"]["mean_diphones"] = Number(fragments_n ? double(fragment_diphones) / fragments_n : kNaN);
    result["fragments"]["longest"] = longest_fragment;
    result["fragments"]["interpolated"] = fragments_interpolated;
    result["fragments"]["linear_fallback"] = fragments_linear;
  }
  result["fallback"] = LevelCounts(levels);

  if (options.check) {
    json check;
    check["keys"] = {{"intended", intended},
                     {"correct", correct},
                     {"accuracy", Number(intended ? double(correct) / intended : kNaN)},
                     {"substitutions", substitutions},
                     {"insertions", insertions},
                     {"deletions", deletions},
                     {"at_targets",
                      {{"correct", at_targets_correct},
                       {"accuracy", Number(intended ? double(at_targets_correct) / intended : kNaN)},
                       {"shape_accuracy", Number(intended ? double(shape_correct) / intended : kNaN)},
                       {"placement_accuracy", Number(intended ? double(placement_correct) / intended : kNaN)}}}};
    const double max_jump = jumps.empty() ? kNaN : *std::max_element(jumps.begin(), jumps.end());
    check["continuity"] = {{"rate_hz", out_rate},
                           {"p99_jump_mm", Number(dict::Quantile(jumps, 0.99))},
                           {"max_jump_mm", Number(max_jump)},
                           {"corpus_rate_hz", Number(dictionary.corpus_rate_hz)},
                           {"corpus_p99_jump_mm", Number(dictionary.corpus_p99_jump_mm)},
                           {"corpus_max_jump_mm", Number(dictionary.corpus_max_jump_mm)}};
    // Gesture timing: csw phasing on the synthesised corpus, rough targets
    // from its key tiers (the intended targets).
    PhasingOptions po;
    po.corpus = corpus_path;
    po.keys = options.keys;
    Progress quiet;
    json timing = json::object();
    try {
      const json measured = Phasing(po, quiet);
      const json& mine = measured["kinematic"];
      const json& theirs = corpus_phasing.is_object() && corpus_phasing.contains("kinematic")
                               ? corpus_phasing["kinematic"]
                               : json::object();
      for (const char* type : {"CV", "V", "C"}) {
        json t = json::object();
        for (const char* component : {"placement", "shape"}) {
          for (const char* landmark : {"onset", "target"}) {
            const std::string name = std::string(component) + "_" + landmark;
            const double mean = SummaryValue(mine, type, component, landmark, "mean_ms");
            const double corpus_mean = SummaryValue(theirs, type, component, landmark, "mean_ms");
            const double ci = SummaryValue(mine, type, component, landmark, "ci95_ms");
            const double corpus_ci = SummaryValue(theirs, type, component, landmark, "ci95_ms");
            t[name + "_ms"] = Number(mean);
            t["corpus_" + name + "_ms"] = Number(corpus_mean);
            t[name + "_ci95_ms"] = Number(ci);
            t["corpus_" + name + "_ci95_ms"] = Number(corpus_ci);
            // The difference of the two means and its 95 % half-width (the
            // two means' independent half-widths combined): whether a
            // difference is the synthesis's or the few keys measured.
            t[name + "_difference_ms"] = Number(mean - corpus_mean);
            t[name + "_difference_ci95_ms"] = Number(std::hypot(ci, corpus_ci));
          }
          t[std::string(component) + "_count"] = SummaryCount(mine, type, component);
        }
        timing[type] = t;
      }
    } catch (const Cancelled&) {
      throw;
    } catch (const Error& e) {
      timing["error"] = e.what();
    }
    check["timing"] = timing;
    result["check"] = check;
  }
  std::ofstream((out / "say.json").string()) << result.dump(2) << "\n";
  return result;
}

std::string SayText(const json& r) {
  std::string s;
  char line[512];
  const auto& sentences = r["sentences"];
  for (const auto& x : sentences) {
    std::snprintf(line, sizeof line, "%s: %.2f s, %d keys, %d wpm -> %s\n", x["take"].get<std::string>().c_str(),
                  x["duration_s"].get<double>(), x["keys"].get<int>(), x["rate_wpm"].get<int>(),
                  x["folder"].get<std::string>().c_str());
    s += line;
    for (const auto& w : x["warnings"]) s += "  warning: " + w.get<std::string>() + "\n";
  }
  const auto& f = r["fallback"];
  std::snprintf(line, sizeof line,
                "%zu sentences; keys reached by whole dikeys %d, closest placement %d, two streams %d, interpolated "
                "%d\n",
                sentences.size(), f.value("whole", 0), f.value("closest placement", 0), f.value("two streams", 0),
                f.value("interpolated", 0));
  s += line;
  if (r.contains("fragments") && r["fragments"].contains("count")) {
    const auto& g = r["fragments"];
    std::snprintf(line, sizeof line,
                  "face from %d fragments (mean %.1f diphones, longest %d, %d interpolated; %s resampling)\n",
                  g["count"].get<int>(), g["mean_diphones"].is_number() ? g["mean_diphones"].get<double>() : kNaN,
                  g["longest"].get<int>(), g["interpolated"].get<int>(), g["resampling"].get<std::string>().c_str());
    s += line;
  }
  s += "corpus of the synthesised takes: " + r["corpus"].get<std::string>() + "\n";
  if (r.contains("check")) {
    const auto& c = r["check"];
    auto num = [](const json& v) { return v.is_number() ? v.get<double>() : kNaN; };
    std::snprintf(line, sizeof line, "recognised keys: %d of %d (%.1f %%)", c["keys"]["correct"].get<int>(),
                  c["keys"]["intended"].get<int>(), 100.0 * num(c["keys"]["accuracy"]));
    s += line;
    if (c["keys"].contains("at_targets")) {
      std::snprintf(line, sizeof line, "; at their target frames %d (%.1f %%)",
                    c["keys"]["at_targets"]["correct"].get<int>(), 100.0 * num(c["keys"]["at_targets"]["accuracy"]));
      s += line;
    }
    s += "\n";
    const auto& k = c["continuity"];
    std::snprintf(line, sizeof line, "marker jumps: p99 %.2f mm, max %.2f mm (corpus: p99 %.2f mm, max %.2f mm)\n",
                  num(k["p99_jump_mm"]), num(k["max_jump_mm"]), num(k["corpus_p99_jump_mm"]),
                  num(k["corpus_max_jump_mm"]));
    s += line;
    const auto& t = c["timing"];
    if (t.contains("error")) {
      s += "timing: not measured (" + t["error"].get<std::string>() + ")\n";
    } else {
      for (const char* type : {"CV", "V", "C"}) {
        if (!t.contains(type)) continue;
        const auto& x = t[type];
        std::snprintf(line, sizeof line,
                      "%s targets re A1: placement %.0f ms (corpus %.0f), shape %.0f ms (corpus %.0f)\n", type,
                      num(x["placement_target_ms"]), num(x["corpus_placement_target_ms"]), num(x["shape_target_ms"]),
                      num(x["corpus_shape_target_ms"]));
        s += line;
        if (!x.contains("placement_onset_difference_ms")) continue;
        std::string parts;
        for (const char* component : {"placement", "shape"}) {
          parts += parts.empty() ? "" : "; ";
          parts += component;
          for (const char* landmark : {"onset", "target"}) {
            const std::string name = std::string(component) + "_" + landmark;
            const double d = num(x[name + "_difference_ms"]), h = num(x[name + "_difference_ci95_ms"]);
            if (std::isfinite(d) && std::isfinite(h))
              std::snprintf(line, sizeof line, " %s %+.0f ± %.0f", landmark, d, h);
            else
              std::snprintf(line, sizeof line, " %s n/a", landmark);
            parts += line;
            if (std::string(landmark) == "onset") parts += ",";
          }
        }
        std::snprintf(line, sizeof line, "%s synthesis - corpus: %s ms (95 %% CI; %d / %d keys)\n", type, parts.c_str(),
                      x.value("placement_count", 0), x.value("shape_count", 0));
        s += line;
      }
    }
  }
  return s;
}

}  // namespace csw::jobs
