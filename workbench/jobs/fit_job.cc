#include "workbench/jobs/fit_job.h"

#include <cmath>
#include <filesystem>
#include <map>

#include "core/error.h"
#include "core/file_util.h"
#include "core/markerset.h"
#include "io/corpus/corpus.h"
#include "io/models/model_file.h"
#include "models/face_model.h"
#include "models/hand_model.h"
#include "models/inversion.h"
#include "models/rigid_model.h"
#include "workbench/jobs/figures.h"
#include "workbench/jobs/job_util.h"
#include "workbench/jobs/model_config.h"
#include "workbench/jobs/model_reports.h"
#include "workbench/jobs/take_data.h"

namespace csw::jobs {

namespace fs = std::filesystem;
using nlohmann::json;

namespace {

// Sets where a model came from, keeping its fit statistics (training frames,
// residual), which inversion uses (e.g. the hand's forearm weighting).
void WithProvenance(const ModelInfo& from, ModelInfo* to) {
  to->corpus = from.corpus;
  to->training_takes = from.training_takes;
  to->config_json = from.config_json;
  to->created_utc = from.created_utc;
  to->csw_version = from.csw_version;
}

std::vector<std::pair<int, int>> SticksOf(const MarkerSet& set, const std::vector<std::string>& names) {
  std::map<std::string, int> idx;
  for (size_t i = 0; i < names.size(); ++i) idx[names[i]] = static_cast<int>(i);
  std::vector<std::pair<int, int>> out;
  for (const auto& [a, b] : set.sticks) {
    if (idx.count(a) && idx.count(b)) out.emplace_back(idx[a], idx[b]);
  }
  return out;
}

Eigen::Matrix3Xd AsPoints(const Eigen::VectorXd& coords) {
  return Eigen::Map<const Eigen::Matrix3Xd>(coords.data(), 3, coords.size() / 3);
}

// Context shared by the three kinds of fit.
struct FitContext {
  const FitOptions& options;
  const ModelConfig& config;
  const MarkerSet& set;
  const std::string& set_file;
  const std::vector<TakeRange>& ranges;
  const ModelInfo& info;
  Progress& progress;
  json& summary;
  const Corpus& corpus;

