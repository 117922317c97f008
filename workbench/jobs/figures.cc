#include "workbench/jobs/figures.h"

#include <dlfcn.h>

#include <cstdlib>
#include <filesystem>
#include <mutex>

#include "core/build_paths.h"
#include "core/error.h"
#include "workbench/report/figures_api.h"

namespace csw::jobs::figures {

namespace fs = std::filesystem;

namespace {

constexpr const char* kModuleName = "libcsw_figures.so";

#ifdef CSW_HAVE_FIGURES_MODULE
std::vector<std::string> Candidates() {
  std::vector<std::string> out;
  if (const char* env = std::getenv("CSW_FIGURES_MODULE"); env && *env) return {env};  // the only place then
  std::error_code ec;
  const fs::path exe = fs::read_symlink("/proc/self/exe", ec);
  if (!ec) {
    out.push_back((exe.parent_path() / kModuleName).string());
    out.push_back((exe.parent_path().parent_path() / "lib" / "csw" / kModuleName).string());
  }
#ifdef CSW_FIGURES_MODULE_PATH
  out.push_back(CSW_FIGURES_MODULE_PATH);
#endif
  return out;
}
#endif

const report::FiguresApi* LoadApi() {
#ifndef CSW_HAVE_FIGURES_MODULE
  throw InvalidInput("--figures: this csw was built without figures (CSW_BUILD_GUI=OFF: no Qt, no " +
                     std::string(kModuleName) + ")");
#else
  std::string tried;
  for (const std::string& path : Candidates()) {
    std::error_code ec;
    if (!fs::exists(path, ec)) {
      tried += "\n  " + path + ": no such file";
      continue;
    }
    void* handle = dlopen(path.c_str(), RTLD_NOW | RTLD_LOCAL);  // never closed: Qt does not unload cleanly
    if (!handle) {
      const char* why = dlerror();
      tried += "\n  " + path + ": " + (why ? why : "cannot load");
      continue;
    }
    using Entry = const report::FiguresApi* (*)();
    auto entry = reinterpret_cast<Entry>(dlsym(handle, CSW_FIGURES_ENTRY_POINT));
    const report::FiguresApi* api = entry ? entry() : nullptr;
    if (!api || api->version != report::kFiguresApiVersion) {
      tried += "\n  " + path + ": not a csw figures module of this version";
      continue;
    }
    return api;
  }
  throw InvalidInput("--figures: cannot load the figures module " + std::string(kModuleName) +
                     " (set CSW_FIGURES_MODULE to its path); tried:" + tried);
#endif
}

const report::FiguresApi& Api() {
  static std::mutex mutex;
  static const report::FiguresApi* api = nullptr;
  std::lock_guard<std::mutex> lock(mutex);
  if (!api) api = LoadApi();
  return *api;
}

// The module's messages already name the file.
void Check(const std::string& error) {
  if (!error.empty()) throw InvalidInput(error);
}

}  // namespace

void Require() { (void)Api(); }

void SaveErrorBars(const std::string& path, const std::string& title, const std::vector<report::ErrorBar>& bars,
                   double target_mm) {
  Check(Api().save_error_bars(path, title, bars, target_mm));
}

void SaveVarianceExplained(const std::string& path, const std::string& title, const std::vector<std::string>& names,
                           const std::vector<double>& fractions) {
  Check(Api().save_variance_explained(path, title, names, fractions));
}

void SaveParameterEffects(const std::string& path, const std::string& title, const Eigen::Matrix3Xd& neutral,
                          const std::vector<report::ParameterEffect>& effects,
                          const std::vector<std::pair<int, int>>& sticks) {
  Check(Api().save_parameter_effects(path, title, neutral, effects, sticks));
}

void SaveGapMap(const std::string& path, const std::string& title, const std::vector<std::string>& names,
                const std::vector<std::vector<std::pair<int64_t, int64_t>>>& gaps, int64_t frames, double rate_hz) {
  Check(Api().save_gap_map(path, title, names, gaps, frames, rate_hz));
}

void SaveGapFill(const std::string& path, const std::string& title, const std::vector<double>& time_s,
                 const Eigen::Matrix3Xd& measured, const Eigen::Matrix3Xd& truth,
                 const std::vector<report::FillSeries>& fills, double gap_start_s, double gap_end_s) {
  Check(Api().save_gap_fill(path, title, time_s, measured, truth, fills, gap_start_s, gap_end_s));
}

void SaveGesturalScore(const std::string& path, const std::string& title, const std::vector<float>& audio,
                       double audio_rate_hz, double audio_start_s, const std::vector<report::PosteriorLane>& lanes,
                       double frame_rate_hz, const std::vector<LabelTier>& tiers, double start_s, double end_s) {
  Check(Api().save_gestural_score(path, title, audio, audio_rate_hz, audio_start_s, lanes, frame_rate_hz, tiers,
                                  start_s, end_s));
}

void SaveHistograms(const std::string& path, const std::string& title,
                    const std::vector<report::HistogramPanel>& panels, double bin_ms, const std::string& x_label) {
  Check(Api().save_histograms(path, title, panels, bin_ms, x_label));
}

void SaveConfusionMatrix(const std::string& path, const std::string& title, const std::vector<std::string>& labels,
                         const std::vector<std::vector<int>>& counts, const std::string& true_axis,
                         const std::string& recognised_axis) {
  Check(Api().save_confusion_matrix(path, title, labels, counts, true_axis, recognised_axis));
}

void SavePlots(const std::string& path, const std::string& title, const std::vector<report::PlotPanel>& panels,
               int columns) {
  Check(Api().save_plots(path, title, panels, columns));
}

}  // namespace csw::jobs::figures
