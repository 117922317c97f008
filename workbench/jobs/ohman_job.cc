#include "workbench/jobs/ohman_job.h"

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <limits>
#include <set>

#include "core/error.h"
#include "core/file_util.h"
#include "core/markerset.h"
#include "io/corpus/corpus.h"
#include "io/models/model_file.h"
#include "models/face_model.h"
#include "workbench/jobs/figures.h"
#include "workbench/jobs/job_util.h"
#include "workbench/jobs/model_config.h"
#include "workbench/jobs/take_data.h"
#include "workbench/jobs/tier_util.h"

namespace csw::jobs {

namespace fs = std::filesystem;
using coarticulation::OhmanConsonant;
using coarticulation::OhmanFit;
using nlohmann::json;

std::string OhmanJobOptions::Check() const {
  if (corpus.empty()) return "no corpus given";
  if (models.empty()) return "no model file given (--models)";
  if (phones.empty()) return "--phones must name a tier";
  if (std::string why = fit.Check(); !why.empty()) return why;
  if (inversion.max_iterations < 1) return "--max-iterations must be >= 1";
  if (!(inversion.prior_mm >= 0)) return "--prior must be >= 0";
  return "";
}

namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

json Vector(const Eigen::VectorXd& v) {
  json a = json::array();
  for (Eigen::Index i = 0; i < v.size(); ++i) a.push_back(std::isfinite(v[i]) ? json(v[i]) : json(nullptr));
  return a;
}

json Row(const Eigen::MatrixXd& m, Eigen::Index r) { return Vector(m.row(r).transpose()); }

ParseError FitError(const std::string& where, const std::string& what) { return ParseError({where, {}, {}}, what); }

const json& Key(const json& j, const std::string& key, const std::string& where, const std::string& path) {
  if (!j.is_object() || !j.contains(key)) throw FitError(where, "Öhman fit: missing '" + path + key + "'");
  return j.at(key);
}

double Number(const json& j, const std::string& key, const std::string& where, const std::string& path) {
  const json& v = Key(j, key, where, path);
  if (!v.is_number()) throw FitError(where, "Öhman fit: '" + path + key + "' must be a number");
  return v.get<double>();
}

Eigen::VectorXd ReadVector(const json& j, const std::string& key, Eigen::Index size, const std::string& where,
                           const std::string& path) {
  const json& v = Key(j, key, where, path);
  if (!v.is_array() || static_cast<Eigen::Index>(v.size()) != size) {
    throw FitError(where, "Öhman fit: '" + path + key + "' must be an array of " + std::to_string(size) + " numbers");
  }
  Eigen::VectorXd out(size);
  for (Eigen::Index i = 0; i < size; ++i) {
    const json& x = v[static_cast<size_t>(i)];
    if (x.is_null()) {
      out[i] = kNaN;
    } else if (x.is_number()) {
      out[i] = x.get<double>();
    } else {
      throw FitError(where, "Öhman fit: '" + path + key + "' must hold numbers or null");
    }
  }
  return out;
}

std::string Fixed(double v, int decimals) {
  if (!std::isfinite(v)) return "-";
  char buf[48];
  std::snprintf(buf, sizeof buf, "%.*f", decimals, v);
  return buf;
}

std::string Fixed(const json& v, int decimals) { return v.is_number() ? Fixed(v.get<double>(), decimals) : "-"; }

void WriteJsonFile(const std::string& path, const json& j) {
  const std::string temp = HiddenSibling(path, ".tmp");
  {
    std::ofstream out(temp, std::ios::binary | std::ios::trunc);
    if (!out) throw IoError(path, "cannot write");
    out << j.dump(2) << "\n";
    if (!out) throw IoError(path, "cannot write");
  }
  try {
    ReplaceFileDurably(temp, path);
  } catch (...) {
    std::error_code ec;
    fs::remove(temp, ec);
    throw;
  }
}

}  // namespace

