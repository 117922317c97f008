#include "workbench/jobs/invert_job.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <functional>
#include <map>
#include <memory>
#include <random>
#include <set>

#include "core/error.h"
#include "core/markerset.h"
#include "io/c3d/c3d.h"
#include "io/corpus/corpus.h"
#include "io/models/model_file.h"
#include "models/face_model.h"
#include "models/hand_model.h"
#include "models/rigid_model.h"
#include "workbench/jobs/figures.h"
#include "workbench/jobs/model_config.h"
#include "workbench/jobs/model_reports.h"
#include "workbench/jobs/parallel_for.h"
#include "workbench/jobs/take_data.h"

namespace csw::jobs {

namespace fs = std::filesystem;
using nlohmann::json;

std::string InvertOptions::Check() const {
  if (corpus.empty()) return "no corpus given";
  if (models.empty()) return "no model file given (--models)";
  if (!only.empty() && only != "face" && only != "hand") return "--only must be face or hand";
  if (!(hide_fraction >= 0 && hide_fraction < 1)) return "--hide must be in [0, 1)";
  if (threads < 0) return "--threads must be >= 0";
  if (worst_frames < 0) return "--worst-frames must be >= 0";
  if (inversion.max_iterations < 1) return "--max-iterations must be >= 1";
  if (!(inversion.prior_mm >= 0)) return "--prior must be >= 0";
  return "";
}

namespace {

// One model to invert.
struct ModelRun {
  std::string kind;  // "face" or "hand"
  const FaceModel* face = nullptr;
  const HandModel* hand = nullptr;
  MarkerSet set;
  std::vector<std::string> names;     // model order
  int cluster = 0;                    // cluster markers first
  std::vector<std::string> training;  // training take specs of the model
  double target_mm = 0;
  const RigidModel& rigid() const { return face ? face->head : hand->forearm; }
};

// One (model, take) pair.
struct TakeJob {
  const ModelRun* run = nullptr;
  TakeRange range;
  MarkerArray original;                         // model order
  MarkerArray input;                            // after hiding
  std::vector<std::pair<int64_t, int>> hidden;  // (frame, column) hidden on purpose
  MarkerArray truth;                            // clean markers (model order), empty when none
  InversionResult result;
  MarkerArray model_only;           // reconstruction before the gap correction
  std::string role;                 // "training" or "held_out"
  double rate_hz = 0;               // the take's frame rate
  std::vector<FrameReport> frames;  // per frame of the range
};

double Distance(const float* a, const float* b);

// The per-frame report of one inverted (model, take) pair, from the solve's
// per-frame results and errors.
std::vector<FrameReport> MakeFrameReports(const TakeJob& job) {
  const ModelRun& run = *job.run;
  const InversionResult& res = job.result;
  const int nm = static_cast<int>(run.names.size());
  std::vector<FrameReport> out(static_cast<size_t>(res.frames()));
  for (int64_t f = 0; f < res.frames(); ++f) {
    FrameReport& r = out[static_cast<size_t>(f)];
    const size_t fi = static_cast<size_t>(f);
    r.take = job.range.take;
    r.frame = job.range.first + f;
    r.time_s = job.rate_hz > 0 ? static_cast<double>(r.frame) / job.rate_hz : 0.0;
    r.model = run.kind;
    for (int c = 0; c < nm; ++c) {
      if (job.input.Visible(f, c)) (c < run.cluster ? r.cluster_visible : r.shape_visible)++;
    }
    ErrorStats e;
    int worst = -1;
    for (int c = run.cluster; c < nm; ++c) {
      const double v = res.error_mm(f, c);
      if (!std::isfinite(v)) continue;
      e.Add(v);
      if (worst < 0 || v > res.error_mm(f, worst)) worst = c;
    }
    r.mean_error_mm = e.count > 0 ? e.mean : std::nan("");
    r.max_error_mm = e.count > 0 ? e.max : std::nan("");
    r.max_marker = worst >= 0 ? run.names[static_cast<size_t>(worst)] : "";
    r.status = res.status[fi];
    r.iterations = res.iterations[fi];
    r.cold_start = res.cold_start[fi] != 0;
    r.cold_retry = res.cold_retry[fi] != 0;
    r.hidden_mean_mm = r.hidden_max_mm = std::nan("");
  }
  std::vector<ErrorStats> hidden(out.size());
  for (const auto& [f, c] : job.hidden) {
    const float* rec = res.reconstructed.at(f, c);
    if (!IsMissing(rec[0])) hidden[static_cast<size_t>(f)].Add(Distance(rec, job.original.at(f, c)));
  }
  for (size_t f = 0; f < out.size(); ++f) {
    if (hidden[f].count == 0) continue;
    out[f].hidden = static_cast<int>(hidden[f].count);
    out[f].hidden_mean_mm = hidden[f].mean;
    out[f].hidden_max_mm = hidden[f].max;
  }
  return out;
}

std::vector<std::unique_ptr<ModelRun>> MakeRuns(const ModelFile& models, const InvertOptions& options) {
  std::vector<std::unique_ptr<ModelRun>> runs;
  auto make_run = [&](const std::string& kind, const ModelInfo& info, std::vector<std::string> names, int cluster,
                      double target) {
    auto r = std::make_unique<ModelRun>();
    r->kind = kind;
    r->set = MarkerSetOfModel(info, options.models);
    r->names = std::move(names);
    r->cluster = cluster;
    r->target_mm = target;
    r->training = info.training_takes;
    return r;
  };
  if (models.face && options.only != "hand") {
    const FaceLayout& l = models.face->layout;
    std::vector<std::string> names = l.head;
    names.insert(names.end(), l.face.begin(), l.face.end());
    names.insert(names.end(), l.throat.begin(), l.throat.end());
    auto r = make_run("face", models.face->info, names, static_cast<int>(l.head.size()), 1.0);
    r->face = &*models.face;
    runs.push_back(std::move(r));
  }
  if (models.hand && options.only != "face") {
    const HandLayout& l = models.hand->layout;
    std::vector<std::string> names = l.forearm;
    names.insert(names.end(), l.hand.begin(), l.hand.end());
    auto r = make_run("hand", models.hand->info, names, static_cast<int>(l.forearm.size()), 2.0);
    r->hand = &*models.hand;
    runs.push_back(std::move(r));
  }
  if (runs.empty()) {
    throw InvalidInput(options.models + ": no " + (options.only.empty() ? "face or hand" : options.only) +
                       " model in the file");
  }
  return runs;
}

// Loads every (model, take) pair; hides samples; reads the truth.
std::vector<std::unique_ptr<TakeJob>> LoadJobs(const Corpus& corpus, const std::vector<TakeRange>& ranges,
                                               const std::vector<std::unique_ptr<ModelRun>>& runs,
                                               const InvertOptions& options, Progress& progress, json* skipped) {
  std::vector<std::unique_ptr<TakeJob>> jobs;
  for (size_t i = 0; i < ranges.size(); ++i) {
    progress.Update("loading takes", static_cast<double>(i) / static_cast<double>(ranges.size()));
    const Take take = corpus.LoadTake(ranges[i].take);
    const std::string where = corpus.path() + ": take '" + ranges[i].take + "'";
    if (options.skip_unbound) {
      try {
        for (const auto& run : runs) BindNames(run->set, take.marker_names, run->names, where);
      } catch (const InvalidInput& e) {
        skipped->push_back({{"take", ranges[i].spec}, {"reason", e.what()}});
        continue;
      }
    }
    Take clean;
    if (!options.truth.empty()) {
      const fs::path p = fs::path(options.truth) / (ranges[i].take + ".clean.c3d");
      if (fs::exists(p)) clean = ReadC3d(p.string());
    }
    for (const auto& run : runs) {
      auto job = std::make_unique<TakeJob>();
      job->run = run.get();
      job->range = ranges[i];
      const std::vector<int> cols = BindNames(run->set, take.marker_names, run->names, where);
      job->original = Extract(take.markers, cols, ranges[i].first, ranges[i].count);
      job->input = job->original;
      if (options.hide_fraction > 0) {
        std::vector<std::pair<int64_t, int>> visible;
        for (int64_t f = 0; f < job->input.frames(); ++f)
          for (int c = run->cluster; c < static_cast<int>(run->names.size()); ++c)
            if (job->input.Visible(f, c)) visible.emplace_back(f, c);
        std::mt19937_64 rng(options.seed ^ std::hash<std::string>{}(ranges[i].spec + "/" + run->kind));
        std::shuffle(visible.begin(), visible.end(), rng);
        visible.resize(static_cast<size_t>(std::floor(options.hide_fraction * static_cast<double>(visible.size()))));
        for (const auto& [f, c] : visible) job->input.SetMissing(f, c);
        job->hidden = std::move(visible);
      }
      if (!clean.marker_names.empty()) {
        if (clean.frames() != take.frames()) {
          throw InvalidInput(options.truth + ": " + ranges[i].take + ".clean.c3d has " +
                             std::to_string(clean.frames()) + " frames, the take " + std::to_string(take.frames()));
        }
        const std::vector<int> tc =
            BindNames(run->set, clean.marker_names, run->names, options.truth + "/" + ranges[i].take + ".clean.c3d");
        job->truth = Extract(clean.markers, tc, ranges[i].first, ranges[i].count);
      }
      job->rate_hz = take.rate_hz;
      job->role = "held_out";
      for (const std::string& spec : run->training) {
        if (TrainingSpecOverlaps(spec, ranges[i], take.frames())) job->role = "training";
      }
      jobs.push_back(std::move(job));
    }
  }
  return jobs;
}

double Distance(const float* a, const float* b) {
  return std::sqrt(std::pow(double(a[0]) - b[0], 2) + std::pow(double(a[1]) - b[1], 2) +
                   std::pow(double(a[2]) - b[2], 2));
}

// Error statistics of one model over its jobs, into the summary; figures.
json Score(const ModelRun& run, const std::vector<std::unique_ptr<TakeJob>>& jobs, const InvertOptions& options,
           json& summary) {
  json takes = json::array();
  std::map<std::string, ErrorSamples> visible_by_role, hidden_by_role, occluded_by_role, hidden_model_by_role,
      occluded_model_by_role;
  ErrorSamples rot_err, trans_err;
  // Per model marker (cluster markers included), pooled over takes.
  const size_t n_markers = run.names.size();
  std::vector<ErrorSamples> marker_visible(n_markers), marker_hidden(n_markers), marker_occluded(n_markers);
  std::vector<const FrameReport*> worst;  // frames with a visible error
  std::vector<report::ErrorBar> bars;
  for (const auto& jp : jobs) {
    const TakeJob& job = *jp;
    if (job.run != &run) continue;
    const InversionResult& res = job.result;
    const int nm = static_cast<int>(run.names.size());
    ErrorSamples visible, hidden, occluded, hidden_model, occluded_model, rot, trans;
    for (const FrameReport& r : job.frames) {
      if (std::isfinite(r.max_error_mm)) worst.push_back(&r);
    }
    for (int64_t f = 0; f < res.frames(); ++f) {
      for (int c = 0; c < nm; ++c) marker_visible[static_cast<size_t>(c)].Add(res.error_mm(f, c));
      for (int c = run.cluster; c < nm; ++c) visible.Add(res.error_mm(f, c));
    }
    for (const auto& [f, c] : job.hidden) {
      const float* r = res.reconstructed.at(f, c);
      const float* o = job.original.at(f, c);
      if (IsMissing(r[0])) continue;
      hidden.Add(Distance(r, o));
      marker_hidden[static_cast<size_t>(c)].Add(Distance(r, o));
      hidden_model.Add(Distance(job.model_only.at(f, c), o));
    }
    if (!job.truth.empty()) {
      for (int64_t f = 0; f < res.frames(); ++f) {
        for (int c = run.cluster; c < nm; ++c) {
          const float* r = res.reconstructed.at(f, c);
          const float* t = job.truth.at(f, c);
          if (job.original.Visible(f, c) || IsMissing(r[0]) || IsMissing(t[0])) continue;
          occluded.Add(Distance(r, t));
          marker_occluded[static_cast<size_t>(c)].Add(Distance(r, t));
          occluded_model.Add(Distance(job.model_only.at(f, c), t));
        }
        if (!res.solved[static_cast<size_t>(f)]) continue;
        Eigen::Matrix3Xd obs(3, run.cluster);
        for (int c = 0; c < run.cluster; ++c)
          for (int k = 0; k < 3; ++k) obs(k, c) = job.truth.at(f, c)[k];
        const RigidFit truth_pose = EstimateRigidKabsch(run.rigid().reference, obs);
        if (!truth_pose.valid) continue;
        const RigidTransform est = RigidTransform::FromParameters(res.pose.row(f).transpose().head<6>().eval());
        rot.Add(Eigen::AngleAxisd(est.rotation.transpose() * truth_pose.transform.rotation).angle() * 180.0 /
                3.14159265358979323846);
        trans.Add((est.translation - truth_pose.transform.translation).norm());
      }
    }
    const int64_t solved = std::count(res.solved.begin(), res.solved.end(), uint8_t{1});
    json t = {{"take", job.range.spec},       {"name", job.range.take},  {"first_frame", job.range.first},
              {"frames", res.frames()},       {"solved_frames", solved}, {"role", job.role},
              {"visible", StatsJson(visible)}};
    if (!job.hidden.empty()) {
      t["hidden"] = StatsJson(hidden);
      t["hidden_model"] = StatsJson(hidden_model);
    }
    if (!job.truth.empty()) {
      t["occluded"] = StatsJson(occluded);
      t["occluded_model"] = StatsJson(occluded_model);
      t["pose"] = {{"rotation_deg", StatsJson(rot, "deg")}, {"translation_mm", StatsJson(trans)}};
    }
    takes.push_back(t);
    visible_by_role[job.role].Merge(visible);
    hidden_by_role[job.role].Merge(hidden);
    occluded_by_role[job.role].Merge(occluded);
    hidden_model_by_role[job.role].Merge(hidden_model);
    occluded_model_by_role[job.role].Merge(occluded_model);
    rot_err.Merge(rot);
    trans_err.Merge(trans);
    bars.push_back({job.range.spec, visible.stats.mean, visible.stats.sd, visible.stats.max, job.role == "held_out"});
  }
  json m = {{"takes", takes}, {"target_mm", run.target_mm}};
  json per_marker = json::array();
  for (size_t c = 0; c < n_markers; ++c) {
    json e = {{"marker", run.names[c]},
              {"role", static_cast<int>(c) < run.cluster ? "cluster" : "shape"},
              {"visible", StatsJson(marker_visible[c])}};
    if (options.hide_fraction > 0) e["hidden"] = StatsJson(marker_hidden[c]);
    if (!options.truth.empty()) e["occluded"] = StatsJson(marker_occluded[c]);
    per_marker.push_back(e);
  }
  m["markers"] = per_marker;
  for (const char* role : {"training", "held_out"}) {
    json r = {{"visible", StatsJson(visible_by_role[role])}};
    if (options.hide_fraction > 0) {
      r["hidden"] = StatsJson(hidden_by_role[role]);
      r["hidden_model"] = StatsJson(hidden_model_by_role[role]);
    }
    if (!options.truth.empty()) {
      r["occluded"] = StatsJson(occluded_by_role[role]);
      r["occluded_model"] = StatsJson(occluded_model_by_role[role]);
    }
    m[role] = r;
  }
  auto pooled = [](const std::map<std::string, ErrorSamples>& by_role) {
    ErrorSamples a;
    for (const auto& [k, v] : by_role) a.Merge(v);
    return StatsJson(a);
  };
  m["overall"] = {{"visible", pooled(visible_by_role)}};
  if (options.hide_fraction > 0) {
    m["overall"]["hidden"] = pooled(hidden_by_role);
    m["overall"]["hidden_model"] = pooled(hidden_model_by_role);
  }
  if (!options.truth.empty()) {
    m["overall"]["occluded"] = pooled(occluded_by_role);
    m["overall"]["occluded_model"] = pooled(occluded_model_by_role);
    m["overall"]["pose"] = {{"rotation_deg", StatsJson(rot_err, "deg")}, {"translation_mm", StatsJson(trans_err)}};
  }
  // Worst first; ties in take and frame order (the order collected).
  const size_t n_worst = std::min(worst.size(), static_cast<size_t>(options.worst_frames));
  std::stable_sort(worst.begin(), worst.end(),
                   [](const FrameReport* a, const FrameReport* b) { return a->max_error_mm > b->max_error_mm; });
  m["worst_frames"] = json::array();
  for (size_t i = 0; i < n_worst; ++i) m["worst_frames"].push_back(FrameJson(*worst[i]));
  if (!options.figures.empty()) {
    fs::create_directories(options.figures);
    for (const char* ext : {".png", ".svg"}) {
      const std::string p = (fs::path(options.figures) / (run.kind + "_errors" + ext)).string();
      figures::SaveErrorBars(
          p, run.kind == "face" ? "Face: reconstruction error per take" : "Hand: reconstruction error per take", bars,
          run.target_mm);
      summary["figures"].push_back(p);
    }
  }
  return m;
}

// Every frame of every job: take (selection order), frame, model. LoadJobs
// makes the jobs take by take, one per model (`models` of them) in run order.
template <typename Visit>
void ForEachFrameInCsvOrder(const std::vector<std::unique_ptr<TakeJob>>& jobs, size_t models, Visit&& visit) {
  for (size_t a = 0; a + models <= jobs.size(); a += models) {
    for (size_t f = 0; f < jobs[a]->frames.size(); ++f) {
      for (size_t j = a; j < a + models; ++j) visit(jobs[j]->frames[f]);
    }
  }
}

void WriteFramesCsv(const std::vector<std::unique_ptr<TakeJob>>& jobs, size_t models, const std::string& path) {
  std::ofstream out(path);
  if (!out) throw IoError(path, "cannot open for writing");
  out << FrameCsvHeader() << "\n";
  ForEachFrameInCsvOrder(jobs, models, [&](const FrameReport& r) { out << FrameCsvRow(r) << "\n"; });
  out.close();
  if (!out) throw IoError(path, "write failed");
}

// Write-back: one new take version per take, in one transaction.
json WriteFilled(const Corpus& corpus, const std::vector<TakeRange>& ranges,
                 const std::vector<std::unique_ptr<TakeJob>>& jobs, const InvertOptions& options, Progress& progress) {
  progress.Update("writing filled takes", 0.0);
  CorpusTransaction tx(options.corpus);
  std::set<std::string> existing;
  for (const auto& n : tx.TakeNames()) existing.insert(n);
  json filled = json::array();
  for (size_t i = 0; i < ranges.size(); ++i) {
    Take take = corpus.LoadTake(ranges[i].take);
    int64_t count = 0;
    std::vector<std::string> models_used;
    for (const auto& jp : jobs) {
      const TakeJob& job = *jp;
      if (job.range.spec != ranges[i].spec) continue;
      models_used.push_back(job.run->kind);
      const std::vector<int> cols = BindNames(job.run->set, take.marker_names, job.run->names, ranges[i].take);
      for (int64_t f = 0; f < job.result.frames(); ++f) {
        for (size_t c = 0; c < cols.size(); ++c) {
          float* dst = take.markers.at(ranges[i].first + f, cols[c]);
          const float* src = job.result.reconstructed.at(f, static_cast<int64_t>(c));
          if (!IsMissing(dst[0]) || IsMissing(src[0])) continue;
          std::copy(src, src + 3, dst);
          ++count;
        }
      }
    }
    take.name = FilledTakeName(existing, ranges[i].take);
    existing.insert(take.name);
    std::string used;
    for (const auto& u : models_used) used += (used.empty() ? "" : "+") + u;
    take.provenance.warnings.push_back("gaps filled by csw invert (" + used + " model from " + options.models +
                                       ") from take '" + ranges[i].spec + "': " + std::to_string(count) + " samples");
    tx.WriteTake(take);
    filled.push_back({{"take", ranges[i].spec}, {"filled_take", take.name}, {"samples_filled", count}});
    progress.Update("writing filled takes", static_cast<double>(i + 1) / static_cast<double>(ranges.size()));
  }
  tx.Commit();
  return filled;
}

}  // namespace

json Invert(const InvertOptions& options, Progress& progress) { return Invert(options, progress, nullptr); }

json Invert(const InvertOptions& options, Progress& progress, std::vector<FrameReport>* frames) {
  if (const std::string why = options.Check(); !why.empty()) throw InvalidInput(why);
  const ModelFile models = LoadModelFile(options.models);
  const Corpus corpus = Corpus::Open(options.corpus);
  std::vector<TakeRange> ranges = SelectCorpusTakes(corpus, options.takes);
  if (!options.figures.empty()) figures::Require();  // before any work
  const std::vector<std::unique_ptr<ModelRun>> runs = MakeRuns(models, options);
  json skipped = json::array();
  const std::vector<std::unique_ptr<TakeJob>> jobs = LoadJobs(corpus, ranges, runs, options, progress, &skipped);
  if (!skipped.empty()) {
    if (jobs.empty()) {
      throw InvalidInput("no selected take holds the models' markers: " + skipped.front()["reason"].get<std::string>());
    }
    std::erase_if(ranges, [&](const TakeRange& r) {
      for (const json& k : skipped)
        if (k["take"] == r.spec) return true;
      return false;
    });
  }

  // Invert in parallel over (model, take) pairs.
  ParallelFor(jobs.size(), options.threads, "inverting", progress, [&](size_t j, Progress& item) {
    TakeJob& job = *jobs[j];
    job.result = job.run->face ? InvertFace(*job.run->face, job.input, options.inversion, &item)
                               : InvertHand(*job.run->hand, job.input, options.inversion, &item);
    job.model_only = job.result.reconstructed;
    // A hand whose gaps the Gaussian filler reconstructed (not the shape
    // model) gets the filler's edge misfit, measured with each frame's
    // pattern of seen markers; the others the model's.
    const bool gaussian = job.run->hand && !job.run->hand->fill.empty() && options.inversion.gaussian_fill;
    if (options.edge_correction && !gaussian) CorrectGapsWithEdgeResiduals(job.input, &job.result);
    if (options.edge_correction && gaussian) CorrectFilledGapsWithEdgeMisfits(*job.run->hand, job.input, &job.result);
    job.frames = MakeFrameReports(job);
  });

  json summary;
  summary["corpus"] = options.corpus;
  summary["models"] = options.models;
  summary["figures"] = json::array();
  if (options.skip_unbound) summary["skipped_takes"] = skipped;
  for (const auto& run : runs) {
    json scores = Score(*run, jobs, options, summary);
    summary[run->kind] = std::move(scores);
  }
  if (!options.frames_csv.empty()) {
    WriteFramesCsv(jobs, runs.size(), options.frames_csv);
    summary["frames_csv"] = options.frames_csv;
  }
  if (frames != nullptr) {
    frames->clear();
    ForEachFrameInCsvOrder(jobs, runs.size(), [&](const FrameReport& r) { frames->push_back(r); });
  }
  if (options.fill) summary["filled"] = WriteFilled(corpus, ranges, jobs, options, progress);
  return summary;
}

namespace {

std::string CsvField(const std::string& v) {
  if (v.find_first_of(",\"\r\n") == std::string::npos) return v;
  std::string q = "\"";
  for (char ch : v) q += ch == '"' ? std::string("\"\"") : std::string(1, ch);
  return q + "\"";
}

std::string Number(double v, const char* format) {
  if (!std::isfinite(v)) return "";
  char buf[32];
  std::snprintf(buf, sizeof(buf), format, v);
  return buf;
}

}  // namespace

std::string FrameCsvHeader() {
  return "take,frame,time_s,model,cluster_visible,shape_visible,mean_error_mm,max_error_mm,max_error_marker,"
         "status,iterations,start,cold_retry,hidden,hidden_mean_mm,hidden_max_mm";
}

std::string FrameCsvRow(const FrameReport& r) {
  std::string s = CsvField(r.take) + "," + std::to_string(r.frame) + "," + Number(r.time_s, "%.6f") + "," + r.model +
                  "," + std::to_string(r.cluster_visible) + "," + std::to_string(r.shape_visible) + "," +
                  Number(r.mean_error_mm, "%.4f") + "," + Number(r.max_error_mm, "%.4f") + "," +
                  CsvField(r.max_marker) + "," + FrameStatusName(r.status) + "," + std::to_string(r.iterations) + ",";
  const bool solved = r.status == FrameStatus::kConverged || r.status == FrameStatus::kMaxIterations;
  s += solved ? (r.cold_start ? "cold" : "warm") : "";
  s += r.cold_retry ? ",yes" : ",no";
  s += "," + std::to_string(r.hidden) + "," + Number(r.hidden_mean_mm, "%.4f") + "," + Number(r.hidden_max_mm, "%.4f");
  return s;
}

json FrameJson(const FrameReport& r) {
  const bool solved = r.status == FrameStatus::kConverged || r.status == FrameStatus::kMaxIterations;
  json j = {{"take", r.take},
            {"frame", r.frame},
            {"time_s", r.time_s},
            {"model", r.model},
            {"cluster_visible", r.cluster_visible},
            {"shape_visible", r.shape_visible},
            {"status", FrameStatusName(r.status)},
            {"iterations", r.iterations},
            {"start", solved ? (r.cold_start ? "cold" : "warm") : ""},
            {"cold_retry", r.cold_retry}};
  if (std::isfinite(r.max_error_mm)) {
    j["mean_error_mm"] = r.mean_error_mm;
    j["max_error_mm"] = r.max_error_mm;
    j["max_error_marker"] = r.max_marker;
  }
  if (r.hidden > 0) {
    j["hidden"] = r.hidden;
    j["hidden_mean_mm"] = r.hidden_mean_mm;
    j["hidden_max_mm"] = r.hidden_max_mm;
  }
  return j;
}

MarkerArray ModelReconstruction(const Take& take, const InvertOptions& options, const std::string& where,
                                Progress& progress) {
  const ModelFile models = LoadModelFile(options.models);
  const std::vector<std::unique_ptr<ModelRun>> runs = MakeRuns(models, options);
  MarkerArray out(take.frames(), take.markers.markers());
  for (const auto& run : runs) {
    const std::vector<int> cols = BindNames(run->set, take.marker_names, run->names, where);
    const MarkerArray input = Extract(take.markers, cols, 0, take.frames());
    InversionResult result = run->face ? InvertFace(*run->face, input, options.inversion, &progress)
                                       : InvertHand(*run->hand, input, options.inversion, &progress);
    const bool gaussian = run->hand && !run->hand->fill.empty() && options.inversion.gaussian_fill;
    if (options.edge_correction && !gaussian) CorrectGapsWithEdgeResiduals(input, &result);
    if (options.edge_correction && gaussian) CorrectFilledGapsWithEdgeMisfits(*run->hand, input, &result);
    for (int64_t f = 0; f < result.frames(); ++f) {
      for (size_t c = 0; c < cols.size(); ++c) {
        const float* src = result.reconstructed.at(f, static_cast<int64_t>(c));
        if (!IsMissing(src[0])) std::copy(src, src + 3, out.at(f, cols[c]));
      }
    }
  }
  return out;
}

}  // namespace csw::jobs
