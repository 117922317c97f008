#include "workbench/jobs/clean_job.h"

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <map>
#include <memory>
#include <optional>
#include <set>
#include <sstream>

#include "analysis/cleaning/dct_fill.h"
#include "analysis/cleaning/fill.h"
#include "analysis/cleaning/filter.h"
#include "analysis/cleaning/gaps.h"
#include "analysis/cleaning/label_swaps.h"
#include "analysis/cleaning/pattern_fill.h"
#include "analysis/cleaning/rigid_fill.h"
#include "analysis/cleaning/spikes.h"
#include "analysis/cleaning/spline_fill.h"
#include "core/error.h"
#include "core/markerset.h"
#include "io/c3d/c3d.h"
#include "io/corpus/corpus.h"
#include "workbench/jobs/figures.h"
#include "workbench/jobs/invert_job.h"
#include "workbench/jobs/job_util.h"
#include "workbench/jobs/take_data.h"
#include "workbench/jobs/take_selection.h"

namespace csw::jobs {

namespace fs = std::filesystem;
using nlohmann::json;
using namespace csw::cleaning;

namespace {

const std::vector<std::string>& KnownMethods() {
  static const std::vector<std::string> m = {"spline", "rigid", "pattern", "dct", "model"};
  return m;
}

// The fill methods named in options (after splitting commas), in order.
std::vector<std::string> MethodList(const std::vector<std::string>& args) {
  std::vector<std::string> out;
  for (const std::string& a : args) {
    std::stringstream ss(a);
    std::string item;
    while (std::getline(ss, item, ',')) {
      if (!item.empty()) out.push_back(item);
    }
  }
  return out;
}

}  // namespace

std::string CleanOptions::Check() const {
  if (corpus.empty()) return "no corpus given";
  std::set<std::string> seen;
  for (const std::string& m : MethodList(fill)) {
    if (std::find(KnownMethods().begin(), KnownMethods().end(), m) == KnownMethods().end())
      return "--fill: unknown method '" + m + "' (spline, rigid, pattern, dct, model)";
    if (!seen.insert(m).second) return "--fill: method '" + m + "' given twice";
  }
  if (seen.count("model") && models.empty()) return "--fill model needs --models MODELS.h5 (from csw fit)";
  if (!seen.count("model") && !models.empty()) return "--models is only used by --fill model";
  if (!(max_gap_s >= 0)) return "--max-gap must be >= 0 seconds";
  if (spline != "smoothing" && spline != "cubic" && spline != "quintic")
    return "--spline must be smoothing, cubic or quintic";
  if (side_frames < 1) return "--side-frames must be >= 1";
  for (const std::string& d : donors) {
    const auto eq = d.find('=');
    if (eq == std::string::npos || eq == 0 || eq + 1 == d.size()) return "--donor '" + d + "': expected MARKER=DONOR";
  }
  if (!filter.empty() && filter != "butterworth" && filter != "kalman") return "--filter must be butterworth or kalman";
  if (filter == "butterworth") {
    if (!(cutoff_hz > 0)) return "--cutoff must be > 0 Hz";
    if (order < 2 || order > 8 || order % 2 != 0) return "--order must be 2, 4, 6 or 8";
  }
  if (kalman_model != "velocity" && kalman_model != "acceleration")
    return "--kalman-model must be velocity or acceleration";
  return "";
}

namespace {

// The model fill: the models' reconstruction of the take, computed once.
class ModelFiller : public GapFiller {
 public:
  ModelFiller(MarkerArray reconstruction, std::string models)
      : recon_(std::move(reconstruction)), models_(std::move(models)) {}
  std::string name() const override { return "model"; }
  bool CanFill(const MarkerArray& in, const Gap& gap, std::string* why_not) const override {
    (void)in;
    for (int64_t f = gap.start; f < gap.end(); ++f) {
      if (IsMissing(recon_.at(f, gap.marker)[0])) {
        if (why_not) {
          *why_not = "the models reconstruct nothing at frame " + std::to_string(f) +
                     " (a marker of no model, or a frame whose solve failed)";
        }
        return false;
      }
    }
    return true;
  }
  bool Fill(const MarkerArray& in, const Gap& gap, MarkerArray* out, FillRecord* record) const override {
    if (!CanFill(in, gap, nullptr)) return false;
    for (int64_t f = gap.start; f < gap.end(); ++f) {
      const float* src = recon_.at(f, gap.marker);
      std::copy(src, src + 3, out->at(f, gap.marker));
    }
    record->method = name();
    record->parameters = "models=" + models_;
    return true;
  }

