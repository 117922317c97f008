#include "workbench/jobs/sign_sequence_job.h"

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <map>
#include <set>
#include <sstream>

#include "analysis/signing/duration_models.h"
#include "analysis/signing/transition_synthesis.h"
#include "analysis/signing/transitions.h"
#include "core/error.h"
#include "core/file_util.h"
#include "core/json_util.h"
#include "io/corpus/corpus.h"
#include "io/formats/bvh.h"
#include "io/formats/textgrid.h"
#include "workbench/jobs/job_util.h"
#include "workbench/jobs/take_data.h"
#include "workbench/jobs/take_selection.h"
#include "workbench/jobs/tier_util.h"
#include "workbench/jobs/transitions_job.h"

namespace csw::jobs {

using nlohmann::json;

namespace {

double Round(double v, double step) { return std::isfinite(v) ? std::round(v / step) * step : v; }

double UnitMm(const std::string& unit) {
  if (unit == "m") return 1000.0;
  if (unit == "dm") return 100.0;
  if (unit == "cm") return 10.0;
  if (unit == "mm") return 1.0;
  return 0.0;
}

struct DurationSource {
  signing::DurationModel model;
  std::string joints = "all";  // "all" or "arm"
  double unit_mm = 1000.0;
  std::string description;
};

DurationSource LoadDurations(const SignSequenceOptions& options) {
  DurationSource d;
  if (options.durations.empty()) {
    d.model = signing::SeedSurfaceModel();
    d.description = "the seed's SURFACE plane (every joint, metres)";
    return d;
  }
  const json file = ParseJsonText(ReadTextFile(options.durations), options.durations);
  auto bad = [&](const std::string& why) {
    return ParseError(Location{options.durations, std::nullopt, std::nullopt}, why);
  };
  if (!file.is_object() || file.value("format", "") != "csw-transition-duration-models") {
    throw bad("not a csw transition duration models file (csw transitions -o)");
  }
  d.joints = file.value("joints", "all");
  if (d.joints != "all" && d.joints != "arm") throw bad("'joints' must be arm or all");
  d.unit_mm = UnitMm(file.value("length_unit", "m"));
  if (d.unit_mm == 0) throw bad("'length_unit' must be m, dm, cm or mm");
  std::string name = options.model;
  if (name.empty()) {
    if (!file.contains("best") || !file["best"].is_string())
      throw bad("no best model recorded: choose one with --model");
    name = file["best"].get<std::string>();
  }
  const signing::DurationModelKind kind = signing::ParseDurationModel(name);
  if (!file.contains("models") || !file["models"].is_array()) throw bad("'models' is missing");
  for (const json& m : file["models"]) {
    try {
      const signing::DurationModel model = signing::DurationModel::FromJson(m);
      if (model.kind == kind) {
        d.model = model;
        d.description = std::string(signing::DurationModelName(kind)) + " of " + options.durations;
        return d;
      }
    } catch (const InvalidInput& e) {
      throw bad(e.what());
    }
  }
  throw bad("no '" + name + "' model in the file");
}

struct Occurrence {
  size_t take = 0;
  int64_t first = 0, last = 0;  // frames of the sign's bounding postures
  double start_s = 0, end_s = 0;
};

// Frames [first, end) of a take as a clip, clamped to the take (at least one frame).
signing::Clip ClampedClip(const Take& take, int64_t first, int64_t end) {
  first = std::clamp<int64_t>(first, 0, take.frames() - 1);
  end = std::clamp<int64_t>(end, first + 1, take.frames());
  return signing::ExtractClip(take, first, end - first);
}

}  // namespace

std::string SignSequenceOptions::Check() const {
  if (corpus.empty()) return "no corpus given";
  if (glosses.empty()) return "give the glosses of the sequence (--glosses A,B,C)";
  for (const std::string& g : glosses) {
    if (g.empty()) return "an empty gloss in --glosses";
  }
  if (tier.empty()) return "--tier must name the sign tier";
  if (method != "blend" && method != "interpolate")
    return "--method must be blend or interpolate, not '" + method + "'";
  if (!model.empty()) {
    try {
      signing::ParseDurationModel(model);
    } catch (const InvalidInput& e) {
      return std::string("--model: ") + e.what();
    }
  }
  if (output.empty()) return "give the output BVH file with -o";
  return "";
}

json SignSequence(const SignSequenceOptions& options, Progress& progress) {
  if (std::string why = options.Check(); !why.empty()) throw UsageError(why);
  const DurationSource durations = LoadDurations(options);
  const Corpus corpus = Corpus::Open(options.corpus);
  const std::vector<TakeRange> ranges = SelectCorpusTakes(corpus, options.takes);
  std::vector<Take> takes;
  std::vector<std::string> skipped;
  for (size_t i = 0; i < ranges.size(); ++i) {
    progress.Update("sign sequence: loading", static_cast<double>(i) / static_cast<double>(ranges.size()));
    progress.CheckCancel();
    Take take = corpus.LoadTake(ranges[i].take);
    if (FindTier(take.tiers, options.tier) == nullptr) continue;
    if (take.skeleton.empty() || take.orientations.empty()) {
      skipped.push_back(take.name + " (no skeleton)");
      continue;
    }
    if (!takes.empty() && take.marker_names != takes.front().marker_names) {
      skipped.push_back(take.name + " (another skeleton than " + takes.front().name + ")");
      continue;
    }
    if (!takes.empty() && std::abs(take.rate_hz - takes.front().rate_hz) > 1e-9 * take.rate_hz) {
      skipped.push_back(take.name + " (another frame rate than " + takes.front().name + ")");
      continue;
    }
    takes.push_back(std::move(take));
  }
  if (takes.empty()) {
    throw InvalidInput(options.corpus + ": no selected skeleton take has a tier '" + options.tier +
                       "'; name the sign tier with --tier");
  }
  const double rate = takes.front().rate_hz;

  // Candidates per gloss.
  std::vector<std::vector<Occurrence>> occurrences(options.glosses.size());
  std::set<std::string> known;
  for (size_t t = 0; t < takes.size(); ++t) {
    const LabelTier* tier = FindTier(takes[t].tiers, options.tier);
    for (const Label& l : tier->labels) {
      known.insert(l.text);
      for (size_t g = 0; g < options.glosses.size(); ++g) {
        if (l.text != options.glosses[g]) continue;
        Occurrence o;
        o.take = t;
        o.start_s = l.start_s;
        o.end_s = l.end_s;
        o.first = std::clamp<int64_t>(std::llround(l.start_s * rate), 0, takes[t].frames() - 1);
        o.last = std::clamp<int64_t>(std::llround(l.end_s * rate), o.first, takes[t].frames() - 1);
        occurrences[g].push_back(o);
      }
    }
  }
  for (size_t g = 0; g < options.glosses.size(); ++g) {
    if (occurrences[g].empty()) {
      std::string list;
      int shown = 0;
      for (const std::string& k : known) {
        if (k.empty() || signing::SignTypeCode(k) != "" || k == "rest" || k == "transition" || k == "preparation" ||
            k == "retraction")
          continue;
        if (shown++ < 30) list += (list.empty() ? "" : ", ") + k;
      }
      throw InvalidInput(options.corpus + ": gloss '" + options.glosses[g] + "' occurs in no tier '" + options.tier +
                         "' of the selected takes (glosses there: " + (list.empty() ? "none" : list) + ")");
    }
  }
  progress.Update("sign sequence: retrieval", 0.0);
  std::vector<std::vector<signing::Clip>> clips(options.glosses.size());
  for (size_t g = 0; g < occurrences.size(); ++g) {
    for (const Occurrence& o : occurrences[g]) {
      clips[g].push_back(signing::ExtractClip(takes[o.take], o.first, o.last - o.first + 1));
    }
  }
  const std::vector<size_t> chosen = signing::RetrieveSequence(clips, durations.unit_mm);

  // Joints the duration model measures over.
  std::vector<std::vector<int>> joint_sets;
  const Take& first_take = takes.front();
  if (durations.joints == "all") {
    joint_sets.push_back({});
  } else {
    const int right = FindWrist(first_take.skeleton, "right"), left = FindWrist(first_take.skeleton, "left");
    if (right < 0 || left < 0) {
      throw InvalidInput(options.durations + ": the models were fitted on arm joints, but the skeleton of take '" +
                         first_take.name + "' has no right and left wrist found by name");
    }
    joint_sets.push_back(signing::ArmJoints(first_take.skeleton, right, left));
    joint_sets.push_back(signing::ArmJoints(first_take.skeleton, left, right));
  }

  json result = {{"corpus", options.corpus}, {"method", options.method}, {"model", durations.description},
                 {"rate_hz", rate},          {"signs", json::array()},   {"transitions", json::array()},
                 {"skipped_takes", skipped}};
  signing::Clip sequence;
  LabelTier signs_tier{"signs", LabelTier::Kind::kInterval, 0.0, 0.0, {}};
  LabelTier source_tier{"source", LabelTier::Kind::kInterval, 0.0, 0.0, {}};
  for (size_t g = 0; g < options.glosses.size(); ++g) {
    progress.Update("sign sequence: synthesis", static_cast<double>(g) / static_cast<double>(options.glosses.size()));
    progress.CheckCancel();
    const Occurrence& o = occurrences[g][chosen[g]];
    const signing::Clip& sign = clips[g][chosen[g]];
    if (g > 0) {
      const Occurrence& p = occurrences[g - 1][chosen[g - 1]];
      const signing::Clip& prev = clips[g - 1][chosen[g - 1]];
      double duration = 0;
      signing::Transition measured;
      for (const std::vector<int>& joints : joint_sets) {
        const signing::Transition t = signing::MeasureBetween(prev, sign, joints, durations.unit_mm);
        const double d = durations.model.Predict(t);
        if (d >= duration) {
          duration = d;
          measured = t;
        }
      }
      const int64_t n = signing::TransitionFrames(duration, rate);
      signing::Clip motion;
      if (options.method == "interpolate") {
        motion = signing::InterpolateTransition(prev, sign, n);
      } else {
        const signing::Clip retraction = ClampedClip(takes[p.take], p.last, p.last + n + 2);
        const signing::Clip preparation = ClampedClip(takes[o.take], o.first - n - 1, o.first + 1);
        // The blend's ends are the retraction's first and the preparation's
        // last frames: the bounding postures themselves, dropped here.
        signing::Clip blend = signing::BlendTransition(retraction, preparation, n + 2, options.smooth);
        motion = blend;
        motion.frames = n;
        motion.positions.assign(blend.positions.begin() + blend.joints, blend.positions.end() - blend.joints);
        motion.orientations.assign(blend.orientations.begin() + blend.joints, blend.orientations.end() - blend.joints);
      }
      const double start = static_cast<double>(sequence.frames - 1) / rate;
      sequence = signing::Concatenate(sequence, motion);
      const double end = static_cast<double>(sequence.frames) / rate;
      signs_tier.labels.push_back({start, end, "transition"});
      result["transitions"].push_back({{"from", options.glosses[g - 1]},
                                       {"to", options.glosses[g]},
                                       {"duration_s", Round(static_cast<double>(n + 1) / rate, 1e-6)},
                                       {"model_s", Round(duration, 1e-6)},
                                       {"geodesic", Round(measured.geodesic, 1e-6)},
                                       {"euclidean", Round(measured.euclidean, 1e-6)}});
    }
    const double start = static_cast<double>(sequence.frames) / rate;
    sequence = signing::Concatenate(sequence, sign);
    const double end = static_cast<double>(sequence.frames - 1) / rate;
    signs_tier.labels.push_back({start, end, options.glosses[g]});
    std::ostringstream src;
    src << takes[o.take].name << " " << Round(o.start_s, 1e-3) << "-" << Round(o.end_s, 1e-3) << " s";
    source_tier.labels.push_back({start, end, src.str()});
    result["signs"].push_back({{"gloss", options.glosses[g]},
                               {"take", takes[o.take].name},
                               {"start_s", Round(o.start_s, 1e-6)},
                               {"end_s", Round(o.end_s, 1e-6)},
                               {"candidates", occurrences[g].size()}});
  }

  Take out;
  out.name = std::filesystem::path(options.output).stem().string();
  out.rate_hz = rate;
  out.skeleton = first_take.skeleton;
  out.marker_names = first_take.marker_names;
  out.source_units = first_take.source_units;
  out.markers.Resize(sequence.frames, sequence.joints);
  out.orientations.Resize(sequence.frames, sequence.joints);
  for (int64_t f = 0; f < sequence.frames; ++f) {
    for (int j = 0; j < sequence.joints; ++j) {
      const Eigen::Vector3d& p = sequence.position(f, j);
      Eigen::Quaterniond q = sequence.orientation(f, j).normalized();
      if (q.w() < 0) q.coeffs() *= -1;
      float* m = out.markers.at(f, j);
      float* o = out.orientations.at(f, j);
      for (int k = 0; k < 3; ++k) m[k] = static_cast<float>(p(k));
      o[0] = static_cast<float>(q.w());
      o[1] = static_cast<float>(q.x());
      o[2] = static_cast<float>(q.y());
      o[3] = static_cast<float>(q.z());
    }
  }
  const double duration = out.duration_s();
  // The tiers end at the last frame's time, where the last sign ends.
  signs_tier.end_s = source_tier.end_s = static_cast<double>(out.frames() - 1) / rate;
  std::filesystem::path tg = options.output;
  tg.replace_extension(".TextGrid");
  if (const std::filesystem::path dir = std::filesystem::path(options.output).parent_path(); !dir.empty()) {
    std::error_code ec;
    std::filesystem::create_directories(dir, ec);
    if (ec) throw IoError(options.output, "cannot create its folder: " + ec.message());
  }
  WriteBvh(options.output, out);
  WriteTextGrid(tg.string(), {FillIntervalGaps(signs_tier), FillIntervalGaps(source_tier)}, 0.0, duration);
  result["output"] = options.output;
  result["textgrid"] = tg.string();
  result["frames"] = out.frames();
  result["duration_s"] = Round(duration, 1e-6);
  progress.Update("sign sequence", 1.0);
  return result;
}

std::string SignSequenceText(const json& r) {
  std::ostringstream o;
  char buf[256];
  o << "sign sequence: " << r["signs"].size() << " signs, " << r["frames"].get<int64_t>() << " frames at "
    << r["rate_hz"].get<double>() << " Hz (" << r["duration_s"].get<double>() << " s), "
    << r["method"].get<std::string>() << " transitions, durations by " << r["model"].get<std::string>() << "\n";
  for (size_t i = 0; i < r["signs"].size(); ++i) {
    const json& s = r["signs"][i];
    std::snprintf(buf, sizeof(buf), "  %-16s from %s %.3f-%.3f s (%d candidates)\n",
                  s["gloss"].get<std::string>().c_str(), s["take"].get<std::string>().c_str(),
                  s["start_s"].get<double>(), s["end_s"].get<double>(), s["candidates"].get<int>());
    o << buf;
    if (i < r["transitions"].size()) {
      const json& t = r["transitions"][i];
      std::snprintf(buf, sizeof(buf), "    transition %.3f s (G %.3f rad, E %.3f)\n", t["duration_s"].get<double>(),
                    t["geodesic"].get<double>(), t["euclidean"].get<double>());
      o << buf;
    }
  }
  for (const json& s : r["skipped_takes"]) o << "skipped take " << s.get<std::string>() << "\n";
  o << "written: " << r["output"].get<std::string>() << " and " << r["textgrid"].get<std::string>() << "\n";
  return o.str();
}

}  // namespace csw::jobs
