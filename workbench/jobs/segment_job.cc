#include "workbench/jobs/segment_job.h"

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <iomanip>
#include <sstream>

#include "analysis/signing/segmentation.h"
#include "core/error.h"
#include "io/corpus/corpus.h"
#include "workbench/jobs/figures.h"
#include "workbench/jobs/job_util.h"
#include "workbench/jobs/take_data.h"
#include "workbench/jobs/take_selection.h"
#include "workbench/jobs/tier_util.h"

namespace csw::jobs {

using nlohmann::json;

namespace {

// v rounded to `digits` decimals (as a JSON number prints without noise digits).
double Round(double v, int digits) {
  const double scale = std::pow(10.0, digits);
  return std::isfinite(v) ? std::round(v * scale) / scale : v;
}

signing::SegmentationOptions ToAnalysis(const SegmentOptions& o) {
  signing::SegmentationOptions s;
  s.speed.cutoff_hz = o.cutoff_hz;
  s.speed.order = o.order;
  s.refine.threshold_s = o.threshold_s;
  s.rest.rest_speed_mm_s = o.rest_speed_mm_s;
  s.rest.min_rest_s = o.min_rest_s;
  s.right = o.hand != "left";
  s.left = o.hand != "right";
  s.right_wrist = o.right_wrist;
  s.left_wrist = o.left_wrist;
  s.right_tier = o.right_tier.empty() ? o.tier + "_right" : o.right_tier;
  s.left_tier = o.left_tier.empty() ? o.tier + "_left" : o.left_tier;
  return s;
}

}  // namespace

std::string SegmentOptions::Check() const {
  if (corpus.empty()) return "no corpus given";
  if (tier.empty()) return "--tier must name the manual sign/transition tier";
  if (hand != "right" && hand != "left" && hand != "both")
    return "--hand must be right, left or both, not '" + hand + "'";
  if (!(cutoff_hz >= 0.0 && std::isfinite(cutoff_hz))) return "--cutoff-hz must be >= 0 (0 = no filter)";
  if (order < 2 || order > 8 || order % 2 != 0) return "--order must be 2, 4, 6 or 8";
  if (!(threshold_s > 0.0 && threshold_s <= 5.0)) return "--threshold-s must be in (0, 5] seconds";
  if (!(rest_speed_mm_s >= 0.0 && rest_speed_mm_s <= 1000.0)) return "--rest-speed must be in [0, 1000] mm/s";
  if (!(min_rest_s > 0.0 && min_rest_s <= 10.0)) return "--min-rest-s must be in (0, 10] seconds";
  const signing::SegmentationOptions s = ToAnalysis(*this);
  if (s.right && s.left && s.right_tier == s.left_tier) return "the right and left output tiers must differ";
  for (const std::string* t : {&s.right_tier, &s.left_tier})
    if (*t == tier) return "the output tier '" + *t + "' would replace the manual tier";
  return "";
}

json Segment(const SegmentOptions& options, Progress& progress) {
  if (const std::string why = options.Check(); !why.empty()) throw UsageError(why);
  const signing::SegmentationOptions seg = ToAnalysis(options);
  if (!options.figures.empty()) {
    figures::Require();
    std::filesystem::create_directories(options.figures);
  }
  const Corpus corpus = Corpus::Open(options.corpus);
  const std::vector<TakeRange> ranges = SelectCorpusTakes(corpus, options.takes);
  json figure_files = json::array();
  json result = {{"corpus", options.corpus},
                 {"tier", options.tier},
                 {"dry_run", options.dry_run},
                 {"options",
                  {{"cutoff_hz", options.cutoff_hz},
                   {"order", options.order},
                   {"threshold_s", options.threshold_s},
                   {"rest_speed_mm_s", options.rest_speed_mm_s},
                   {"min_rest_s", options.min_rest_s}}},
                 {"takes", json::array()}};
  std::vector<std::pair<std::string, std::vector<LabelTier>>> writes;
  int64_t all_boundaries = 0, all_moved = 0;
  for (size_t i = 0; i < ranges.size(); ++i) {
    const TakeRange& range = ranges[i];
    progress.Update("segment: " + range.take, static_cast<double>(i) / static_cast<double>(ranges.size()));
    progress.CheckCancel();
    const std::string where = corpus.path() + ": take '" + range.take + "'";
    Take take = corpus.LoadTake(range.take);
    if (range.first != 0 || range.count != take.frames())
      throw UsageError("csw segment works on whole takes: '" + range.spec + "' selects frames of take '" + range.take +
                       "'");
    const LabelTier* manual = FindTier(take.tiers, options.tier);
    if (manual == nullptr)
      throw InvalidInput(where + ": no tier '" + options.tier + "' (tiers: " + TierNames(take.tiers) +
                         "); name the manual sign/transition tier with --tier");
    std::vector<signing::HandSegmentation> hands;
    try {
      hands = signing::RefineSegmentation(take, *manual, seg);
    } catch (const InvalidInput& e) {
      throw InvalidInput(corpus.path() + ": " + e.what());
    }
    json tj = {{"take", range.spec}, {"rate_hz", take.rate_hz}, {"hands", json::array()}};
    std::vector<LabelTier> tiers;
    for (LabelTier& t : take.tiers) {
      bool replaced = false;
      for (const auto& h : hands) replaced = replaced || t.name == h.tier.name;
      if (!replaced) tiers.push_back(std::move(t));
    }
    for (const signing::HandSegmentation& h : hands) {
      json moves = json::array();
      double sum = 0, max = 0;
      int kept = 0;
      for (const signing::BoundaryRefinement& b : h.boundaries) {
        json m = {{"manual_s", Round(b.manual_s, 4)}, {"refined_s", Round(b.refined_s, 4)}, {"moved", b.moved}};
        if (!b.moved) {
          m["why"] = b.why;
          ++kept;
        } else {
          sum += std::abs(b.refined_s - b.manual_s);
          max = std::max(max, std::abs(b.refined_s - b.manual_s));
        }
        moves.push_back(m);
      }
      const int moved = h.moved();
      tj["hands"].push_back({{"hand", h.hand == 'R' ? "right" : "left"},
                             {"wrist", h.marker_name},
                             {"tier", h.tier.name},
                             {"boundaries", h.boundaries.size()},
                             {"moved", moved},
                             {"kept", kept},
                             {"minima", h.minima.size()},
                             {"shift_ms",
                              {{"mean", moved ? json(Round(1000 * sum / moved, 1)) : json(nullptr)},
                               {"max", moved ? json(Round(1000 * max, 1)) : json(nullptr)}}},
                             {"moves", moves}});
      all_boundaries += static_cast<int64_t>(h.boundaries.size());
      all_moved += moved;
      tiers.push_back(h.tier);
    }
    if (!options.figures.empty()) {
      // Speeds as fractions of the take's largest (the lanes are drawn in [0, 1]).
      double top = 0;
      for (const auto& h : hands)
        for (double v : h.speed)
          if (std::isfinite(v)) top = std::max(top, v);
      report::PosteriorLane lane;
      lane.name = "wrist speed / " + std::to_string(static_cast<int>(std::round(top))) + " mm/s";
      lane.posteriors.resize(take.frames(), static_cast<Eigen::Index>(hands.size()));
      for (size_t k = 0; k < hands.size(); ++k) {
        lane.classes.push_back(hands[k].hand == 'R' ? "right" : "left");
        lane.posteriors.col(static_cast<Eigen::Index>(k)) = hands[k].speed / (top > 0 ? top : 1.0);
      }
      std::vector<LabelTier> drawn = {*FindTier(tiers, options.tier)};
      for (const auto& h : hands) drawn.push_back(h.tier);
      for (const std::string& name : options.figure_tiers) {
        const LabelTier* t = FindTier(tiers, name);
        if (t == nullptr)
          throw InvalidInput(where + ": no tier '" + name + "' to draw (tiers: " + TierNames(tiers) + ")");
        drawn.push_back(*t);
      }
      const std::string path = (std::filesystem::path(options.figures) / ("segment_" + range.take + ".png")).string();
      figures::SaveGesturalScore(path, "Segmentation refinement: " + range.take, {}, 1.0, 0.0, {lane}, take.rate_hz,
                                 drawn, 0.0, take.duration_s());
      figure_files.push_back(path);
    }
    result["takes"].push_back(tj);
    writes.emplace_back(range.take, std::move(tiers));
  }
  result["figures"] = figure_files;
  result["boundaries"] = all_boundaries;
  result["moved"] = all_moved;
  result["tiers_written"] = !options.dry_run && !writes.empty();
  if (!options.dry_run && !writes.empty()) {
    progress.Update("writing tiers", 1.0);
    CorpusTransaction tx(options.corpus, progress);
    for (const auto& [name, tiers] : writes) tx.WriteTiers(name, tiers);
    tx.Commit();
  }
  return result;
}

std::string SegmentText(const json& r) {
  std::ostringstream o;
  o << std::fixed;
  for (const json& t : r["takes"]) {
    for (const json& h : t["hands"]) {
      o << "take " << t["take"].get<std::string>() << ", " << h["hand"].get<std::string>() << " hand ("
        << h["wrist"].get<std::string>() << "): " << h["moved"].get<int64_t>() << " of "
        << h["boundaries"].get<int64_t>() << " boundaries moved";
      if (!h["shift_ms"]["mean"].is_null())
        o << std::setprecision(1) << " (by " << h["shift_ms"]["mean"].get<double>() << " ms on average, "
          << h["shift_ms"]["max"].get<double>() << " ms at most)";
      o << " -> tier '" << h["tier"].get<std::string>() << "'\n";
      for (const json& m : h["moves"])
        if (!m["moved"].get<bool>())
          o << std::setprecision(3) << "  kept " << m["manual_s"].get<double>() << " s: " << m["why"].get<std::string>()
            << "\n";
    }
  }
  o << r["moved"].get<int64_t>() << " of " << r["boundaries"].get<int64_t>() << " boundaries moved";
  if (r["tiers_written"].get<bool>())
    o << "; refined tiers written";
  else if (r["dry_run"].get<bool>())
    o << " (dry run: nothing written)";
  o << "\n";
  return o.str();
}

}  // namespace csw::jobs