json OhmanFitToJson(const OhmanFit& fit, const std::vector<std::string>& parameter_names,
                    const std::vector<std::string>& take_names) {
  json j;
  j["format"] = "csw-ohman";
  j["version"] = 1;
  j["parameters"] = parameter_names;
  j["vowels"] = json::array();
  for (size_t v = 0; v < fit.vowels.size(); ++v) {
    j["vowels"].push_back({{"vowel", fit.vowels[v]},
                           {"source", v < fit.vowel_source.size() ? fit.vowel_source[v] : "none"},
                           {"occurrences", v < fit.vowel_occurrences.size() ? fit.vowel_occurrences[v] : 0},
                           {"target", Row(fit.vowel_targets, static_cast<Eigen::Index>(v))}});
  }
  j["rest"] = Vector(fit.rest);
  j["range"] = Vector(fit.range);
  j["consonants"] = json::array();
  for (const OhmanConsonant& c : fit.consonants) {
    json cj = {{"consonant", c.consonant},
               {"contexts", c.vowels},
               {"tokens", c.tokens},
               {"w", Vector(c.w)},
               {"intercept", Vector(c.intercept)},
               {"c", Vector(c.c)},
               {"residual", Vector(c.residual)}};
    json identifiable = json::array();
    for (Eigen::Index x = 0; x < c.c.size(); ++x) identifiable.push_back(c.Identifiable(static_cast<int>(x)));
    cj["identifiable"] = identifiable;
    for (const char* key : {"effect", "measured_effect", "realisation"}) {
      const Eigen::MatrixXd& m = std::string(key) == "effect"            ? c.effect
                                 : std::string(key) == "measured_effect" ? c.measured_effect
                                                                         : c.realisation;
      json per = json::object();
      for (size_t v = 0; v < c.vowels.size(); ++v) per[c.vowels[v]] = Row(m, static_cast<Eigen::Index>(v));
      cj[key] = per;
    }
    cj["k_style"] = {{"left_inset_s", c.k_style.left_inset_s},
                     {"left_ramp_s", c.k_style.left_ramp_s},
                     {"right_inset_s", c.k_style.right_inset_s},
                     {"right_ramp_s", c.k_style.right_ramp_s},
                     {"rms", c.k_style.rms},
                     {"samples", c.k_style.samples}};
    cj["mean_k"] = {{"times_s", c.mean_k_times_s}, {"k", c.mean_k}};
    j["consonants"].push_back(std::move(cj));
  }
  j["tokens"] = json::array();
  for (const coarticulation::VcvToken& t : fit.tokens) {
    const std::string take = t.series >= 0 && static_cast<size_t>(t.series) < take_names.size()
                                 ? take_names[static_cast<size_t>(t.series)]
                                 : "";
    j["tokens"].push_back(
        {{"take", take},
         {"vowel", t.vowel},
         {"consonant", t.consonant},
         {"v1_centre_s", t.v1_centre_s},
         {"c_start_s", t.c_start_s},
         {"c_end_s", t.c_end_s},
         {"v2_centre_s", t.v2_centre_s},
         {"realisation_s", t.realisation_s},
         {"k_times_s", t.k_times_s},
         {"k", Vector(Eigen::Map<const Eigen::VectorXd>(t.k.data(), static_cast<Eigen::Index>(t.k.size())))}});
  }
  j["warnings"] = fit.warnings;
  return j;
}