  std::vector<MarkerArray> Load(const std::vector<std::string>& names) const {
    std::vector<MarkerArray> takes;
    for (size_t i = 0; i < ranges.size(); ++i) {
      progress.Update("loading takes", static_cast<double>(i) / static_cast<double>(ranges.size()));
      takes.push_back(LoadRange(corpus, ranges[i], set, names));
    }
    return takes;
  }
  // "<figures>/<stem>.png" and ".svg", drawn by `draw(path)` and listed in the summary.
  template <typename Draw>
  void Figure(const std::string& stem, Draw&& draw) const {
    fs::create_directories(options.figures);
    for (const char* ext : {".png", ".svg"}) {
      const std::string path = (fs::path(options.figures) / (stem + ext)).string();
      draw(path);
      summary["figures"].push_back(path);
    }
  }
  void ParameterFigures(const std::string& kind, const std::string& title, const std::vector<std::string>& names,
                        const std::vector<double>& variance, const Eigen::Matrix3Xd& neutral,
                        const std::vector<report::ParameterEffect>& effects,
                        const std::vector<std::pair<int, int>>& sticks) const {
    Figure(kind + "_variance",
           [&](const std::string& p) { figures::SaveVarianceExplained(p, title, names, variance); });
    Figure(kind + "_parameters", [&](const std::string& p) {
      figures::SaveParameterEffects(p,
                                    kind == "face" ? "Face model: each parameter at -2 sd (blue) and +2 sd (red)"
                                                   : "Hand model: each parameter at -2 sd (blue) and +2 sd (red)",
                                    neutral, effects, sticks);
    });
  }
};

// The residual of each training take's cluster markers after the best rigid
// fit of the model's reference shape (closed form), per take.
std::vector<ErrorStats> ClusterResiduals(const RigidModel& m, const std::vector<MarkerArray>& takes) {
  std::vector<int> cols(m.markers.size());
  for (size_t c = 0; c < cols.size(); ++c) cols[c] = static_cast<int>(c);
  RigidOptions closed_form;
  closed_form.loss = RobustLoss::kNone;
  std::vector<ErrorStats> out;
  for (const MarkerArray& t : takes) {
    const RigidSeries s = EstimateRigidSeries(t, cols, m.reference, closed_form);
    ErrorStats e;
    for (Eigen::Index f = 0; f < s.residual_mm.rows(); ++f)
      for (Eigen::Index c = 0; c < s.residual_mm.cols(); ++c) e.Add(s.residual_mm(f, c));
    out.push_back(e);
  }
  return out;
}

void FitRigid(const FitContext& x, ModelFile* update) {
  json models = json::array();
  auto fit_cluster = [&](const std::string& name, const std::vector<std::string>& markers) {
    const std::vector<MarkerArray> takes = x.Load(markers);
    RigidModel m = FitRigidModel(name, markers, takes, x.config.rigid, &x.progress);
    WithProvenance(x.info, &m.info);
    std::vector<double> ev(m.motion.explained_fraction.data(),
                           m.motion.explained_fraction.data() + m.motion.explained_fraction.size());
    const std::vector<ErrorStats> residuals = ClusterResiduals(m, takes);
    json per_take = json::array();
    std::vector<report::ErrorBar> bars;
    for (size_t i = 0; i < residuals.size(); ++i) {
      per_take.push_back({{"take", x.ranges[i].spec}, {"residual", StatsJson(residuals[i])}});
      bars.push_back({x.ranges[i].spec, residuals[i].mean, residuals[i].sd, residuals[i].max, false});
    }
    models.push_back({{"name", name},
                      {"markers", markers},
                      {"motion_parameters", m.motion.count()},
                      {"variance_explained", ev},
                      {"training_frames", m.info.training_frames},
                      {"rms_mm", m.info.training_rms_mm},
                      {"takes", per_take}});
    if (!x.options.figures.empty()) {
      std::vector<std::string> names;
      for (size_t k = 0; k < ev.size(); ++k) names.push_back("nm" + std::to_string(k + 1));
      x.Figure(name + "_residuals", [&](const std::string& p) {
        figures::SaveErrorBars(p, "Rigid " + name + " model: cluster residual per training take", bars, 0);
      });
      x.Figure(name + "_motion_variance", [&](const std::string& p) {
        figures::SaveVarianceExplained(p, "Rigid " + name + " model: motion variance explained", names, ev);
      });
    }
    return m;
  };
  if (x.set.head_cluster.size() >= 3) update->head = fit_cluster("head", x.set.head_cluster);
  if (x.set.forearm_cluster.size() >= 3) update->forearm = fit_cluster("forearm", x.set.forearm_cluster);
  if (!update->head && !update->forearm) {
    throw InvalidInput(x.set_file + ": the marker set has neither a head_cluster nor a forearm_cluster");
  }
  x.summary["rigid"] = models;
}

void FitFace(const FitContext& x, ModelFile* update) {
  const FaceLayout layout = MakeFaceLayout(x.set, x.set_file);
  FaceModelOptions fo;
  fo.steps = FaceSteps(x.config, layout, x.options.config.empty() ? x.set_file : x.options.config);
  fo.default_components = x.config.face_components;
  fo.min_distance_mm = x.config.min_distance_mm;
  fo.head = x.config.rigid;
  fo.throat_weight_rounds = x.config.throat_weight_rounds;
  std::vector<std::string> names = layout.head;
  names.insert(names.end(), layout.face.begin(), layout.face.end());
  names.insert(names.end(), layout.throat.begin(), layout.throat.end());
  FaceModel m = FitFaceModel(layout, x.Load(names), fo, &x.progress);
  WithProvenance(x.info, &m.info);
  WithProvenance(x.info, &m.head.info);
  json throat = json::array();
  for (size_t i = 0; i < layout.throat.size(); ++i) {
    const auto j = static_cast<Eigen::Index>(layout.face.size() + i);
    json offset = json::array({0.0, 0.0, 0.0});
    if (m.rotation_offsets.rows() > j)
      offset = {m.rotation_offsets(j, 0), m.rotation_offsets(j, 1), m.rotation_offsets(j, 2)};
    throat.push_back({{"marker", layout.throat[i]},
                      {"head_weight", m.head_weights(j)},
                      {"rotation_offset_mm", offset},
                      {"fitted", std::isnan(layout.throat_weights[i])}});
  }
  x.summary["face"] = {{"parameters", m.shape.parameter_names},
                       {"variance_explained", m.shape.variance_explained},
                       {"residual_variance", m.shape.residual_variance},
                       {"training_frames", m.info.training_frames},
                       {"selected_frames", m.info.selected_frames},
                       {"training_rms_mm", m.info.training_rms_mm},
                       {"throat", throat}};
  if (!x.options.figures.empty()) {
    std::vector<std::string> shape_names = layout.face;
    shape_names.insert(shape_names.end(), layout.throat.begin(), layout.throat.end());
    std::vector<report::ParameterEffect> effects;
    for (int k = 0; k < m.num_parameters(); ++k) {
      Eigen::VectorXd p = Eigen::VectorXd::Zero(m.num_parameters());
      p(k) = -2;
      const Eigen::Matrix3Xd low = AsPoints(m.shape.Predict(p));
      p(k) = 2;
      effects.push_back({m.shape.parameter_names[static_cast<size_t>(k)], low, AsPoints(m.shape.Predict(p))});
    }
    x.ParameterFigures("face", "Face model: variance explained", m.shape.parameter_names, m.shape.variance_explained,
                       AsPoints(m.shape.mean), effects, SticksOf(x.set, shape_names));
  }
  update->face = std::move(m);
}

void FitHand(const FitContext& x, ModelFile* update) {
  const HandLayout layout = MakeHandLayout(x.set, x.set_file);
  HandModelOptions ho;
  ho.angle_components = x.config.angle_components;
  ho.min_distance_mm = x.config.min_distance_mm;
  ho.regression.ridge = x.config.ridge;
  ho.gaussian_fill = x.config.gaussian_fill;
  ho.forearm = x.config.rigid;
  std::vector<std::string> names = layout.forearm;
  names.insert(names.end(), layout.hand.begin(), layout.hand.end());
  HandModel m = FitHandModel(layout, x.Load(names), ho, &x.progress);
  WithProvenance(x.info, &m.info);
  WithProvenance(x.info, &m.forearm.info);
  std::vector<std::string> warnings = m.warnings;  // shown by FitText as well as in the JSON
  warnings.insert(warnings.end(), m.shape.regression.warnings.begin(), m.shape.regression.warnings.end());
  x.summary["hand"] = {{"parameters", m.num_parameters()},
                       {"angles", m.angle_names.size()},
                       {"variance_explained", m.shape.angle_pca.variance_explained},
                       {"regression_rank", m.shape.regression.rank},
                       {"warnings", warnings},
                       {"training_frames", m.info.training_frames},
                       {"selected_frames", m.info.selected_frames},
                       {"training_rms_mm", m.info.training_rms_mm}};
  if (!m.fill.empty()) {
    x.summary["hand"]["gaussian_fill"] = {{"frames", m.fill.frames}, {"iterations", m.fill.iterations}};
  }
  if (!x.options.figures.empty()) {
    std::vector<std::string> pnames;
    for (int k = 0; k < m.num_parameters(); ++k) pnames.push_back("naH" + std::to_string(k + 1));
    std::vector<report::ParameterEffect> effects;
    const Eigen::VectorXd zero = Eigen::VectorXd::Zero(m.num_parameters());
    for (int k = 0; k < m.num_parameters(); ++k) {
      Eigen::VectorXd p = zero;
      p(k) = -2 * m.param_scale(k);
      const Eigen::Matrix3Xd low = AsPoints(m.shape.Predict(p));
      p(k) = 2 * m.param_scale(k);
      effects.push_back({pnames[static_cast<size_t>(k)], low, AsPoints(m.shape.Predict(p))});
    }
    x.ParameterFigures("hand", "Hand model: joint-angle variance explained", pnames,
                       m.shape.angle_pca.variance_explained, AsPoints(m.shape.Predict(zero)), effects,
                       SticksOf(x.set, layout.hand));
  }
  update->hand = std::move(m);
}

// The marker set the selected takes were imported with (the corpus remembers
// it): every take must have one, and all the same.
MarkerSet RememberedMarkerSet(const Corpus& corpus, const std::vector<TakeRange>& ranges) {
  std::string text;
  std::string first_take;
  for (const TakeRange& r : ranges) {
    const std::string t = corpus.TakeMarkerSet(r.take);
    if (t.empty()) {
      throw UsageError("no marker set: take '" + r.take + "' of " + corpus.path() +
                       " was imported without --markerset; give --markerset SET.json (or \"markerset\" in the "
                       "--config file)");
    }
    if (first_take.empty()) {
      text = t;
      first_take = r.take;
    } else if (t != text) {
      throw UsageError("takes '" + first_take + "' and '" + r.take + "' of " + corpus.path() +
                       " were imported with different marker sets; give --markerset SET.json");
    }
  }
  if (first_take.empty()) throw UsageError("no marker set: no take selected; give --markerset SET.json");
  return ParseMarkerSet(text, corpus.path() + ": take '" + first_take + "'");
}

}  // namespace

std::string FitOptions::Check() const {
  if (corpus.empty()) return "no corpus given";
  if (kind != "rigid" && kind != "face" && kind != "hand") return "model kind must be rigid, face or hand";
  if (output.empty()) return "no output model file given (-o)";
  return "";
}

json Fit(const FitOptions& options, Progress& progress) {
  if (const std::string why = options.Check(); !why.empty()) throw InvalidInput(why);
  const ModelConfig config = LoadModelConfig(options.config);
  std::string set_file = options.markerset.empty() ? config.markerset : options.markerset;
  const Corpus corpus = Corpus::Open(options.corpus);
  const std::vector<TakeRange> ranges = SelectCorpusTakes(corpus, options.takes);
  MarkerSet set;
  if (!set_file.empty()) {
    set = LoadMarkerSet(set_file);
  } else {
    set = RememberedMarkerSet(corpus, ranges);
    set_file = options.corpus + " (marker set remembered with take '" + ranges.front().take + "')";
  }
  if (!options.figures.empty()) figures::Require();  // before any work

  ModelInfo info;
  info.corpus = options.corpus;
  for (const auto& r : ranges) info.training_takes.push_back(r.spec);
  info.config_json = CombinedConfig(config, set);
  info.created_utc = UtcNow();
  info.csw_version = CSW_VERSION;

  json summary;
  summary["corpus"] = options.corpus;
  summary["output"] = options.output;
  summary["kind"] = options.kind;
  summary["training_takes"] = info.training_takes;
  summary["figures"] = json::array();
  const FitContext context{options, config, set, set_file, ranges, info, progress, summary, corpus};
  ModelFile update;
  if (options.kind == "rigid") {
    FitRigid(context, &update);
  } else if (options.kind == "face") {
    FitFace(context, &update);
  } else {
    FitHand(context, &update);
  }
  progress.Update("saving", 1.0);
  UpdateModelFile(options.output, update);
  return summary;
}

}  // namespace csw::jobs
