#include "workbench/jobs/transitions_job.h"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <limits>
#include <map>
#include <sstream>

#include "analysis/signing/segmentation.h"
#include "core/error.h"
#include "core/file_util.h"
#include "io/corpus/corpus.h"
#include "workbench/jobs/figures.h"
#include "workbench/jobs/job_util.h"
#include "workbench/jobs/take_data.h"
#include "workbench/jobs/take_selection.h"
#include "workbench/jobs/tier_util.h"

namespace csw::jobs {

using nlohmann::json;

namespace {

double UnitMm(const std::string& unit) {
  if (unit == "m") return 1000.0;
  if (unit == "dm") return 100.0;
  if (unit == "cm") return 10.0;
  if (unit == "mm") return 1.0;
  return 0.0;
}

double Round(double v, double step) { return std::isfinite(v) ? std::round(v / step) * step : v; }

// "right", "left" or "" from a tier name (the side rules of csw segment).
std::string SideOf(const std::string& name) {
  const char side = signing::NameSide(name);
  return side == 'R' ? "right" : side == 'L' ? "left" : "";
}

// The wrist joint each hand tier uses, from --wrists or FindWrist.
int WristFor(const Take& take, const std::string& tier, const TransitionsOptions& options) {
  for (const std::string& pair : options.wrists) {
    const size_t eq = pair.find('=');
    if (pair.substr(0, eq) != tier) continue;
    const std::string joint = pair.substr(eq + 1);
    for (size_t j = 0; j < take.skeleton.size(); ++j) {
      if (take.skeleton[j].name == joint) return static_cast<int>(j);
    }
    throw InvalidInput("take '" + take.name + "': --wrists names joint '" + joint + "' for tier '" + tier +
                       "', which its skeleton does not have");
  }
  const std::string side = SideOf(tier);
  if (side.empty()) {
    throw InvalidInput("take '" + take.name + "', tier '" + tier +
                       "': the tier's name does not say which hand (right/left); name its wrist with --wrists " + tier +
                       "=JOINT");
  }
  const int w = FindWrist(take.skeleton, side);
  if (w < 0) {
    throw InvalidInput("take '" + take.name + "': no " + side +
                       " wrist or hand joint found in its skeleton; name it with --wrists " + tier + "=JOINT");
  }
  return w;
}

json MinMeanMax(const std::vector<double>& v) {
  if (v.empty()) return {{"min", nullptr}, {"mean", nullptr}, {"max", nullptr}};
  double sum = 0;
  for (double x : v) sum += x;
  return {{"min", Round(*std::min_element(v.begin(), v.end()), 1e-6)},
          {"mean", Round(sum / static_cast<double>(v.size()), 1e-6)},
          {"max", Round(*std::max_element(v.begin(), v.end()), 1e-6)}};
}

void WriteDurably(const std::string& path, const std::string& text) {
  const std::string tmp = HiddenSibling(path, ".tmp");
  {
    std::ofstream out(tmp, std::ios::binary);
    if (!out) throw IoError(path, "cannot open for writing");
    out << text;
    out.close();
    if (!out) throw IoError(path, "write failed");
  }
  try {
    ReplaceFileDurably(tmp, path);
  } catch (...) {
    std::error_code ec;
    std::filesystem::remove(tmp, ec);
    throw;
  }
}

std::string CsvField(const std::string& s) {
  if (s.find_first_of(",\"\n") == std::string::npos) return s;
  std::string out = "\"";
  for (char c : s) out += c == '"' ? std::string("\"\"") : std::string(1, c);
  return out + "\"";
}

}  // namespace

int FindWrist(const std::vector<SkeletonJoint>& skeleton, const std::string& side) {
  // The rules of csw segment (analysis/signing/segmentation.h FindWrists), on
  // the joints (end sites are not wrists).
  std::vector<std::string> names;
  for (const SkeletonJoint& j : skeleton) names.push_back(j.end_site ? std::string() : j.name);
  try {
    const signing::WristJoints w = signing::FindWrists(names, "", "", side == "right", side == "left");
    return static_cast<int>(side == "right" ? w.right : w.left);
  } catch (const InvalidInput&) {
    return -1;  // none found: the caller says what to do about it
  }
}

std::string TransitionsOptions::Check() const {
  if (corpus.empty()) return "no corpus given";
  if (tiers.empty()) return "--tiers must name at least one sign/transition tier";
  for (const std::string& w : wrists) {
    const size_t eq = w.find('=');
    if (eq == std::string::npos || eq == 0 || eq + 1 == w.size()) {
      return "--wrists takes TIER=JOINT pairs, not '" + w + "'";
    }
    if (std::find(tiers.begin(), tiers.end(), w.substr(0, eq)) == tiers.end()) {
      return "--wrists names tier '" + w.substr(0, eq) + "', which is not among --tiers";
    }
  }
  if (joints != "arm" && joints != "all") return "--joints must be arm or all, not '" + joints + "'";
  if (UnitMm(length_unit) == 0) return "--length-unit must be m, dm, cm or mm, not '" + length_unit + "'";
  if (models.empty()) return "--models must name at least one model";
  for (const std::string& m : models) {
    try {
      signing::ParseDurationModel(m);
    } catch (const InvalidInput& e) {
      return std::string("--models: ") + e.what();
    }
  }
  if (folds < 2) return "--folds must be at least 2";
  if (std::string why = model.Check(); !why.empty()) return why;
  if (std::string why = transition.Check(); !why.empty()) return why;
  if (!output.empty() && output == csv) return "-o and --csv must be different files";
  return "";
}

json AnalyseTransitions(const std::vector<Take>& takes, const TransitionsOptions& options, Progress& progress,
                        std::vector<signing::Transition>* transitions_out) {
  if (std::string why = options.Check(); !why.empty()) throw UsageError(why);
  signing::TransitionOptions topt = options.transition;
  topt.length_unit_mm = UnitMm(options.length_unit);
  json result = {{"takes", json::array()}, {"length_unit", options.length_unit}, {"joints", options.joints}};
  std::vector<signing::Transition> all;
  int tiers_found = 0;
  for (size_t i = 0; i < takes.size(); ++i) {
    const Take& take = takes[i];
    progress.Update("transitions: " + take.name, static_cast<double>(i) / static_cast<double>(takes.size()));
    progress.CheckCancel();
    if (take.skeleton.empty() || take.orientations.empty()) {
      throw InvalidInput("take '" + take.name +
                         "' is not a skeleton capture (no joint hierarchy or orientations: import a BVH file)");
    }
    const LabelTier* types = options.types.empty() ? nullptr : FindTier(take.tiers, options.types);
    json tj = {{"take", take.name}, {"tiers", json::array()}, {"types_tier", types != nullptr}};
    std::map<std::string, int> wrist_of;  // per hand tier the take has
    if (options.joints == "arm") {
      for (const std::string& name : options.tiers) {
        if (FindTier(take.tiers, name) != nullptr) wrist_of[name] = WristFor(take, name, options);
      }
    }
    for (const std::string& name : options.tiers) {
      const LabelTier* tier = FindTier(take.tiers, name);
      if (tier == nullptr) continue;
      ++tiers_found;
      const int wrist = options.joints == "arm" ? wrist_of[name] : -1;
      std::vector<int> joints;
      if (options.joints == "all") {
        for (int j = 0; j < static_cast<int>(take.skeleton.size()); ++j) joints.push_back(j);
      } else {
        // The other hand's wrist bounds the arm at the shoulder: another hand
        // tier's wrist, else the other side's wrist of the skeleton.
        int other = -1;
        for (const auto& [other_tier, w] : wrist_of) {
          if (other_tier != name && w != wrist) other = w;
        }
        if (other < 0) other = FindWrist(take.skeleton, SideOf(name) == "left" ? "right" : "left");
        if (other < 0 || other == wrist) {
          throw InvalidInput("take '" + take.name + "', tier '" + name +
                             "': the arm joints need the other hand's wrist too (it bounds the arm at the shoulder); "
                             "name both with --wrists, or use --joints all");
        }
        joints = signing::ArmJoints(take.skeleton, wrist, other);
      }
      std::vector<signing::Transition> ts = signing::ExtractTransitions(take, *tier, types, joints, topt);
      tj["tiers"].push_back(
          {{"tier", name},
           {"wrist", wrist >= 0 ? json(take.skeleton[static_cast<size_t>(wrist)].name) : json(nullptr)},
           {"joints", joints.size()},
           {"transitions", ts.size()}});
      all.insert(all.end(), ts.begin(), ts.end());
    }
    result["takes"].push_back(tj);
  }
  if (tiers_found == 0) {
    std::string names;
    for (const std::string& t : options.tiers) names += (names.empty() ? "'" : ", '") + t + "'";
    throw InvalidInput("none of the selected takes has a tier " + names +
                       "; name the sign/transition tiers with --tiers");
  }
  signing::NormaliseDistances(all);
  result["transitions"] = all.size();
  json per_type = json::array();
  for (const signing::TypeStatistics& s : signing::StatisticsPerType(all)) {
    per_type.push_back({{"type", s.type.empty() ? json(nullptr) : json(s.type)},
                        {"count", s.count},
                        {"mean_s", Round(s.mean_s, 1e-5)},
                        {"sd_s", Round(s.sd_s, 1e-5)}});
  }
  result["per_type"] = per_type;
  std::vector<double> g, e, d;
  for (const signing::Transition& t : all) {
    g.push_back(t.geodesic);
    e.push_back(t.euclidean);
    d.push_back(t.duration_s);
  }
  result["distances"] = {{"geodesic", MinMeanMax(g)}, {"euclidean", MinMeanMax(e)}, {"duration_s", MinMeanMax(d)}};

  // The models: fitted on every transition, judged by cross-validation.
  const int folds = std::min<int>(options.folds, static_cast<int>(all.size()));
  result["folds"] = folds;
  json models = json::array();
  json fitted = json::array();
  std::string best;
  double best_error = std::numeric_limits<double>::infinity();
  for (const std::string& name : options.models) {
    progress.Update("transitions: models", 1.0);
    const signing::DurationModelKind kind = signing::ParseDurationModel(name);
    json mj = {{"model", signing::DurationModelName(kind)}};
    try {
      const signing::DurationModel m = signing::FitDurationModel(kind, all, options.model);
      mj["fit"] = m.ToJson();
      mj["training_mae_s"] = Round(m.training_mae_s, 1e-6);
      fitted.push_back(m.ToJson());
      if (folds >= 2) {
        const double cv = signing::CrossValidatedError(kind, all, folds, options.model);
        mj["cv_mae_s"] = Round(cv, 1e-6);
        if (cv < best_error) {
          best_error = cv;
          best = signing::DurationModelName(kind);
        }
      } else {
        mj["cv_mae_s"] = nullptr;
      }
    } catch (const InvalidInput& ex) {
      mj["error"] = ex.what();
    }
    models.push_back(mj);
  }
  result["models"] = models;
  result["best"] = best.empty() ? json(nullptr) : json(best);
  result["fitted"] = fitted;
  if (!options.figures.empty()) {
    progress.Update("transitions: figures", 1.0);
    figures::Require();
    std::filesystem::create_directories(options.figures);
    using report::PlotSeries;
    report::PlotPanel fig7{"Duration against the mean normalised distance (the seed's Fig. 7)",
                           "mean of the normalised geodesic and Euclidean distances",
                           "duration (s)",
                           {},
                           {}};
    report::PlotPanel euclid{"Duration against the Euclidean distance",
                             "mean Euclidean distance (" + options.length_unit + ")",
                             "duration (s)",
                             {},
                             {}};
    report::PlotPanel geo{
        "Duration against the geodesic distance", "mean geodesic distance (rad)", "duration (s)", {}, {}};
    report::PlotPanel fit{"Predicted against measured (fitted on every transition)",
                          "measured duration (s)",
                          "predicted duration (s)",
                          {},
                          {}};
    PlotSeries points{"transitions", {}, {}, PlotSeries::Style::kPoints, 0};
    PlotSeries pe = points, pg = points;
    double n_lo = 0, n_hi = 0, d_lo = 0, d_hi = 0;
    for (size_t i = 0; i < all.size(); ++i) {
      const signing::Transition& t = all[i];
      points.x.push_back(t.normalised);
      points.y.push_back(t.duration_s);
      pe.x.push_back(t.euclidean);
      pe.y.push_back(t.duration_s);
      pg.x.push_back(t.geodesic);
      pg.y.push_back(t.duration_s);
      n_lo = i == 0 ? t.normalised : std::min(n_lo, t.normalised);
      n_hi = i == 0 ? t.normalised : std::max(n_hi, t.normalised);
      d_lo = i == 0 ? t.duration_s : std::min(d_lo, t.duration_s);
      d_hi = i == 0 ? t.duration_s : std::max(d_hi, t.duration_s);
    }
    fig7.series.push_back(points);
    euclid.series.push_back(pe);
    geo.series.push_back(pg);
    int colour = 1;
    for (const json& fj : result["fitted"]) {
      const signing::DurationModel m = signing::DurationModel::FromJson(fj);
      if (m.kind == signing::DurationModelKind::kLinear) {
        fig7.series.push_back({"LINEAR",
                               {n_lo, n_hi},
                               {m.intercept + m.slope * n_lo, m.intercept + m.slope * n_hi},
                               PlotSeries::Style::kLine,
                               3});
      }
      if (m.kind == signing::DurationModelKind::kSurface && !all.empty()) {
        // The fitted plane seen from the geodesic axis: its lines at the
        // quartiles of the Euclidean distance (the seed's Fig. 11 in 2-D).
        std::vector<double> es = e;
        std::sort(es.begin(), es.end());
        const double g_lo = *std::min_element(g.begin(), g.end()), g_hi = *std::max_element(g.begin(), g.end());
        for (double q : {0.25, 0.5, 0.75}) {
          const double eq = es[static_cast<size_t>(q * static_cast<double>(es.size() - 1))];
          geo.series.push_back(
              {q == 0.5 ? std::string("SURFACE at the quartiles of E") : std::string(),
               {g_lo, g_hi},
               {m.theta[0] + m.theta[1] * g_lo + m.theta[2] * eq, m.theta[0] + m.theta[1] * g_hi + m.theta[2] * eq},
               PlotSeries::Style::kDashed,
               4});
        }
      }
      PlotSeries s{std::string(signing::DurationModelName(m.kind)), {}, {}, PlotSeries::Style::kPoints, colour++};
      for (const signing::Transition& t : all) {
        s.x.push_back(t.duration_s);
        s.y.push_back(m.Predict(t));
      }
      fit.series.push_back(s);
    }
    fit.series.push_back({"predicted = measured", {d_lo, d_hi}, {d_lo, d_hi}, PlotSeries::Style::kDashed, 7});
    const std::string png = (std::filesystem::path(options.figures) / "transitions.png").string();
    figures::SavePlots(png, "Transitions: " + std::to_string(all.size()) + " from " + options.corpus,
                       {fig7, fit, euclid, geo}, 2);
    result["figures"] = json::array({png});
  }
  if (transitions_out != nullptr) *transitions_out = std::move(all);
  return result;
}

json Transitions(const TransitionsOptions& options, Progress& progress) {
  if (std::string why = options.Check(); !why.empty()) throw UsageError(why);
  const Corpus corpus = Corpus::Open(options.corpus);
  const std::vector<TakeRange> ranges = SelectCorpusTakes(corpus, options.takes);
  std::vector<Take> takes;
  for (size_t i = 0; i < ranges.size(); ++i) {
    progress.Update("transitions: loading", static_cast<double>(i) / static_cast<double>(ranges.size()));
    progress.CheckCancel();
    if (ranges[i].first != 0) {
      throw UsageError("csw transitions works on whole takes: '" + ranges[i].spec + "' selects frames of take '" +
                       ranges[i].take + "'");
    }
    takes.push_back(corpus.LoadTake(ranges[i].take));
    if (ranges[i].count != takes.back().frames()) {
      throw UsageError("csw transitions works on whole takes: '" + ranges[i].spec + "' selects frames of take '" +
                       ranges[i].take + "'");
    }
  }
  std::vector<signing::Transition> all;
  json result;
  try {
    result = AnalyseTransitions(takes, options, progress, &all);
  } catch (const UsageError&) {
    throw;
  } catch (const InvalidInput& e) {
    throw InvalidInput(options.corpus + ": " + e.what());
  }
  result["corpus"] = options.corpus;
  if (!options.output.empty()) {
    json file = {{"format", "csw-transition-duration-models"},
                 {"version", 1},
                 {"corpus", options.corpus},
                 {"length_unit", options.length_unit},
                 {"joints", options.joints},
                 {"best", result["best"]},
                 {"models", result["fitted"]},
                 {"created_utc", UtcNow()}};
    WriteDurably(options.output, file.dump(2) + "\n");
    result["output"] = options.output;
  }
  if (!options.csv.empty()) {
    std::ostringstream out;
    out << "take,tier,from_sign,to_sign,type,start_s,end_s,duration_s,geodesic_rad,euclidean_" << options.length_unit
        << ",normalised,from_speed,to_speed,from_angular_speed,to_angular_speed,joints\n";
    char buf[512];
    for (const signing::Transition& t : all) {
      out << CsvField(t.take) << "," << CsvField(t.hand) << "," << CsvField(t.from_sign) << "," << CsvField(t.to_sign)
          << "," << t.type();
      std::snprintf(buf, sizeof(buf), ",%.6f,%.6f,%.6f,%.8g,%.8g,%.8g,%.8g,%.8g,%.8g,%.8g,%d\n", t.start_s, t.end_s,
                    t.duration_s, t.geodesic, t.euclidean, t.normalised, t.from_speed, t.to_speed, t.from_angular_speed,
                    t.to_angular_speed, t.joints_used);
      out << buf;
    }
    WriteDurably(options.csv, out.str());
    result["csv"] = options.csv;
  }
  result.erase("fitted");
  progress.Update("transitions", 1.0);
  return result;
}

std::string TransitionsText(const json& r) {
  std::ostringstream o;
  char buf[256];
  o << "transitions: " << r.value("transitions", 0) << " (distances in " << r.value("length_unit", "m") << ", "
    << r.value("joints", "arm") << " joints)\n";
  for (const json& t : r["takes"]) {
    o << "  " << t["take"].get<std::string>() << ":";
    for (const json& tier : t["tiers"]) {
      o << " " << tier["tier"].get<std::string>() << " " << tier["transitions"].get<int>();
      if (!tier["wrist"].is_null()) o << " (wrist " << tier["wrist"].get<std::string>() << ")";
    }
    o << "\n";
  }
  o << "per type (the seed's Table 2):\n  type   count  mean (s)  sd (s)\n";
  for (const json& s : r["per_type"]) {
    const std::string type = s["type"].is_null() ? "?" : s["type"].get<std::string>();
    std::snprintf(buf, sizeof(buf), "  %-6s %5d  %8.3f  %6.3f\n", type.c_str(), s["count"].get<int>(),
                  s["mean_s"].get<double>(), s["sd_s"].get<double>());
    o << buf;
  }
  o << "duration models (" << r.value("folds", 0) << "-fold cross-validation):\n";
  for (const json& m : r["models"]) {
    const std::string name = m["model"].get<std::string>();
    if (m.contains("error")) {
      o << "  " << name << ": not fitted: " << m["error"].get<std::string>() << "\n";
      continue;
    }
    std::string params;
    const json& f = m["fit"];
    if (f.contains("theta")) {
      std::snprintf(buf, sizeof(buf), "theta = (%.6g, %.6g, %.6g)", f["theta"][0].get<double>(),
                    f["theta"][1].get<double>(), f["theta"][2].get<double>());
      params = buf;
    } else if (f.contains("slope_s")) {
      std::snprintf(buf, sizeof(buf), "d = %.4g + %.4g n", f["intercept_s"].get<double>(), f["slope_s"].get<double>());
      params = buf;
    } else if (f.contains("alpha")) {
      std::snprintf(buf, sizeof(buf), "alpha = %.4g", f["alpha"].get<double>());
      params = buf;
    }
    std::string cv = "-";
    if (!m["cv_mae_s"].is_null()) {
      std::snprintf(buf, sizeof(buf), "%.1f", m["cv_mae_s"].get<double>() * 1000.0);
      cv = buf;
    }
    std::snprintf(buf, sizeof(buf), "  %-15s %-36s MAE train %.1f ms, cross-validated %s ms\n", name.c_str(),
                  params.c_str(), m["training_mae_s"].get<double>() * 1000.0, cv.c_str());
    o << buf;
  }
  if (!r["best"].is_null()) o << "best (lowest cross-validated error): " << r["best"].get<std::string>() << "\n";
  if (r.contains("output")) o << "models: " << r["output"].get<std::string>() << "\n";
  if (r.contains("csv")) o << "per-transition CSV: " << r["csv"].get<std::string>() << "\n";
  if (r.contains("figures")) {
    for (const json& f : r["figures"]) o << "figure: " << f.get<std::string>() << "\n";
  }
  return o.str();
}

}  // namespace csw::jobs
