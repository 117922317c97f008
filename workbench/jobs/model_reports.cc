#include "workbench/jobs/model_reports.h"

#include <algorithm>
#include <cstdio>
#include <sstream>
#include <utility>
#include <vector>

namespace csw::jobs {

using nlohmann::json;

namespace {

// "0.123 ± 0.045 mm (max 0.678, n=90)" or "no samples".
std::string StatsText(const json& j) {
  if (j.value("count", 0) == 0) return std::string("no samples");
  std::ostringstream t;
  t.setf(std::ios::fixed);
  t.precision(3);
  t << j["mean_mm"].get<double>() << " ± " << j["sd_mm"].get<double>() << " mm (";
  if (j.contains("p99_mm")) {
    t << "p99 " << j["p99_mm"].get<double>() << ", p99.9 " << j["p99_9_mm"].get<double>() << ", ";
  }
  t << "max " << j["max_mm"].get<double>() << ", n=" << j["count"].get<int64_t>() << ")";
  return t.str();
}

}  // namespace

json StatsJson(const ErrorStats& s, const std::string& unit) {
  if (s.count == 0) return json{{"count", 0}};
  return json{{"count", s.count}, {"mean_" + unit, s.mean}, {"sd_" + unit, s.sd}, {"max_" + unit, s.max}};
}

json StatsJson(const ErrorSamples& s, const std::string& unit) {
  json j = StatsJson(s.stats, unit);
  if (s.stats.count == 0) return j;
  j["p99_" + unit] = s.Percentile(99.0);
  j["p99_9_" + unit] = s.Percentile(99.9);
  return j;
}

std::string FitText(const json& s) {
  std::ostringstream o;
  o.setf(std::ios::fixed);
  o.precision(3);
  o << "fitted " << s.value("kind", "") << " model(s) into " << s.value("output", "") << " from "
    << s["training_takes"].size() << " take(s)\n";
  if (s.contains("rigid")) {
    for (const auto& m : s["rigid"]) {
      o << "  " << m["name"].get<std::string>() << " motion: " << m["motion_parameters"].get<int>()
        << " parameters over " << m["training_frames"].get<int64_t>() << " frames, cluster rms "
        << m["rms_mm"].get<double>() << " mm\n";
      if (m.contains("takes")) {
        for (const auto& t : m["takes"]) {
          o << "    " << t["take"].get<std::string>() << ": residual " << StatsText(t["residual"]) << "\n";
        }
      }
    }
  }
  auto variance = [&](const json& names, const json& ev) {
    double cum = 0;
    for (size_t k = 0; k < ev.size(); ++k) {
      cum += ev[k].get<double>();
      o << "    " << (names.is_array() ? names[k].get<std::string>() : "p" + std::to_string(k + 1)) << ": "
        << 100 * ev[k].get<double>() << " % (cumulated " << 100 * cum << " %)\n";
    }
  };
  if (s.contains("face")) {
    const json& f = s["face"];
    o << "  face: " << f["parameters"].size() << " parameters, " << f["selected_frames"].get<int64_t>() << " of "
      << f["training_frames"].get<int64_t>() << " frames selected, training rms " << f["training_rms_mm"].get<double>()
      << " mm\n";
    variance(f["parameters"], f["variance_explained"]);
    for (const auto& t : f["throat"]) {
      o << "    throat " << t["marker"].get<std::string>() << ": head weight " << t["head_weight"].get<double>()
        << (t["fitted"].get<bool>() ? " (fitted)" : " (fixed)");
      if (t.contains("rotation_offset_mm")) {
        const json& k = t["rotation_offset_mm"];
        char buf[96];
        std::snprintf(buf, sizeof buf, ", rotation offset (%.1f, %.1f, %.1f) mm", k[0].get<double>(),
                      k[1].get<double>(), k[2].get<double>());
        o << buf;
      }
      o << "\n";
    }
  }
  if (s.contains("hand")) {
    const json& h = s["hand"];
    o << "  hand: " << h["parameters"].get<int>() << " parameters from " << h["angles"].get<size_t>() << " angles, "
      << h["selected_frames"].get<int64_t>() << " of " << h["training_frames"].get<int64_t>()
      << " frames selected, training rms " << h["training_rms_mm"].get<double>() << " mm\n";
    if (h.contains("gaussian_fill")) {
      o << "  hand gap filler: Gaussian, " << h["gaussian_fill"]["frames"].get<int64_t>()
        << " training frames (incomplete ones included), " << h["gaussian_fill"]["iterations"].get<int>()
        << " EM rounds\n";
    }
    variance(json(), h["variance_explained"]);
    for (const auto& w : h.value("warnings", json::array())) o << "  hand warning: " << w.get<std::string>() << "\n";
  }
  for (const auto& f : s["figures"]) o << "  figure: " << f.get<std::string>() << "\n";
  if (s.contains("warnings")) {
    for (const auto& w : s["warnings"]) o << "  warning: " << w.get<std::string>() << "\n";
  }
  return o.str();
}

std::string InvertText(const json& s) {
  std::ostringstream o;
  o.setf(std::ios::fixed);
  o.precision(3);
  for (const char* kind : {"face", "hand"}) {
    if (!s.contains(kind)) continue;
    const json& m = s[kind];
    o << kind << " (target " << m["target_mm"].get<double>() << " mm):\n";
    for (const auto& t : m["takes"]) {
      o << "  " << t["take"].get<std::string>() << " [" << t["role"].get<std::string>() << "] "
        << t["solved_frames"].get<int64_t>() << "/" << t["frames"].get<int64_t>() << " frames, visible "
        << StatsText(t["visible"]);
      if (t.contains("hidden")) o << ", hidden " << StatsText(t["hidden"]);
      if (t.contains("occluded")) o << ", occluded " << StatsText(t["occluded"]);
      o << "\n";
    }
    for (const char* role : {"training", "held_out"}) {
      const json& r = m[role];
      if (r["visible"].value("count", 0) == 0) continue;
      o << "  " << role << ": visible " << StatsText(r["visible"]);
      if (r.contains("hidden")) {
        o << "; hidden " << StatsText(r["hidden"]) << " (model alone " << StatsText(r["hidden_model"]) << ")";
      }
      if (r.contains("occluded")) {
        o << "; occluded " << StatsText(r["occluded"]) << " (model alone " << StatsText(r["occluded_model"]) << ")";
      }
      o << "\n";
    }
    if (m["overall"].contains("pose")) {
      const json& p = m["overall"]["pose"];
      if (p["rotation_deg"].value("count", 0) > 0) {
        o << "  pose vs truth: " << p["rotation_deg"]["mean_deg"].get<double>() << "° and "
          << p["translation_mm"]["mean_mm"].get<double>() << " mm on average\n";
      }
    }
    // The 3 shape markers with the largest 99.9th percentile, visible and hidden.
    if (m.contains("markers")) {
      for (const char* which : {"visible", "hidden"}) {
        std::vector<std::pair<double, std::string>> ranked;
        for (const auto& e : m["markers"]) {
          if (e.value("role", "") != "shape" || !e.contains(which) || !e[which].contains("p99_9_mm")) continue;
          ranked.emplace_back(e[which]["p99_9_mm"].get<double>(), e["marker"].get<std::string>());
        }
        if (ranked.empty()) continue;
        std::stable_sort(ranked.begin(), ranked.end(), [](const auto& a, const auto& b) { return a.first > b.first; });
        o << "  largest p99.9 " << which << ":";
        for (size_t i = 0; i < std::min<size_t>(ranked.size(), 3); ++i) {
          o << (i ? ", " : " ") << ranked[i].second << " " << ranked[i].first << " mm";
        }
        o << "\n";
      }
    }
    if (m.contains("worst_frames")) {
      const json& w = m["worst_frames"];
      for (size_t i = 0; i < std::min<size_t>(w.size(), 5); ++i) {
        const json& f = w[i];
        o << (i == 0 ? "  worst frames: " : "                ") << f["take"].get<std::string>() << " frame "
          << f["frame"].get<int64_t>() << " (" << f["time_s"].get<double>() << " s): max "
          << f["max_error_mm"].get<double>() << " mm at " << f["max_error_marker"].get<std::string>() << ", mean "
          << f["mean_error_mm"].get<double>() << " mm, " << f["status"].get<std::string>() << ", "
          << f["iterations"].get<int>() << " iterations" << (f["cold_retry"].get<bool>() ? ", cold retry" : "") << "\n";
      }
    }
  }
  if (s.contains("filled")) {
    for (const auto& f : s["filled"]) {
      o << "filled " << f["samples_filled"].get<int64_t>() << " samples of " << f["take"].get<std::string>()
        << " into new take " << f["filled_take"].get<std::string>() << "\n";
    }
  }
  for (const auto& f : s["figures"]) o << "figure: " << f.get<std::string>() << "\n";
  if (s.contains("warnings")) {
    for (const auto& w : s["warnings"]) o << "warning: " << w.get<std::string>() << "\n";
  }
  return o.str();
}

}  // namespace csw::jobs
