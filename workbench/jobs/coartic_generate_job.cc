#include "workbench/jobs/coartic_generate_job.h"

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <sstream>

#include "analysis/coarticulation/ohman.h"
#include "core/error.h"
#include "core/file_util.h"
#include "core/json_util.h"
#include "io/formats/textgrid.h"
#include "workbench/jobs/figures.h"
#include "workbench/jobs/job_util.h"
#include "workbench/jobs/ohman_job.h"
#include "workbench/jobs/tier_util.h"

namespace csw::jobs {

using nlohmann::json;

namespace {

double Round(double v, double step) { return std::isfinite(v) ? std::round(v / step) * step : v; }

}  // namespace

std::string CoarticGenerateOptions::Check() const {
  if (fit.empty()) return "give the Öhman fit file (csw coartic fit -o)";
  if (phones.empty() == textgrid.empty())
    return "give the phones either as text (--phones) or as a TextGrid (--textgrid)";
  if (!textgrid.empty() && tier.empty()) return "--tier must name the phone tier";
  for (double d : {vowel_ms, consonant_ms, pause_ms}) {
    if (!(d > 0) || !std::isfinite(d)) return "default phone durations must be positive";
  }
  if (!(rate_hz > 0 && rate_hz <= 10000)) return "--rate must be in (0, 10000] Hz";
  return "";
}

std::vector<Label> ParsePhoneString(const std::string& text, const std::vector<std::string>& vowels,
                                    const CoarticGenerateOptions& options) {
  std::vector<Label> out;
  std::istringstream in(text);
  std::string item;
  double t = 0;
  while (in >> item) {
    std::string symbol = item;
    double ms = 0;
    const size_t colon = item.rfind(':');
    if (colon != std::string::npos && colon > 0) {
      symbol = item.substr(0, colon);
      const std::string d = item.substr(colon + 1);
      char* end = nullptr;
      ms = std::strtod(d.c_str(), &end);
      if (d.empty() || end == nullptr || *end != '\0' || !(ms > 0) || !std::isfinite(ms) || ms > 60000) {
        throw InvalidInput("phones: '" + item + "': the duration after ':' must be milliseconds in (0, 60000]");
      }
    }
    const bool pause = coarticulation::IsPauseLabel(symbol) || symbol == "_" || symbol == "#";
    if (ms == 0) {
      if (pause) {
        ms = options.pause_ms;
      } else {
        ms = std::find(vowels.begin(), vowels.end(), symbol) != vowels.end() ? options.vowel_ms : options.consonant_ms;
      }
    }
    out.push_back({t, t + ms / 1000.0, pause ? std::string() : symbol});
    t += ms / 1000.0;
  }
  if (out.empty()) throw InvalidInput("phones: no phone in '" + text + "'");
  return out;
}

json CoarticGenerate(const CoarticGenerateOptions& options, Progress& progress) {
  if (std::string why = options.Check(); !why.empty()) throw UsageError(why);
  progress.Update("coartic generate", 0.0);
  std::vector<std::string> names;
  const coarticulation::OhmanFit fit =
      OhmanFitFromJson(ParseJsonText(ReadTextFile(options.fit), options.fit), options.fit, &names);
  std::vector<Label> phones;
  double end_s = 0;
  if (!options.textgrid.empty()) {
    const std::vector<LabelTier> tiers = ReadTextGrid(options.textgrid);
    const LabelTier* tier = FindTier(tiers, options.tier);
    if (tier == nullptr) {
      throw InvalidInput(options.textgrid + ": no tier '" + options.tier + "' (tiers: " + TierNames(tiers) + ")");
    }
    if (tier->kind != LabelTier::Kind::kInterval) {
      throw InvalidInput(options.textgrid + ": tier '" + options.tier + "' is not an interval tier");
    }
    phones = tier->labels;
    end_s = tier->end_s;
  } else {
    phones = ParsePhoneString(options.phones, fit.vowels, options);
    end_s = phones.back().end_s;
  }
  phones = coarticulation::NormalisePhones(phones, end_s);
  const double duration = std::max(end_s, phones.empty() ? 0.0 : phones.back().end_s);
  const auto samples = static_cast<int64_t>(std::floor(duration * options.rate_hz + 1e-6)) + 1;
  std::vector<double> times(static_cast<size_t>(samples));
  for (int64_t i = 0; i < samples; ++i) times[static_cast<size_t>(i)] = static_cast<double>(i) / options.rate_hz;
  coarticulation::GenerateOptions g;
  g.skip_unknown = options.skip_unknown;
  Eigen::MatrixXd p;
  try {
    p = coarticulation::GenerateOhman(fit, phones, times, g);
  } catch (const InvalidInput& e) {
    throw InvalidInput(options.fit + ": " + e.what());
  }
  const Eigen::MatrixXd carrier = coarticulation::OhmanCarrier(fit, phones, times, g);
  if (names.size() != static_cast<size_t>(p.cols())) {
    names.clear();
    for (int k = 0; k < p.cols(); ++k) names.push_back("p" + std::to_string(k + 1));
  }
  json result = {{"fit", options.fit},    {"rate_hz", options.rate_hz},
                 {"samples", samples},    {"duration_s", Round(duration, 1e-6)},
                 {"parameters", names},   {"phones", json::array()},
                 {"range", json::array()}};
  for (const Label& l : phones) {
    result["phones"].push_back(
        {{"phone", l.text}, {"start_s", Round(l.start_s, 1e-6)}, {"end_s", Round(l.end_s, 1e-6)}});
  }
  for (int k = 0; k < p.cols(); ++k) {
    result["range"].push_back({{"parameter", names[static_cast<size_t>(k)]},
                               {"min", Round(p.col(k).minCoeff(), 1e-6)},
                               {"max", Round(p.col(k).maxCoeff(), 1e-6)}});
  }
  if (!options.output.empty()) {
    std::ostringstream out;
    out << "time_s";
    for (const std::string& n : names) out << "," << n;
    out << "\n";
    char buf[64];
    for (int64_t i = 0; i < samples; ++i) {
      std::snprintf(buf, sizeof(buf), "%.6f", times[static_cast<size_t>(i)]);
      out << buf;
      for (int k = 0; k < p.cols(); ++k) {
        std::snprintf(buf, sizeof(buf), ",%.9g", p(i, k));
        out << buf;
      }
      out << "\n";
    }
    const std::string tmp = HiddenSibling(options.output, ".tmp");
    {
      std::ofstream f(tmp, std::ios::binary);
      if (!f) throw IoError(options.output, "cannot open for writing");
      f << out.str();
      f.close();
      if (!f) throw IoError(options.output, "write failed");
    }
    ReplaceFileDurably(tmp, options.output);
    result["output"] = options.output;
  }
  if (!options.figures.empty()) {
    figures::Require();
    std::filesystem::create_directories(options.figures);
    std::vector<double> marks;
    for (const Label& l : phones) marks.push_back(l.start_s);
    std::string phone_text;
    for (const Label& l : phones) phone_text += l.text.empty() ? "_ " : l.text + " ";
    std::vector<report::PlotPanel> panels;
    for (int k = 0; k < p.cols(); ++k) {
      report::PlotPanel panel{names[static_cast<size_t>(k)], "time (s)", names[static_cast<size_t>(k)], {}, marks};
      report::PlotSeries gen{"generated", times, {}, report::PlotSeries::Style::kLine, 0};
      report::PlotSeries car{"vocalic carrier", times, {}, report::PlotSeries::Style::kDashed, 7};
      for (int64_t i = 0; i < samples; ++i) {
        gen.y.push_back(p(i, k));
        car.y.push_back(carrier(i, k));
      }
      panel.series = {car, gen};
      panels.push_back(panel);
    }
    const std::string png = (std::filesystem::path(options.figures) / "generated.png").string();
    figures::SavePlots(png, "Öhman generation: " + phone_text, panels, 2);
    result["figures"] = json::array({png});
  }
  progress.Update("coartic generate", 1.0);
  return result;
}

std::string CoarticGenerateText(const json& r) {
  std::ostringstream o;
  o << "generated " << r["samples"].get<int64_t>() << " samples at " << r["rate_hz"].get<double>() << " Hz ("
    << r["duration_s"].get<double>() << " s) from " << r["fit"].get<std::string>() << "\nphones:";
  for (const json& p : r["phones"]) {
    const std::string s = p["phone"].get<std::string>();
    o << " " << (s.empty() ? "_" : s);
  }
  o << "\n";
  char buf[200];
  for (const json& x : r["range"]) {
    std::snprintf(buf, sizeof(buf), "  %-12s %10.4f .. %10.4f\n", x["parameter"].get<std::string>().c_str(),
                  x["min"].get<double>(), x["max"].get<double>());
    o << buf;
  }
  if (r.contains("output")) o << "trajectories: " << r["output"].get<std::string>() << "\n";
  if (r.contains("figures")) {
    for (const json& f : r["figures"]) o << "figure: " << f.get<std::string>() << "\n";
  }
  return o.str();
}

}  // namespace csw::jobs