 private:
  MarkerArray recon_;
  std::string models_;
};

// Columns of a role's markers that the take has (unbound names are skipped:
// a marker set may name more markers than one take carries).
std::vector<int> RoleColumns(const MarkerBinding& b, const std::vector<std::string>& names) {
  std::vector<int> cols;
  for (const std::string& n : names) {
    auto it = b.index.find(n);
    if (it != b.index.end()) cols.push_back(it->second);
  }
  return cols;
}

struct Groups {
  std::vector<std::vector<int>> rigid;    // rigid clusters (head, forearm, hand segments of >= 3 markers)
  std::vector<std::vector<int>> pattern;  // donor candidates (same cluster or segment)
  std::vector<std::vector<int>> swaps;    // pairs looked for inside these (hand segments, face, clusters)
};

Groups GroupsOf(const MarkerSet& set, const MarkerBinding& b) {
  Groups g;
  auto add = [](std::vector<std::vector<int>>& to, std::vector<int> cols, size_t min) {
    if (cols.size() >= min) to.push_back(std::move(cols));
  };
  add(g.rigid, RoleColumns(b, set.head_cluster), 3);
  add(g.rigid, RoleColumns(b, set.forearm_cluster), 3);
  for (const HandSegment& s : set.hand_segments) add(g.rigid, RoleColumns(b, s.markers), 4);
  std::vector<std::string> face = set.face;
  for (const ThroatMarker& t : set.throat) face.push_back(t.marker);
  std::vector<std::string> hand;
  for (const HandSegment& s : set.hand_segments) hand.insert(hand.end(), s.markers.begin(), s.markers.end());
  add(g.pattern, RoleColumns(b, set.head_cluster), 2);
  add(g.pattern, RoleColumns(b, set.forearm_cluster), 2);
  add(g.pattern, RoleColumns(b, face), 2);
  for (const HandSegment& s : set.hand_segments) add(g.pattern, RoleColumns(b, s.markers), 2);
  add(g.pattern, RoleColumns(b, hand), 2);
  return g;
}

json GapJson(const Gap& g, const std::vector<std::string>& names) {
  json j = {{"marker", names[static_cast<size_t>(g.marker)]}, {"start", g.start}, {"length", g.length}};
  if (g.leading) j["leading"] = true;
  if (g.trailing) j["trailing"] = true;
  return j;
}

json GapReportJson(const GapReport& r, const std::vector<std::string>& names, double rate_hz,
                   const std::vector<GapMethods>& assessed, const std::vector<std::string>& methods) {
  json per = json::array();
  for (const MarkerGaps& m : r.per_marker) {
    if (m.gaps.empty()) continue;
    json gaps = json::array();
    for (const Gap& g : m.gaps) gaps.push_back({g.start, g.length});
    per.push_back({{"marker", names[static_cast<size_t>(m.marker)]},
                   {"gaps", m.gaps.size()},
                   {"missing_frames", m.missing_frames},
                   {"fraction_missing", m.fraction_missing},
                   {"longest", m.longest},
                   {"longest_s", static_cast<double>(m.longest) / rate_hz},
                   {"never_visible", m.never_visible},
                   {"list", std::move(gaps)}});
  }
  const std::vector<Gap> all = r.AllGaps();
  json bins = json::array();
  const std::pair<int64_t, int64_t> kBins[] = {{1, 5}, {6, 20}, {21, 60}, {61, 0}};
  for (const auto& [lo, hi] : kBins) {
    bins.push_back({{"frames", hi ? std::to_string(lo) + "-" + std::to_string(hi) : "> " + std::to_string(lo - 1)},
                    {"gaps", CountGapsInRange(all, lo, hi)}});
  }
  // Which methods can fill how many gaps (each method alone), and gaps no method can fill.
  json can = json::object();
  for (const std::string& m : methods) can[m] = 0;
  int64_t none = 0, too_long = 0;
  for (const GapMethods& a : assessed) {
    for (const std::string& m : a.can_fill) can[m] = can[m].get<int64_t>() + 1;
    if (a.too_long) ++too_long;
    if (a.can_fill.empty()) ++none;
  }
  return {{"count", r.gap_count},
          {"missing_samples", r.missing_samples},
          {"fraction_missing", r.fraction_missing},
          {"longest", r.longest},
          {"longest_s", static_cast<double>(r.longest) / rate_hz},
          {"leading_or_trailing", r.leading_or_trailing},
          {"by_length", std::move(bins)},
          {"fillable_by", std::move(can)},
          {"longer_than_max_gap", too_long},
          {"fillable_by_none", none},
          {"per_marker", std::move(per)}};
}

std::string FillTierText(const FillRecord& r, const std::vector<std::string>& names) {
  return names[static_cast<size_t>(r.marker)] + " frames " + std::to_string(r.start) + "-" +
         std::to_string(r.start + r.length - 1) + " (" + std::to_string(r.length) + "): " + r.method +
         (r.parameters.empty() ? "" : " " + r.parameters);
}

// Errors of filled samples against the truth, by method and gap-length bin.
struct BinErrors {
  std::vector<double> errors;
};

json Quantiles(std::vector<double> e) {
  if (e.empty()) return {{"samples", 0}};
  std::sort(e.begin(), e.end());
  double sum = 0;
  for (double v : e) sum += v;
  auto at = [&](double q) {
    const size_t i = static_cast<size_t>(std::ceil(q * static_cast<double>(e.size()))) - 1;
    return e[std::min(i, e.size() - 1)];
  };
  return {{"samples", e.size()},
          {"mean_mm", sum / static_cast<double>(e.size())},
          {"p99_mm", at(0.99)},
          {"max_mm", e.back()}};
}

const char* BinName(int64_t length) {
  if (length <= 5) return "1-5";
  if (length <= 20) return "6-20";
  if (length <= 60) return "21-60";
  return "> 60";
}

// Scores the filled samples of `filled` against the truth take (columns by name).
json ScoreFills(const std::vector<FillRecord>& records, const MarkerArray& filled, const Take& truth,
                const std::vector<std::string>& names, const std::string& where) {
  std::vector<int> col(names.size(), -1);
  for (size_t i = 0; i < names.size(); ++i) {
    const int64_t c = truth.MarkerIndex(names[i]);
    col[i] = static_cast<int>(c);
  }
  if (truth.frames() != filled.frames())
    throw InvalidInput(where + ": the truth has " + std::to_string(truth.frames()) + " frames, the take " +
                       std::to_string(filled.frames()));
  std::map<std::string, std::map<std::string, std::vector<double>>> by;  // method -> bin -> errors
  std::vector<double> all;
  for (const FillRecord& r : records) {
    const int tc = col[static_cast<size_t>(r.marker)];
    if (tc < 0) continue;
    for (int64_t f = r.start; f < r.start + r.length; ++f) {
      const float* a = filled.at(f, r.marker);
      const float* b = truth.markers.at(f, tc);
      if (IsMissing(a[0]) || IsMissing(b[0])) continue;
      const double d = std::sqrt(std::pow(double(a[0]) - b[0], 2) + std::pow(double(a[1]) - b[1], 2) +
                                 std::pow(double(a[2]) - b[2], 2));
      by[r.method][BinName(r.length)].push_back(d);
      all.push_back(d);
    }
  }
  json j = {{"all", Quantiles(all)}, {"by_method", json::object()}};
  for (auto& [method, bins] : by) {
    json m = json::object();
    std::vector<double> pooled;
    for (auto& [bin, e] : bins) {
      pooled.insert(pooled.end(), e.begin(), e.end());
      m[bin] = Quantiles(std::move(e));
    }
    m["all"] = Quantiles(std::move(pooled));
    j["by_method"][method] = std::move(m);
  }
  return j;
}

// The take's gap map and its longest filled gap, before and after.
json DrawFigures(const std::string& take, const MarkerArray& before, const MarkerArray& after, const Take& truth,
                 const std::vector<FillRecord>& records, const std::vector<std::string>& names, double rate,
                 const std::string& folder) {
  json paths = json::array();
  fs::create_directories(folder);
  const std::string map_path = (fs::path(folder) / (take + "_gaps.png")).string();
  std::vector<std::vector<std::pair<int64_t, int64_t>>> gaps(static_cast<size_t>(before.markers()));
  for (const Gap& g : FindAllGaps(before)) gaps[static_cast<size_t>(g.marker)].push_back({g.start, g.length});
  figures::SaveGapMap(map_path, "Gaps of take " + take, names, gaps, before.frames(), rate);
  paths.push_back(map_path);
  if (records.empty()) return paths;
  const FillRecord* longest = &records.front();
  for (const FillRecord& r : records)
    if (r.length > longest->length) longest = &r;
  const int64_t margin = std::max<int64_t>(30, longest->length);
  const int64_t first = std::max<int64_t>(0, longest->start - margin);
  const int64_t end = std::min<int64_t>(before.frames(), longest->start + longest->length + margin);
  const Eigen::Index n = static_cast<Eigen::Index>(end - first);
  std::vector<double> time(static_cast<size_t>(n));
  Eigen::Matrix3Xd measured(3, n), filled(3, n), clean;
  const int64_t tc =
      truth.frames() == before.frames() ? truth.MarkerIndex(names[static_cast<size_t>(longest->marker)]) : -1;
  if (tc >= 0) clean.resize(3, n);
  for (Eigen::Index i = 0; i < n; ++i) {
    const int64_t f = first + i;
    time[static_cast<size_t>(i)] = static_cast<double>(f) / rate;
    for (int c = 0; c < 3; ++c) {
      measured(c, i) = before.at(f, longest->marker)[c];
      filled(c, i) = after.at(f, longest->marker)[c];
      if (tc >= 0) clean(c, i) = truth.markers.at(f, tc)[c];
    }
  }
  const std::string fill_path = (fs::path(folder) / (take + "_longest_fill.png")).string();
  const std::string marker = names[static_cast<size_t>(longest->marker)];
  figures::SaveGapFill(fill_path,
                       "Take " + take + ", marker " + marker + ": " + std::to_string(longest->length) +
                           "-frame gap filled by " + longest->method,
                       time, measured, clean, {{longest->method + " fill", filled}},
                       static_cast<double>(longest->start - 1) / rate,
                       static_cast<double>(longest->start + longest->length) / rate);
  paths.push_back(fill_path);
  return paths;
}

// One take through the pipeline.
json CleanTake(const Corpus& corpus, const TakeRange& range, const std::optional<MarkerSet>& given_set,
               const CleanOptions& options, const std::vector<std::string>& methods, Progress& progress,
               std::optional<Take>* cleaned) {
  Take take = corpus.LoadTake(range.take);
  const std::string where = corpus.path() + ": take '" + range.take + "'";
  if (range.first != 0 || range.count != take.frames())
    throw UsageError("csw clean works on whole takes: '" + range.spec + "' selects frames of take '" + range.take +
                     "'");
  if (!(take.rate_hz > 0)) throw InvalidInput(where + ": no frame rate");
  const double rate = take.rate_hz;
  const std::vector<std::string> names = take.marker_names;  // a copy: the take is moved into the result

  // The marker set: given, or remembered; required by rigid and pattern fills.
  std::optional<MarkerSet> set = given_set;
  if (!set) {
    const std::string text = corpus.TakeMarkerSet(range.take);
    if (!text.empty()) set = ParseMarkerSet(text, where);
  }
  const bool needs_set = std::find(methods.begin(), methods.end(), "rigid") != methods.end() ||
                         (std::find(methods.begin(), methods.end(), "pattern") != methods.end());
  if (needs_set && !set)
    throw UsageError("no marker set: take '" + range.take + "' of " + corpus.path() +
                     " was imported without --markerset; the rigid and pattern fills need one: give --markerset "
                     "SET.json");
  Groups groups;
  if (set) groups = GroupsOf(*set, BindMarkerSet(*set, names, false, where));

  json out = {{"take", range.take}, {"frames", take.frames()}, {"rate_hz", rate}, {"markers", names.size()}};
  MarkerArray markers = take.markers;
  bool changed = false;

  // 1. Label swaps.
  progress.Update("clean " + range.take + ": label swaps", 0.0);
  SwapOptions swap_options;
  const SwapReport swaps = DetectLabelSwaps(markers, rate, swap_options);
  json sj = json::array();
  for (const DetectedSwap& s : swaps.swaps) {
    sj.push_back({{"a", names[static_cast<size_t>(s.marker_a)]},
                  {"b", names[static_cast<size_t>(s.marker_b)]},
                  {"first_frame", s.first_frame},
                  {"end_frame", s.end_frame},
                  {"open_ended", s.open_ended},
                  {"confidence", s.confidence}});
  }
  if (options.fix_swaps && !swaps.swaps.empty()) {
    FixLabelSwaps(swaps.swaps, &markers);
    changed = true;
  }
  out["swaps"] = {{"detected", std::move(sj)}, {"fixed", options.fix_swaps && !swaps.swaps.empty()}};
  progress.CheckCancel();

  // 2. Spikes.
  progress.Update("clean " + range.take + ": spikes", 0.0);
  const SpikeReport spikes = DetectSpikes(markers, rate);
  json kj = json::array();
  for (const Spike& s : spikes.spikes) {
    kj.push_back({{"marker", names[static_cast<size_t>(s.marker)]},
                  {"frame", s.frame},
                  {"acceleration_mm_s2", s.acceleration_mm_s2},
                  {"offset_mm", s.offset_mm}});
  }
  int64_t removed = 0;
  if (options.fix_spikes && !spikes.spikes.empty()) {
    removed = RemoveSpikes(spikes.spikes, &markers);
    changed = true;
  }
  out["spikes"] = {
      {"threshold_mm_s2", spikes.threshold_mm_s2}, {"detected", std::move(kj)}, {"removed_samples", removed}};
  progress.CheckCancel();

  // 3. Gap report, and which methods can fill each gap.
  progress.Update("clean " + range.take + ": gap report", 0.0);
  const GapReport report = MakeGapReport(markers);
  const int64_t max_gap = options.max_gap_s > 0 ? static_cast<int64_t>(std::floor(options.max_gap_s * rate)) : 0;

  SplineFillOptions spline_options;
  spline_options.kind = options.spline == "cubic"     ? SplineKind::kCubic
                        : options.spline == "quintic" ? SplineKind::kQuintic
                                                      : SplineKind::kSmoothing;
  spline_options.side_frames = options.side_frames;
  DctFillOptions dct_options;
  dct_options.side_frames = options.side_frames;
  std::map<int, int> named_donors;
  for (const std::string& d : options.donors) {
    const auto eq = d.find('=');
    const std::string m = d.substr(0, eq), donor = d.substr(eq + 1);
    const auto im = std::find(names.begin(), names.end(), m);
    const auto id = std::find(names.begin(), names.end(), donor);
    if (im == names.end()) throw UsageError("--donor '" + d + "': " + where + " has no marker '" + m + "'");
    if (id == names.end()) throw UsageError("--donor '" + d + "': " + where + " has no marker '" + donor + "'");
    named_donors[static_cast<int>(im - names.begin())] = static_cast<int>(id - names.begin());
  }

  std::vector<std::unique_ptr<GapFiller>> owned;
  std::vector<const GapFiller*> fillers;
  // Without --fill the report still says which of the usual methods could fill each gap.
  const std::vector<std::string> assess_methods =
      methods.empty() ? std::vector<std::string>{"spline", "rigid", "pattern", "dct"} : methods;
  std::vector<std::string> assessed_names;
  for (const std::string& m : assess_methods) {
    if (m == "spline") {
      owned.push_back(std::make_unique<SplineFiller>(spline_options));
    } else if (m == "dct") {
      owned.push_back(std::make_unique<DctFiller>(dct_options));
    } else if (m == "rigid") {
      if (groups.rigid.empty()) continue;
      owned.push_back(std::make_unique<RigidClusterFiller>(RigidClusterFiller::FromMarkers(markers, groups.rigid)));
    } else if (m == "pattern") {
      if (groups.pattern.empty() && named_donors.empty()) continue;
      owned.push_back(std::make_unique<PatternFiller>(groups.pattern, PatternFillOptions{}, named_donors));
    } else if (m == "model") {
      progress.Update("clean " + range.take + ": model reconstruction", 0.0);
      InvertOptions io;
      io.corpus = options.corpus;
      io.models = options.models;
      io.inversion = options.inversion;
      owned.push_back(std::make_unique<ModelFiller>(ModelReconstruction(take, io, where, progress), options.models));
    }
    fillers.push_back(owned.back().get());
    assessed_names.push_back(m);
  }
  const std::vector<GapMethods> assessed = AssessGaps(markers, report.AllGaps(), fillers, max_gap);
  out["gaps"] = GapReportJson(report, names, rate, assessed, assessed_names);
  out["max_gap_frames"] = max_gap;
  progress.CheckCancel();

  // 4. Fills.
  const MarkerArray before_fill = markers;
  Take truth;
  json fj = {{"methods", assessed_names}};
  std::vector<FillRecord> records;
  if (!methods.empty()) {
    MarkerArray filled;
    const FillReport fr = FillGaps(markers, fillers, max_gap, &filled, &progress);
    std::map<std::string, int64_t> by_method;
    for (const FillRecord& r : fr.filled) by_method[r.method] += 1;
    json unfilled = json::array();
    for (const auto& [gap, why] : fr.unfilled) {
      json g = GapJson(gap, names);
      g["why"] = why;
      unfilled.push_back(std::move(g));
    }
    fj["filled_gaps"] = fr.filled.size();
    fj["filled_samples"] = fr.filled_samples();
    fj["by_method"] = by_method;
    fj["unfilled_gaps"] = fr.unfilled.size();
    fj["unfilled_samples"] = fr.unfilled_samples();
    fj["unfilled"] = std::move(unfilled);
    json list = json::array();
    for (const FillRecord& r : fr.filled) {
      list.push_back({{"marker", names[static_cast<size_t>(r.marker)]},
                      {"start", r.start},
                      {"length", r.length},
                      {"method", r.method},
                      {"parameters", r.parameters}});
    }
    fj["filled"] = std::move(list);
    if (!fr.filled.empty()) {
      markers = std::move(filled);
      changed = true;
    }
    records = fr.filled;
    if (!options.truth.empty()) {
      const fs::path p = fs::path(options.truth) / (range.take + ".clean.c3d");
      if (fs::exists(p)) {
        truth = ReadC3d(p.string());
        fj["truth"] = p.string();
        fj["errors"] = ScoreFills(records, markers, truth, names, p.string());
      }
    }
  }
  out["fills"] = std::move(fj);
  progress.CheckCancel();
  if (!options.figures.empty())
    out["figures"] = DrawFigures(range.take, before_fill, markers, truth, records, names, rate, options.figures);

  // 5. Filter.
  if (!options.filter.empty()) {
    progress.Update("clean " + range.take + ": " + options.filter + " filter", 0.0);
    json flt = {{"method", options.filter}};
    if (options.filter == "butterworth") {
      ButterworthOptions bo;
      bo.cutoff_hz = options.cutoff_hz;
      bo.order = options.order;
      FilterReport fr;
      ButterworthFilterInPlace(markers, rate, bo, &fr);
      flt["cutoff_hz"] = bo.cutoff_hz;
      flt["order"] = bo.order;
      flt["runs_filtered"] = fr.runs_filtered;
      flt["runs_too_short"] = fr.unfiltered.size();
      flt["min_run_length"] = fr.min_run_length;
    } else {
      KalmanOptions ko;
      ko.model =
          options.kalman_model == "acceleration" ? MotionModel::kConstantAcceleration : MotionModel::kConstantVelocity;
      markers = KalmanSmooth(markers, rate, ko);
      flt["model"] = options.kalman_model;
    }
    changed = true;
    out["filter"] = std::move(flt);
  }

  if (changed && !options.dry_run) {
    Take t = std::move(take);
    t.markers = std::move(markers);
    std::string summary = "cleaned by csw clean from take '" + range.take + "':";
    if (options.fix_swaps) summary += " " + std::to_string(swaps.swaps.size()) + " label swap(s) fixed;";
    if (options.fix_spikes) summary += " " + std::to_string(removed) + " spike sample(s) removed;";
    if (!methods.empty()) summary += " " + std::to_string(records.size()) + " gap(s) filled;";
    if (!options.filter.empty()) summary += " " + options.filter + " filter;";
    t.provenance.warnings.push_back(summary);
    if (!records.empty()) {
      LabelTier tier;
      tier.name = "csw-fills";
      tier.kind = LabelTier::Kind::kPoint;
      tier.start_s = 0;
      tier.end_s = t.duration_s();
      std::vector<FillRecord> sorted = records;
      std::stable_sort(sorted.begin(), sorted.end(),
                       [](const FillRecord& a, const FillRecord& b) { return a.start < b.start; });
      for (const FillRecord& r : sorted) {
        const double at = static_cast<double>(r.start) / rate;
        tier.labels.push_back({at, at, FillTierText(r, names)});
      }
      t.tiers.erase(
          std::remove_if(t.tiers.begin(), t.tiers.end(), [](const LabelTier& x) { return x.name == "csw-fills"; }),
          t.tiers.end());
      t.tiers.push_back(std::move(tier));
    }
    *cleaned = std::move(t);
  }
  return out;
}

}  // namespace

json Clean(const CleanOptions& options, Progress& progress) {
  if (const std::string why = options.Check(); !why.empty()) throw UsageError(why);
  const std::vector<std::string> methods = MethodList(options.fill);
  const Corpus corpus = Corpus::Open(options.corpus);
  const std::vector<TakeRange> ranges = SelectCorpusTakes(corpus, options.takes);
  std::optional<MarkerSet> set;
  if (!options.markerset.empty()) set = LoadMarkerSet(options.markerset);
  if (!options.figures.empty()) figures::Require();  // before any work

  json result = {{"corpus", options.corpus}, {"dry_run", options.dry_run}, {"takes", json::array()}};
  std::vector<Take> cleaned;
  for (size_t i = 0; i < ranges.size(); ++i) {
    std::optional<Take> t;
    json tj = CleanTake(corpus, ranges[i], set, options, methods, progress, &t);
    if (t) cleaned.push_back(std::move(*t));
    result["takes"].push_back(std::move(tj));
  }

  // One transaction for every new take version: all or nothing.
  if (!cleaned.empty()) {
    progress.Update("writing cleaned takes", 0.0);
    CorpusTransaction tx(options.corpus);
    std::set<std::string> existing;
    for (const auto& n : tx.TakeNames()) existing.insert(n);
    size_t k = 0;
    for (json& tj : result["takes"]) {
      for (Take& t : cleaned) {
        if (t.name != tj["take"].get<std::string>()) continue;
        t.name = FilledTakeName(existing, t.name);
        existing.insert(t.name);
        tj["cleaned_take"] = t.name;
        tx.WriteTake(t);
        progress.Update("writing cleaned takes", static_cast<double>(++k) / static_cast<double>(cleaned.size()));
      }
    }
    tx.Commit();
  }

  result["figures"] = json::array();
  for (json& tj : result["takes"]) {
    if (!tj.contains("figures")) continue;
    for (const json& p : tj["figures"]) result["figures"].push_back(p);
    tj.erase("figures");
  }
  return result;
}

std::string CleanText(const json& r) {
  std::ostringstream o;
  o.setf(std::ios::fixed);
  o.precision(1);
  for (const json& t : r["takes"]) {
    const json& g = t["gaps"];
    const double rate = t["rate_hz"].get<double>();
    o << "take " << t["take"].get<std::string>() << ": " << t["frames"].get<int64_t>() << " frames at " << rate
      << " Hz, " << t["markers"].get<int64_t>() << " markers\n";
    o << "  gaps: " << g["count"].get<int64_t>() << " (" << 100.0 * g["fraction_missing"].get<double>()
      << " % of samples missing), longest " << g["longest"].get<int64_t>() << " frames ("
      << g["longest_s"].get<double>() << " s)";
    o << "; by length:";
    for (const json& b : g["by_length"]) o << " " << b["frames"].get<std::string>() << ": " << b["gaps"].get<int64_t>();
    o << "\n  fillable by (max gap " << t["max_gap_frames"].get<int64_t>() << " frames):";
    for (const auto& [m, n] : g["fillable_by"].items()) o << " " << m << " " << n.get<int64_t>();
    o << "; none " << g["fillable_by_none"].get<int64_t>() << "\n";
    const json& s = t["swaps"];
    o << "  label swaps: " << s["detected"].size() << (s["fixed"].get<bool>() ? " (fixed)" : "");
    for (const json& w : s["detected"]) {
      o << "; " << w["a"].get<std::string>() << "<->" << w["b"].get<std::string>() << " frames "
        << w["first_frame"].get<int64_t>() << "-" << w["end_frame"].get<int64_t>();
    }
    o << "\n  spikes: " << t["spikes"]["detected"].size();
    if (t["spikes"]["removed_samples"].get<int64_t>() > 0)
      o << " (" << t["spikes"]["removed_samples"].get<int64_t>() << " samples removed)";
    o << "\n";
    const json& f = t["fills"];
    if (f.contains("filled_gaps")) {
      o << "  filled: " << f["filled_gaps"].get<int64_t>() << " gaps (" << f["filled_samples"].get<int64_t>()
        << " samples):";
      for (const auto& [m, n] : f["by_method"].items()) o << " " << m << " " << n.get<int64_t>();
      o << "; left unfilled: " << f["unfilled_gaps"].get<int64_t>() << " gaps (" << f["unfilled_samples"].get<int64_t>()
        << " samples)\n";
    }
    if (t.contains("filter")) o << "  filter: " << t["filter"]["method"].get<std::string>() << "\n";
    if (t.contains("cleaned_take")) o << "  written as take " << t["cleaned_take"].get<std::string>() << "\n";
  }
  if (r["dry_run"].get<bool>()) o << "dry run: nothing written\n";
  for (const json& p : r["figures"]) o << "figure: " << p.get<std::string>() << "\n";
  return o.str();
}

}  // namespace csw::jobs