OhmanFit OhmanFitFromJson(const json& j, const std::string& where, std::vector<std::string>* parameter_names) {
  if (!j.is_object()) throw FitError(where, "Öhman fit: not a JSON object");
  const json& format = Key(j, "format", where, "");
  if (!format.is_string() || format.get<std::string>() != "csw-ohman") {
    throw FitError(where, "Öhman fit: 'format' must be \"csw-ohman\"");
  }
  const double version = Number(j, "version", where, "");
  if (version != 1) throw FitError(where, "Öhman fit: version " + Fixed(version, 0) + " is not supported (1 is)");
  const json& names = Key(j, "parameters", where, "");
  if (!names.is_array() || names.empty()) throw FitError(where, "Öhman fit: 'parameters' must be a non-empty array");
  std::vector<std::string> params;
  for (const json& n : names) {
    if (!n.is_string()) throw FitError(where, "Öhman fit: 'parameters' must hold names");
    params.push_back(n.get<std::string>());
  }
  const auto P = static_cast<Eigen::Index>(params.size());
  OhmanFit fit;
  fit.num_parameters = static_cast<int>(P);
  const json& vowels = Key(j, "vowels", where, "");
  if (!vowels.is_array()) throw FitError(where, "Öhman fit: 'vowels' must be an array");
  fit.vowel_targets.resize(static_cast<Eigen::Index>(vowels.size()), P);
  for (size_t v = 0; v < vowels.size(); ++v) {
    const std::string path = "vowels[" + std::to_string(v) + "].";
    const json& name = Key(vowels[v], "vowel", where, path);
    if (!name.is_string()) throw FitError(where, "Öhman fit: '" + path + "vowel' must be a string");
    fit.vowels.push_back(name.get<std::string>());
    fit.vowel_source.push_back(vowels[v].value("source", "isolated"));
    fit.vowel_occurrences.push_back(vowels[v].value("occurrences", 0));
    fit.vowel_targets.row(static_cast<Eigen::Index>(v)) = ReadVector(vowels[v], "target", P, where, path).transpose();
  }
  fit.rest = ReadVector(j, "rest", P, where, "");
  if (!fit.rest.allFinite()) throw FitError(where, "Öhman fit: 'rest' must be finite");
  fit.range = ReadVector(j, "range", P, where, "");
  const json& consonants = Key(j, "consonants", where, "");
  if (!consonants.is_array()) throw FitError(where, "Öhman fit: 'consonants' must be an array");
  for (size_t i = 0; i < consonants.size(); ++i) {
    const json& cj = consonants[i];
    const std::string path = "consonants[" + std::to_string(i) + "].";
    OhmanConsonant c;
    const json& name = Key(cj, "consonant", where, path);
    if (!name.is_string()) throw FitError(where, "Öhman fit: '" + path + "consonant' must be a string");
    c.consonant = name.get<std::string>();
    const json& contexts = Key(cj, "contexts", where, path);
    if (!contexts.is_array()) throw FitError(where, "Öhman fit: '" + path + "contexts' must be an array");
    for (const json& v : contexts) {
      if (!v.is_string()) throw FitError(where, "Öhman fit: '" + path + "contexts' must hold vowels");
      c.vowels.push_back(v.get<std::string>());
    }
    c.tokens = cj.value("tokens", 0);
    c.w = ReadVector(cj, "w", P, where, path);
    c.intercept = ReadVector(cj, "intercept", P, where, path);
    c.c = ReadVector(cj, "c", P, where, path);
    c.residual = ReadVector(cj, "residual", P, where, path);
    const auto nc = static_cast<Eigen::Index>(c.vowels.size());
    c.effect.resize(nc, P);
    c.measured_effect.resize(nc, P);
    c.realisation.resize(nc, P);
    for (const char* key : {"effect", "measured_effect", "realisation"}) {
      Eigen::MatrixXd& m = std::string(key) == "effect"            ? c.effect
                           : std::string(key) == "measured_effect" ? c.measured_effect
                                                                   : c.realisation;
      const json& per = Key(cj, key, where, path);
      for (Eigen::Index v = 0; v < nc; ++v)
        m.row(v) = ReadVector(per, c.vowels[static_cast<size_t>(v)], P, where, path + key + ".").transpose();
    }
    const json& ks = Key(cj, "k_style", where, path);
    const std::string kp = path + "k_style.";
    c.k_style.left_inset_s = Number(ks, "left_inset_s", where, kp);
    c.k_style.left_ramp_s = Number(ks, "left_ramp_s", where, kp);
    c.k_style.right_inset_s = Number(ks, "right_inset_s", where, kp);
    c.k_style.right_ramp_s = Number(ks, "right_ramp_s", where, kp);
    if (!(c.k_style.left_ramp_s >= 0 && c.k_style.right_ramp_s >= 0)) {
      throw FitError(where, "Öhman fit: '" + kp + "' ramps must be >= 0");
    }
    c.k_style.rms = ks.value("rms", 0.0);
    c.k_style.samples = ks.value("samples", 0);
    if (cj.contains("mean_k")) {
      const json& mk = cj["mean_k"];
      if (mk.contains("times_s") && mk["times_s"].is_array())
        c.mean_k_times_s = mk["times_s"].get<std::vector<double>>();
      if (mk.contains("k") && mk["k"].is_array()) c.mean_k = mk["k"].get<std::vector<double>>();
    }
    fit.consonants.push_back(std::move(c));
  }
  if (j.contains("warnings") && j["warnings"].is_array()) {
    for (const json& w : j["warnings"])
      if (w.is_string()) fit.warnings.push_back(w.get<std::string>());
  }
  if (parameter_names) *parameter_names = params;
  return fit;
}

json Ohman(const OhmanJobOptions& options, Progress& progress) {
  if (const std::string why = options.Check(); !why.empty()) throw UsageError(why);
  const ModelFile models = LoadModelFile(options.models);
  if (!models.face) throw InvalidInput(options.models + ": no face model in the file (csw fit face)");
  const FaceModel& face = *models.face;
  const MarkerSet set = MarkerSetOfModel(face.info, options.models);
  const Corpus corpus = Corpus::Open(options.corpus);
  const std::vector<TakeRange> ranges = SelectCorpusTakes(corpus, options.takes);
  if (!options.figures.empty()) figures::Require();  // before any work
  std::vector<std::string> names = face.layout.head;
  names.insert(names.end(), face.layout.face.begin(), face.layout.face.end());
  names.insert(names.end(), face.layout.throat.begin(), face.layout.throat.end());

  json result;
  result["corpus"] = options.corpus;
  result["models"] = options.models;
  result["takes"] = json::array();
  result["skipped"] = json::array();
  std::vector<coarticulation::ParameterSeries> series;
  std::vector<std::string> take_names;
  for (size_t i = 0; i < ranges.size(); ++i) {
    const TakeRange& range = ranges[i];
    progress.Update("inverting the face model", static_cast<double>(i) / static_cast<double>(ranges.size()));
    const Take take = corpus.LoadTake(range.take);
    const LabelTier* tier = FindTier(take.tiers, options.phones);
    if (!tier || tier->kind != LabelTier::Kind::kInterval) {
      result["skipped"].push_back(
          {{"take", range.spec},
           {"reason", "no interval tier '" + options.phones + "' (tiers: " + TierNames(take.tiers) + ")"}});
      continue;
    }
    const std::string where = corpus.path() + ": take '" + range.take + "'";
    const std::vector<int> cols = BindNames(set, take.marker_names, names, where);
    const MarkerArray input = Extract(take.markers, cols, range.first, range.count);
    const InversionResult inv = InvertFace(face, input, options.inversion, &progress);
    coarticulation::ParameterSeries s;
    s.name = range.take;
    s.rate_hz = take.rate_hz;
    s.values = inv.params;
    // Phone times on the range's clock.
    const double offset = static_cast<double>(range.first) / take.rate_hz;
    for (Label l : tier->labels) {
      l.start_s -= offset;
      l.end_s -= offset;
      s.phones.push_back(std::move(l));
    }
    int64_t solved = 0;
    for (uint8_t f : inv.solved) solved += f;
    result["takes"].push_back(
        {{"take", range.spec}, {"frames", range.count}, {"solved_frames", solved}, {"tokens", 0}});
    series.push_back(std::move(s));
    take_names.push_back(range.spec);
  }
  if (series.empty()) {
    throw InvalidInput(options.corpus + ": no selected take has the phone tier '" + options.phones + "'");
  }
  progress.Update("fitting the Öhman model", 0.0);
  const OhmanFit fit = coarticulation::FitOhman(series, options.fit);
  for (const coarticulation::VcvToken& t : fit.tokens) {
    json& tj = result["takes"][static_cast<size_t>(t.series)];
    tj["tokens"] = tj["tokens"].get<int>() + 1;
  }
  const std::vector<std::string>& params = face.shape.parameter_names;
  result["fit"] = OhmanFitToJson(fit, params, take_names);
  int identifiable = 0, cells = 0;
  for (const OhmanConsonant& c : fit.consonants)
    for (int x = 0; x < fit.num_parameters; ++x) identifiable += c.Identifiable(x), ++cells;
  result["summary"] = {{"tokens", fit.tokens.size()},
                       {"consonants", fit.consonants.size()},
                       {"parameters", fit.num_parameters},
                       {"identifiable", identifiable},
                       {"consonant_parameters", cells}};
  // Trajectories regenerated from the fit for every take, against the inverted
  // parameters (in-sample: the MOTHER paper's Figure 9).
  struct Regenerated {
    std::vector<double> times;
    std::vector<Eigen::Index> rows;
    Eigen::MatrixXd generated, carrier;
  };
  std::vector<Regenerated> regenerated(series.size());
  for (size_t i = 0; i < series.size(); ++i) {
    const coarticulation::ParameterSeries& s = series[i];
    Regenerated& g = regenerated[i];
    for (Eigen::Index f = 0; f < s.values.rows(); ++f)
      if (s.values.row(f).allFinite()) g.times.push_back(static_cast<double>(f) / s.rate_hz), g.rows.push_back(f);
    json& tj = result["takes"][i];
    const std::vector<Label> phones =
        coarticulation::NormalisePhones(s.phones, static_cast<double>(s.values.rows()) / s.rate_hz);
    coarticulation::GenerateOptions lenient;
    lenient.skip_unknown = true;
    std::set<std::string> unknown;
    for (const Label& l : phones)
      if (!coarticulation::IsPauseLabel(l.text) && fit.VowelIndex(l.text) < 0 && !fit.Find(l.text))
        unknown.insert(l.text);
    g.generated = coarticulation::GenerateOhman(fit, phones, g.times, lenient);
    g.carrier = coarticulation::OhmanCarrier(fit, phones, g.times, lenient);
    json corr = json::array(), rms = json::array();
    for (int x = 0; x < fit.num_parameters; ++x) {
      Eigen::VectorXd obs(static_cast<Eigen::Index>(g.rows.size()));
      for (size_t k = 0; k < g.rows.size(); ++k) obs[static_cast<Eigen::Index>(k)] = s.values(g.rows[k], x);
      const Eigen::VectorXd gen = g.generated.col(x);
      const Eigen::VectorXd da = obs.array() - obs.mean(), db = gen.array() - gen.mean();
      const double den = std::sqrt(da.squaredNorm() * db.squaredNorm());
      corr.push_back(den > 0 ? json(da.dot(db) / den) : json(nullptr));
      rms.push_back(obs.size() > 0 ? json(std::sqrt((gen - obs).squaredNorm() / static_cast<double>(obs.size())))
                                   : json(nullptr));
    }
    tj["generation"] = {{"correlation", corr}, {"rms", rms}, {"unknown_phones", unknown}};
  }

  result["figures"] = json::array();
  if (!options.figures.empty()) {
    fs::create_directories(options.figures);
    for (size_t i = 0; i < series.size(); ++i) {
      const Regenerated& g = regenerated[i];
      if (result["takes"][i]["tokens"].get<int>() == 0 || g.generated.rows() == 0) continue;
      std::vector<report::PlotPanel> panels;
      for (int x = 0; x < fit.num_parameters; ++x) {
        report::PlotPanel panel;
        panel.title = x < static_cast<int>(params.size()) ? params[static_cast<size_t>(x)] : "";
        panel.x_label = "time (s)";
        report::PlotSeries obs{"inverted", {}, {}, report::PlotSeries::Style::kLine, 0};
        report::PlotSeries carrier{"vocalic carrier v", {}, {}, report::PlotSeries::Style::kLine, 7};
        report::PlotSeries gen{"generated", {}, {}, report::PlotSeries::Style::kDashed, 3};
        for (size_t k = 0; k < g.rows.size(); ++k) {
          const double t = g.times[k];
          obs.x.push_back(t);
          obs.y.push_back(series[i].values(g.rows[k], x));
          carrier.x.push_back(t);
          carrier.y.push_back(g.carrier(static_cast<Eigen::Index>(k), x));
          gen.x.push_back(t);
          gen.y.push_back(g.generated(static_cast<Eigen::Index>(k), x));
        }
        panel.series = {std::move(carrier), std::move(obs), std::move(gen)};
        panels.push_back(std::move(panel));
      }
      const std::string path = (fs::path(options.figures) / ("ohman_generated_" + take_names[i] + ".png")).string();
      figures::SavePlots(path, "Öhman model, " + take_names[i], panels, 2);
      result["figures"].push_back(path);
    }
    for (const OhmanConsonant& c : fit.consonants) {
      report::PlotPanel panel;
      panel.x_label = "time from the consonant centre (ms)";
      panel.y_label = "k";
      panel.y_min = -0.2;
      panel.y_max = 1.2;
      panel.vertical_marks = {0.0};
      for (const std::string& v : c.vowels) {
        report::PlotSeries ps;
        ps.name = "[" + v + c.consonant + v + "]";
        for (const coarticulation::VcvToken& t : fit.tokens) {
          if (t.consonant != c.consonant || t.vowel != v) continue;
          const double centre = 0.5 * (t.c_start_s + t.c_end_s);
          if (!ps.x.empty()) {  // a NaN point breaks the line between tokens
            ps.x.push_back(std::nan(""));
            ps.y.push_back(std::nan(""));
          }
          for (size_t k = 0; k < t.k.size(); ++k) {
            ps.x.push_back(1000.0 * (t.k_times_s[k] - centre));
            ps.y.push_back(t.k[k]);
          }
        }
        panel.series.push_back(std::move(ps));
      }
      // The stylised k for a consonant of the mean token duration.
      double dur = 0;
      int n = 0;
      for (const coarticulation::VcvToken& t : fit.tokens)
        if (t.consonant == c.consonant) dur += t.c_end_s - t.c_start_s, ++n;
      dur /= std::max(1, n);
      report::PlotSeries style;
      style.name = "stylised (mean duration)";
      style.style = report::PlotSeries::Style::kDashed;
      for (double tau = -0.2; tau <= 0.2 + 1e-9; tau += 0.002) {
        style.x.push_back(1000.0 * tau);
        style.y.push_back(c.k_style.Evaluate(tau, -0.5 * dur, 0.5 * dur));
      }
      panel.series.push_back(std::move(style));
      const std::string path = (fs::path(options.figures) / ("ohman_k_" + c.consonant + ".png")).string();
      figures::SavePlots(path, "Emergence k(t) of [" + c.consonant + "] in its contexts", {panel}, 1);
      result["figures"].push_back(path);
    }
  }
  if (!options.output.empty()) {
    WriteJsonFile(options.output, result["fit"]);
    result["output"] = options.output;
  }
  progress.Update("fitting the Öhman model", 1.0);
  return result;
}

std::string OhmanText(const json& r) {
  std::string s;
  const json& fit = r.at("fit");
  const json& params = fit.at("parameters");
  const size_t P = params.size();
  s += "Öhman coarticulation model: " + std::to_string(r.at("summary").at("tokens").get<size_t>()) + " VCV tokens, " +
       std::to_string(r.at("summary").at("consonants").get<size_t>()) + " consonants, " + std::to_string(P) +
       " parameters (face model " + r.at("models").get<std::string>() + ")\n";
  for (const json& t : r.at("takes")) {
    s += "  take " + t.at("take").get<std::string>() + ": " + std::to_string(t.at("tokens").get<int>()) + " tokens, " +
         std::to_string(t.at("solved_frames").get<int64_t>()) + "/" + std::to_string(t.at("frames").get<int64_t>()) +
         " frames solved";
    if (t.contains("generation")) {
      const json& g = t["generation"];
      s += "; generated vs inverted r:";
      for (const json& c : g.at("correlation")) s += " " + Fixed(c, 3);
      if (!g.at("unknown_phones").empty()) {
        s += " (left out:";
        for (const json& u : g.at("unknown_phones")) s += " " + u.get<std::string>();
        s += ")";
      }
    }
    s += "\n";
  }
  for (const json& t : r.at("skipped"))
    s += "  skipped " + t.at("take").get<std::string>() + ": " + t.at("reason").get<std::string>() + "\n";
  s += "Vowel references:\n";
  for (const json& v : fit.at("vowels")) {
    s += "  " + v.at("vowel").get<std::string>() + " (" + v.at("source").get<std::string>() + ", " +
         std::to_string(v.at("occurrences").get<int>()) + "):";
    for (const json& x : v.at("target")) s += " " + Fixed(x, 3);
    s += "\n";
  }
  for (const json& c : fit.at("consonants")) {
    const json& ks = c.at("k_style");
    s += "[" + c.at("consonant").get<std::string>() + "] " + std::to_string(c.at("tokens").get<int>()) +
         " tokens; k: plateau from start + " + Fixed(1000.0 * ks.at("left_inset_s").get<double>(), 0) +
         " ms to end - " + Fixed(1000.0 * ks.at("right_inset_s").get<double>(), 0) + " ms, ramps " +
         Fixed(1000.0 * ks.at("left_ramp_s").get<double>(), 0) + " / " +
         Fixed(1000.0 * ks.at("right_ramp_s").get<double>(), 0) + " ms, rms " + Fixed(ks.at("rms"), 3) + "\n";
    s += "  parameter        w        c   residual  effect per context\n";
    for (size_t x = 0; x < P; ++x) {
      char line[160];
      std::snprintf(line, sizeof line, "  %-12s %8s %8s %8s ", params[x].get<std::string>().c_str(),
                    Fixed(c.at("w")[x], 3).c_str(), Fixed(c.at("c")[x], 3).c_str(),
                    Fixed(c.at("residual")[x], 3).c_str());
      s += line;
      for (const json& v : c.at("contexts"))
        s += "  " + v.get<std::string>() + " " + Fixed(c.at("effect").at(v.get<std::string>())[x], 3);
      s += "\n";
    }
  }
  for (const json& w : fit.at("warnings")) s += "warning: " + w.get<std::string>() + "\n";
  for (const json& f : r.at("figures")) s += "figure: " + f.get<std::string>() + "\n";
  if (r.contains("output")) s += "fit written to " + r.at("output").get<std::string>() + "\n";
  return s;
}

}  // namespace csw::jobs
