#include "workbench/jobs/demo_job.h"

#include <algorithm>
#include <cctype>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <functional>
#include <sstream>

#include "core/build_paths.h"
#include "core/error.h"
#include "workbench/jobs/dict_job.h"
#include "workbench/jobs/figures.h"
#include "workbench/jobs/import_job.h"
#include "workbench/jobs/invert_job.h"
#include "workbench/jobs/job_util.h"
#include "workbench/jobs/keys_job.h"
#include "workbench/jobs/model_jobs.h"
#include "workbench/jobs/phasing_job.h"
#include "workbench/jobs/say_job.h"
#include "workbench/jobs/video_job.h"

#ifndef CSW_DEMO_SOURCE_DIR
#define CSW_DEMO_SOURCE_DIR ""
#endif

namespace csw::jobs {

namespace fs = std::filesystem;
using nlohmann::json;

namespace {

const char* const kStageTitles[][2] = {
    {"import", "Import"},
    {"fit", "Face and hand models"},
    {"invert", "Inversion and gap filling"},
    {"keys", "Key recogniser"},
    {"phasing", "Phasing of hand and lips"},
    {"dict", "Dictionaries"},
    {"say", "Synthesised sentences"},
};

std::string TitleOf(const std::string& name) {
  for (const auto& t : kStageTitles)
    if (name == t[0]) return t[1];
  return name;
}

bool IsCaptureOrLabel(const fs::path& p) {
  const std::string f = FormatOf(p.string());
  return f == "c3d" || f == "trc" || f == "bvh" || f == "textgrid" || f == "eaf" || f == "wav";
}

// The PNG files among a job's "figures" (paths).
void AddFigures(const json& result, json& figures) {
  if (!result.is_object() || !result.contains("figures") || !result["figures"].is_array()) return;
  for (const json& f : result["figures"])
    if (f.is_string() && fs::path(f.get<std::string>()).extension() == ".png") figures.push_back(f);
}

// Runs one stage: its title on the progress, its time, and any csw::Error
// rethrown as the same kind with "demo: stage NAME (FILE): " in front.
json RunStage(const std::string& name, const std::string& file, Progress& progress, const std::function<json()>& body) {
  progress.Update("demo: " + name, 0);
  const auto start = std::chrono::steady_clock::now();
  json stage = {{"name", name}, {"title", TitleOf(name)}};
  const std::string where = "demo: stage " + name + " (" + file + "): ";
  try {
    stage["result"] = body();
  } catch (const Cancelled&) {
    throw;
  } catch (const UsageError& e) {
    throw UsageError(where + e.what());
  } catch (const InvalidInput& e) {
    throw InvalidInput(where + e.what());
  } catch (const Error& e) {
    throw Error(where + e.what());
  }
  stage["seconds"] = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  stage["figures"] = json::array();
  stage["files"] = json::array();
  progress.Update("demo: " + name, 1);
  return stage;
}

json File(const std::string& label, const std::string& path) { return {{"label", label}, {"path", path}}; }

// ---- HTML ----

const json* Find(const json& j, std::initializer_list<const char*> keys) {
  const json* p = &j;
  for (const char* k : keys) {
    if (!p->is_object() || !p->contains(k)) return nullptr;
    p = &(*p)[k];
  }
  return p;
}

std::string Fixed(double v, int digits) {
  char buf[64];
  std::snprintf(buf, sizeof buf, "%.*f", digits, v);
  return buf;
}

// A number at `keys` formatted with `digits` decimals (scaled), "–" when absent.
std::string Num(const json& j, std::initializer_list<const char*> keys, int digits = 2, double scale = 1) {
  const json* p = Find(j, keys);
  if (!p || !p->is_number()) return "–";
  return Fixed(p->get<double>() * scale, digits);
}
std::string Percent(const json& j, std::initializer_list<const char*> keys) {
  const std::string s = Num(j, keys, 1, 100);
  return s == "–" ? s : s + " %";
}
std::string Size(const json& j, std::initializer_list<const char*> keys) {
  const json* p = Find(j, keys);
  if (!p) return "–";
  if (p->is_array() || p->is_object()) return std::to_string(p->size());
  if (p->is_number()) return Fixed(p->get<double>(), 0);
  return "–";
}

std::string Relative(const std::string& path, const fs::path& base) {
  std::error_code ec;
  const fs::path a = fs::absolute(path, ec);
  const fs::path b = fs::absolute(base, ec);
  fs::path r = a.lexically_normal().lexically_relative(b.lexically_normal());
  if (r.empty()) r = a;
  return r.generic_string();
}

// A relative URL: every character outside the unreserved set and '/'
// percent-encoded, then HTML-escaped.
std::string Href(const std::string& path, const fs::path& base) {
  const std::string rel = Relative(path, base);
  std::string out;
  for (const unsigned char c : rel) {
    if (std::isalnum(c) || c == '/' || c == '.' || c == '-' || c == '_' || c == '~') {
      out += static_cast<char>(c);
    } else {
      char buf[4];
      std::snprintf(buf, sizeof buf, "%%%02X", c);
      out += buf;
    }
  }
  return HtmlEscape(out);
}

using Rows = std::vector<std::pair<std::string, std::string>>;

void Table(std::ostringstream& h, const Rows& rows) {
  h << "<table>\n";
  for (const auto& [k, v] : rows) h << "<tr><th>" << HtmlEscape(k) << "</th><td>" << HtmlEscape(v) << "</td></tr>\n";
  h << "</table>\n";
}

void Grid(std::ostringstream& h, const std::vector<std::string>& header,
          const std::vector<std::vector<std::string>>& rows) {
  h << "<table class=\"grid\">\n<tr>";
  for (const std::string& c : header) h << "<th>" << HtmlEscape(c) << "</th>";
  h << "</tr>\n";
  for (const auto& r : rows) {
    h << "<tr>";
    for (const std::string& c : r) h << "<td>" << HtmlEscape(c) << "</td>";
    h << "</tr>\n";
  }
  h << "</table>\n";
}

void ImportNumbers(std::ostringstream& h, const json& r) {
  std::vector<std::vector<std::string>> rows;
  if (const json* folders = Find(r, {"folders"}); folders && folders->is_array())
    for (const json& f : *folders)
      rows.push_back(
          {f.value("folder", std::string("–")), Size(f, {"takes"}), Size(f, {"frames"}), Size(f, {"warnings"})});
  rows.push_back({"total", Size(r, {"takes"}), Size(r, {"frames"}), ""});
  Grid(h, {"folder", "takes", "frames", "warnings"}, rows);
}

void FitNumbers(std::ostringstream& h, const json& r) {
  std::vector<std::vector<std::string>> rows;
  for (const char* kind : {"face", "hand"}) {
    const json* k = Find(r, {kind, kind});
    if (!k) continue;
    // The variance explained by all the parameters (the fractions' sum).
    std::string explained = "–";
    if (const json* v = Find(*k, {"variance_explained"}); v && v->is_array()) {
      double sum = 0;
      for (const json& x : *v)
        if (x.is_number()) sum += x.get<double>();
      explained = Fixed(100 * sum, 1) + " %";
    }
    rows.push_back({kind, Size(*k, {"parameters"}), explained, Size(*k, {"training_frames"}),
                    Num(*k, {"training_rms_mm"}, 3), Size(r, {kind, "training_takes"})});
  }
  Grid(h, {"model", "parameters", "variance explained", "training frames", "training RMS error (mm)", "training takes"},
       rows);
}

void InvertNumbers(std::ostringstream& h, const json& r) {
  std::vector<std::vector<std::string>> rows;
  for (const char* kind : {"face", "hand"}) {
    if (!Find(r, {kind})) continue;
    for (const char* part : {"training", "held_out", "overall"})
      rows.push_back({kind, part, Num(r, {kind, part, "visible", "mean_mm"}, 3),
                      Num(r, {kind, part, "visible", "p99_9_mm"}, 3), Num(r, {kind, part, "visible", "max_mm"}, 3),
                      Num(r, {kind, "target_mm"}, 1)});
  }
  Grid(h, {"model", "frames", "mean error (mm)", "99.9th percentile (mm)", "max (mm)", "target (mm)"}, rows);
  h << "<p>Errors: reconstructed minus observed position of every visible marker; held out = the takes the "
       "models were not fitted on. Filled takes: "
    << HtmlEscape(Size(r, {"filled"})) << ".</p>\n";
}

std::string Ratio(const json& j, std::initializer_list<const char*> num, std::initializer_list<const char*> den) {
  const json* a = Find(j, num);
  const json* b = Find(j, den);
  if (!a || !b || !a->is_number() || !b->is_number() || b->get<double>() == 0) return "–";
  return Fixed(a->get<double>(), 0) + " / " + Fixed(b->get<double>(), 0) + " (" +
         Fixed(100 * a->get<double>() / b->get<double>(), 1) + " %)";
}

void KeysNumbers(std::ostringstream& h, const json& r) {
  const json empty = json::object();
  const json* s = Find(r, {"score"});
  const json& score = s ? *s : empty;
  Table(h,
        {{"training takes", Size(r, {"train", "takes"})},
         {"scored takes", Size(score, {"takes"})},
         {"hand shape accuracy (frames at the targets)", Percent(score, {"shape", "accuracy"})},
         {"placement accuracy (frames at the targets)", Percent(score, {"placement", "accuracy"})},
         {"keys found, free decoding",
          Ratio(score, {"sequence", "free", "keys_correct"}, {"sequence", "free", "keys_expected"})},
         {"keys found, decoding aligned to the labels",
          Ratio(score, {"sequence", "aligned", "keys_correct"}, {"sequence", "aligned", "keys_expected"})},
         {"insertions / substitutions / deletions (free)",
          Size(score, {"sequence", "free", "insertions"}) + " / " + Size(score, {"sequence", "free", "substitutions"}) +
              " / " + Size(score, {"sequence", "free", "deletions"})}});
}

std::string MeanSd(const json& j, std::initializer_list<const char*> keys) {
  const json* p = Find(j, keys);
  if (!p) return "–";
  return Num(*p, {"mean_ms"}, 0) + " ± " + Num(*p, {"sd_ms"}, 0) + " (n = " + Size(*p, {"count"}) + ")";
}

void PhasingNumbers(std::ostringstream& h, const json& r) {
  std::vector<std::vector<std::string>> rows;
  for (const char* type : {"CV", "V", "C"}) {
    const json* k = Find(r, {"kinematic", type});
    if (!k) continue;
    rows.push_back({type, MeanSd(*k, {"placement", "onset"}), MeanSd(*k, {"placement", "target"}),
                    MeanSd(*k, {"shape", "onset"}), MeanSd(*k, {"shape", "target"})});
  }
  Grid(h, {"syllable", "placement onset (ms)", "placement target (ms)", "shape onset (ms)", "shape target (ms)"}, rows);
  h << "<p>Mean ± standard deviation, in ms relative to the acoustic onset of the syllable (A1), from the "
       "hand's kinematics; keys measured: "
    << HtmlEscape(Size(r, {"keys_measured"})) << ".</p>\n";
}

void DictNumbers(std::ostringstream& h, const json& r) {
  Table(h, {{"dikeys (units kept / successions)",
             Size(r, {"dikeys", "kept"}) + " / " + Size(r, {"dikeys", "successions"})},
            {"diphones (units kept / successions)",
             Size(r, {"diphones", "kept"}) + " / " + Size(r, {"diphones", "successions"})},
            {"distinct diphones", Size(r, {"diphones", "distinct"})},
            {"placement successions covered", Size(r, {"coverage", "dictionary", "placement", "present"}) + " of " +
                                                  Size(r, {"coverage", "corpus", "placement", "present"})},
            {"shape successions covered", Size(r, {"coverage", "dictionary", "shape", "present"}) + " of " +
                                              Size(r, {"coverage", "corpus", "shape", "present"})},
            {"key successions missing", Size(r, {"coverage", "missing_dikeys"})},
            {"marker jumps between frames, p99 / max (mm)",
             Num(r, {"continuity", "p99_jump_mm"}) + " / " + Num(r, {"continuity", "max_jump_mm"})}});
}

// A CV landmark of csw say --check's timing: "synthesis / corpus", and the
// difference with its 95 % half-width when both are known.
std::string Timing(const json& r, const std::string& name) {
  const json* t = Find(r, {"check", "timing", "CV"});
  if (!t) return "–";
  auto num = [&](const std::string& key) {
    return t->contains(key) && (*t)[key].is_number() ? Fixed((*t)[key].get<double>(), 0) : std::string("–");
  };
  std::string s = num(name + "_ms") + " / " + num("corpus_" + name + "_ms");
  const std::string d = num(name + "_difference_ms"), ci = num(name + "_difference_ci95_ms");
  if (d != "–" && ci != "–") s += " (difference " + d + " ± " + ci + ", 95 % CI)";
  return s;
}

void SayNumbers(std::ostringstream& h, const json& r, const fs::path& base) {
  Table(h, {{"sentences", Size(r, {"sentences"})},
            {"keys recognised (free decoding)", Percent(r, {"check", "keys", "accuracy"})},
            {"keys recognised at their targets", Percent(r, {"check", "keys", "at_targets", "accuracy"})},
            {"marker jumps p99, synthesis / corpus (mm)", Num(r, {"check", "continuity", "p99_jump_mm"}) + " / " +
                                                              Num(r, {"check", "continuity", "corpus_p99_jump_mm"})},
            {"marker jumps max, synthesis / corpus (mm)", Num(r, {"check", "continuity", "max_jump_mm"}) + " / " +
                                                              Num(r, {"check", "continuity", "corpus_max_jump_mm"})},
            {"CV placement target, synthesis / corpus (ms)", Timing(r, "placement_target")},
            {"CV shape target, synthesis / corpus (ms)", Timing(r, "shape_target")},
            {"CV placement onset, synthesis / corpus (ms)", Timing(r, "placement_onset")},
            {"CV shape onset, synthesis / corpus (ms)", Timing(r, "shape_onset")}});
  const json* sentences = Find(r, {"sentences"});
  if (!sentences || !sentences->is_array()) return;
  int n = 0;
  for (const json& s : *sentences) {
    ++n;
    h << "<div class=\"sentence\">\n<h3>" << n << ". " << HtmlEscape(s.value("text", std::string())) << "</h3>\n";
    Table(h, {{"duration (s)", Num(s, {"duration_s"})},
              {"keys", Size(s, {"keys"})},
              {"keys recognised", Percent(s, {"check", "accuracy"})}});
    const json* files = Find(s, {"files"});
    if (files && files->is_object()) {
      h << "<p class=\"files\">";
      for (const auto& [label, path] :
           {std::pair{"wav", "speech (WAV)"}, std::pair{"textgrid", "labels (TextGrid)"},
            std::pair{"c3d", "markers (C3D)"}, std::pair{"video", "point-light video (MP4)"}})
        if (files->contains(label) && (*files)[label].is_string() && !(*files)[label].get<std::string>().empty())
          h << "<a href=\"" << Href((*files)[label].get<std::string>(), base) << "\">" << HtmlEscape(path) << "</a> ";
      h << "</p>\n";
      if (files->contains("video") && (*files)["video"].is_string() && !(*files)["video"].get<std::string>().empty()) {
        h << "<div class=\"figures\">";
        if (s.contains("frame_png") && s["frame_png"].is_string())
          h << "<img src=\"" << Href(s["frame_png"].get<std::string>(), base)
            << "\" alt=\"a frame of the point-light video\" width=\"320\">";
        h << "<video controls preload=\"metadata\" width=\"320\" src=\""
          << Href((*files)["video"].get<std::string>(), base) << "\"></video></div>\n";
      } else if (files->contains("wav") && (*files)["wav"].is_string())
        h << "<audio controls src=\"" << Href((*files)["wav"].get<std::string>(), base) << "\"></audio>\n";
    }
    if (const json* w = Find(s, {"warnings"}); w && w->is_array() && !w->empty()) {
      h << "<ul class=\"warnings\">\n";
      for (const json& x : *w)
        if (x.is_string()) h << "<li>" << HtmlEscape(x.get<std::string>()) << "</li>\n";
      h << "</ul>\n";
    }
    h << "</div>\n";
  }
}

constexpr const char* kCss = R"(body{font-family:sans-serif;max-width:1100px;margin:2em auto;padding:0 1em;color:#222}
h1{border-bottom:2px solid #446}h2{margin-top:2em;border-bottom:1px solid #aab}
table{border-collapse:collapse;margin:.5em 0}th,td{border:1px solid #ccd;padding:.25em .6em;text-align:left}
th{background:#eef}table.grid td{text-align:right}table.grid td:first-child{text-align:left}
.figures{display:flex;flex-wrap:wrap;gap:.5em}.figures img{max-width:520px;border:1px solid #ddd}
.files a{margin-right:1em}.meta{color:#666;font-size:90%}.warnings{color:#a40}.sentence{margin:1em 0;padding:.5em 1em;background:#f7f7fb}
)";

}  // namespace

std::string HtmlEscape(const std::string& text) {
  std::string out;
  out.reserve(text.size());
  for (const char c : text) {
    switch (c) {
      case '&':
        out += "&amp;";
        break;
      case '<':
        out += "&lt;";
        break;
      case '>':
        out += "&gt;";
        break;
      case '"':
        out += "&quot;";
        break;
      case '\'':
        out += "&#39;";
        break;
      default:
        out += c;
    }
  }
  return out;
}

std::string DemoDataDir() {
  std::vector<fs::path> candidates;
  if (const char* env = std::getenv("CSW_SOURCE_DIR"); env && *env) candidates.push_back(fs::path(env) / "datasets");
  if (*CSW_DEMO_SOURCE_DIR) candidates.push_back(fs::path(CSW_DEMO_SOURCE_DIR) / "datasets");
  candidates.push_back(fs::current_path() / "datasets");
  std::error_code ec;
  for (const fs::path& c : candidates)
    if (fs::is_directory(c, ec)) return c.string();
  return "";
}

std::string DemoOptions::Check() const {
  if (output.empty()) return "no output folder given (-o)";
  if (cued.empty()) return "no folder of cued takes given (--cued)";
  if (cued_takes < 0) return "--takes must be 0 (all) or more";
  if (sentences < 0) return "--sentences must be 0 (none) or more";
  if (threads < 0) return "--threads must be 0 (hardware threads) or more";
  if (source.empty() && DemoDataDir().empty())
    return "the demo corpus was not found (no datasets folder in $CSW_SOURCE_DIR, the source tree or here): give "
           "--source";
  return "";
}

json Demo(const DemoOptions& options, Progress& progress) {
  if (const std::string why = options.Check(); !why.empty()) throw UsageError(why);
  const auto start = std::chrono::steady_clock::now();
  const std::string data = DemoDataDir();
  const fs::path source = options.source.empty() ? fs::path(data) / "demo" : fs::path(options.source);
  if (!fs::is_directory(source)) throw UsageError(source.string() + ": the demo corpus folder does not exist");
  std::string config = options.config;
  if (config.empty() && !data.empty() && fs::is_regular_file(fs::path(data) / "configs/virtual-cuer.json"))
    config = (fs::path(data) / "configs/virtual-cuer.json").string();
  std::string sentences_file = options.sentences_file;
  if (sentences_file.empty() && options.sentences > 0) {
    if (data.empty()) throw UsageError("no sentence file given (--sentences-file) and no datasets folder found");
    sentences_file = (fs::path(data) / "unseen_sentences_fr.txt").string();
  }

  const fs::path out = options.output;
  fs::create_directories(out);
  const fs::path figures_path = out / "figures";
  fs::create_directories(figures_path);
  const std::string corpus = (out / "corpus.h5").string();
  const std::string models = (out / "models.h5").string();
  const std::string keys = (out / "keys.h5").string();
  const std::string dictionary = (out / "dict.h5").string();
  const std::string phasing_json = (out / "phasing.json").string();
  for (const std::string& f : {corpus, models, keys, dictionary}) fs::remove(f);
  fs::remove_all(corpus + ".d");

  json result = {{"source", source.string()}, {"output", out.string()}, {"corpus", corpus}, {"stages", json::array()}};
  json& stages = result["stages"];
  result["warnings"] = json::array();
  // Without the figures module (a build without Qt) the stages run without figures.
  std::string figures_dir = figures_path.string();
  try {
    figures::Require();
  } catch (const InvalidInput& e) {
    figures_dir.clear();
    result["warnings"].push_back(std::string("no figures: ") + e.what());
  }

  // import: every sub-folder with a marker set, in name order.
  std::vector<std::string> cued;
  {
    json stage = RunStage("import", source.string(), progress, [&] {
      std::vector<fs::path> folders;
      for (const auto& e : fs::directory_iterator(source))
        if (e.is_directory() && fs::is_regular_file(e.path() / "markerset.json")) folders.push_back(e.path());
      std::sort(folders.begin(), folders.end());
      if (folders.empty()) throw InvalidInput("no sub-folder with a markerset.json");
      if (std::find(folders.begin(), folders.end(), source / options.cued) == folders.end())
        throw InvalidInput("no sub-folder '" + options.cued + "' with a markerset.json (the cued takes)");
      json r = {{"folders", json::array()}, {"takes", 0}, {"frames", 0}};
      for (const fs::path& folder : folders) {
        ImportOptions io;
        for (const auto& e : fs::directory_iterator(folder))
          if (e.is_regular_file() && IsCaptureOrLabel(e.path())) io.files.push_back(e.path().string());
        std::sort(io.files.begin(), io.files.end());
        io.corpus = corpus;
        io.markerset = (folder / "markerset.json").string();
        const ImportResult imported = Import(io, progress);
        json j = ImportReportJson(io, imported);
        j["folder"] = folder.filename().string();
        r["folders"].push_back(j);
        r["takes"] = r["takes"].get<int64_t>() + static_cast<int64_t>(imported.takes.size());
        r["frames"] = r["frames"].get<int64_t>() + imported.frames;
        if (folder.filename() == options.cued) cued = imported.takes;
      }
      if (options.cued_takes > 0 && static_cast<int>(cued.size()) > options.cued_takes) cued.resize(options.cued_takes);
      if (cued.size() < 2) throw InvalidInput("fewer than 2 cued takes in '" + options.cued + "'");
      r["cued_takes"] = cued;
      return r;
    });
    stage["files"].push_back(File("corpus (HDF5; open it in csw-workbench)", corpus));
    stages.push_back(stage);
  }
  // The first third (at least one take) trains, every cued take is scored.
  const size_t n_train = std::max<size_t>(1, cued.size() / 3);
  const std::vector<std::string> train(cued.begin(), cued.begin() + static_cast<std::ptrdiff_t>(n_train));
  std::vector<std::string> filled, train_filled;
  for (const std::string& t : cued) filled.push_back(t + ".filled");
  for (const std::string& t : train) train_filled.push_back(t + ".filled");

  {
    json stage = RunStage("fit", corpus, progress, [&] {
      json r;
      for (const char* kind : {"face", "hand"}) {
        FitOptions fo;
        fo.corpus = corpus;
        fo.kind = kind;
        fo.takes = train;
        fo.config = config;
        fo.output = models;
        fo.figures = figures_dir;
        r[kind] = Fit(fo, progress);
      }
      return r;
    });
    AddFigures(stage["result"]["face"], stage["figures"]);
    AddFigures(stage["result"]["hand"], stage["figures"]);
    stage["files"].push_back(File("models (HDF5)", models));
    stages.push_back(stage);
  }
  {
    json stage = RunStage("invert", models, progress, [&] {
      InvertOptions io;
      io.corpus = corpus;
      io.models = models;
      io.takes = cued;
      io.fill = true;
      io.figures = figures_dir;
      io.threads = options.threads;
      return Invert(io, progress);
    });
    AddFigures(stage["result"], stage["figures"]);
    stages.push_back(stage);
  }
  {
    json stage = RunStage("keys", corpus, progress, [&] {
      KeysTrainOptions kt;
      kt.corpus = corpus;
      kt.takes = train_filled;
      kt.output = keys;
      json r;
      r["train"] = KeysTrain(kt, progress);
      KeysScoreOptions ks;
      ks.corpus = corpus;
      ks.keys = keys;
      ks.takes = filled;
      ks.figures = figures_dir;
      r["score"] = KeysScore(ks, progress);
      return r;
    });
    AddFigures(stage["result"]["score"], stage["figures"]);
    stage["files"].push_back(File("key recogniser (HDF5)", keys));
    stages.push_back(stage);
  }
  {
    json stage = RunStage("phasing", keys, progress, [&] {
      PhasingOptions po;
      po.corpus = corpus;
      po.keys = keys;
      po.takes = filled;
      po.figures = figures_dir;
      json r = Phasing(po, progress);
      std::ofstream f(phasing_json);
      f << r.dump(1) << "\n";
      if (!f) throw IoError(phasing_json, "cannot be written");
      return r;
    });
    AddFigures(stage["result"], stage["figures"]);
    stage["files"].push_back(File("phasing (JSON)", phasing_json));
    stages.push_back(stage);
  }
  {
    json stage = RunStage("dict", corpus, progress, [&] {
      DictBuildOptions db;
      db.corpus = corpus;
      db.models = models;
      db.keys = keys;
      db.output = dictionary;
      db.takes = filled;
      db.tier = "keys";
      db.threads = options.threads;
      return DictBuild(db, progress);
    });
    stage["files"].push_back(File("dictionary (HDF5)", dictionary));
    stages.push_back(stage);
  }
  if (options.sentences > 0) {
    json stage = RunStage("say", sentences_file, progress, [&] {
      std::vector<std::string> texts = ReadSentences(sentences_file);
      if (static_cast<int>(texts.size()) > options.sentences) texts.resize(options.sentences);
      SayOptions so;
      so.texts = texts;
      so.dict = dictionary;
      so.models = models;
      so.output = (out / "say").string();
      so.video = options.video;
      so.check = true;
      so.keys = keys;
      so.corpus_phasing = phasing_json;
      json r = Say(so, progress);
      // One frame of each video as a PNG, shown next to it (a still for the
      // page, and for machines whose OpenCV has no H.264 encoder: browsers do
      // not play its MPEG-4 Part 2 fallback).
      if (options.video && r.contains("sentences"))
        for (json& sentence : r["sentences"]) {
          const json* video = Find(sentence, {"files", "video"});
          const json* c3d = Find(sentence, {"files", "c3d"});
          if (!video || !c3d || !video->is_string() || !c3d->is_string()) continue;
          const fs::path folder = fs::path(video->get<std::string>()).parent_path();
          VideoOptions vo;
          vo.input = c3d->get<std::string>();
          vo.output = (folder / "frame_video.mp4").string();
          if (fs::is_regular_file(folder / "markerset.json")) vo.markerset = (folder / "markerset.json").string();
          vo.png = (folder / "frame.png").string();
          vo.png_time_s = sentence.value("duration_s", 0.0) / 2;
          Video(vo, progress);
          fs::remove(vo.output);
          sentence["frame_png"] = vo.png;
        }
      return r;
    });
    if (stage["result"].contains("corpus") && stage["result"]["corpus"].is_string())
      stage["files"].push_back(
          File("corpus of the synthesised takes (HDF5)", stage["result"]["corpus"].get<std::string>()));
    stages.push_back(stage);
  }
  const fs::path report_dir = out / "report";
  result["report"] = (report_dir / "index.html").string();
  result["report_json"] = (report_dir / "report.json").string();
  result["seconds"] = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  WriteDemoReport(result, report_dir.string());
  return result;
}

std::string DemoHtml(const json& result, const std::string& report_dir) {
  const fs::path base = report_dir;
  std::ostringstream h;
  h << "<!DOCTYPE html>\n<html lang=\"en\">\n<head>\n<meta charset=\"utf-8\">\n"
       "<title>Cued Speech Workbench: the demo</title>\n<style>\n"
    << kCss << "</style>\n</head>\n<body>\n<h1>Cued Speech Workbench: the demo pipeline</h1>\n";
  h << "<p>The whole pipeline of <code>csw demo</code> on the demo corpus <code>"
    << HtmlEscape(result.value("source", std::string())) << "</code>: import, model fitting, inversion and gap "
    << "filling, the key recogniser, phasing, the synthesis dictionaries and new sentences synthesised. Every "
    << "stage lists its numbers, its figures and its files; the full results are in <a href=\""
    << Href((base / "report.json").string(), base) << "\">report.json</a>.</p>\n";
  if (const json* warnings = Find(result, {"warnings"}); warnings && warnings->is_array() && !warnings->empty()) {
    h << "<ul class=\"warnings\">\n";
    for (const json& w : *warnings)
      if (w.is_string()) h << "<li>" << HtmlEscape(w.get<std::string>()) << "</li>\n";
    h << "</ul>\n";
  }
  const json* stages = Find(result, {"stages"});
  if (stages && stages->is_array()) {
    h << "<ul>\n";
    for (const json& s : *stages)
      h << "<li><a href=\"#" << HtmlEscape(s.value("name", std::string())) << "\">"
        << HtmlEscape(s.value("title", s.value("name", std::string()))) << "</a></li>\n";
    h << "</ul>\n";
    for (const json& s : *stages) {
      const std::string name = s.value("name", std::string());
      h << "<h2 id=\"" << HtmlEscape(name) << "\">" << HtmlEscape(s.value("title", name)) << "</h2>\n";
      h << "<p class=\"meta\">stage <code>" << HtmlEscape(name) << "</code>, " << HtmlEscape(Num(s, {"seconds"}, 1))
        << " s</p>\n";
      const json empty = json::object();
      const json& r = s.contains("result") ? s["result"] : empty;
      if (name == "import") ImportNumbers(h, r);
      if (name == "fit") FitNumbers(h, r);
      if (name == "invert") InvertNumbers(h, r);
      if (name == "keys") KeysNumbers(h, r);
      if (name == "phasing") PhasingNumbers(h, r);
      if (name == "dict") DictNumbers(h, r);
      if (name == "say") SayNumbers(h, r, base);
      if (const json* figs = Find(s, {"figures"}); figs && figs->is_array() && !figs->empty()) {
        h << "<div class=\"figures\">\n";
        for (const json& f : *figs) {
          if (!f.is_string()) continue;
          const std::string path = f.get<std::string>();
          const std::string href = Href(path, base);
          h << "<a href=\"" << href << "\"><img src=\"" << href << "\" alt=\""
            << HtmlEscape(fs::path(path).filename().string()) << "\"></a>\n";
        }
        h << "</div>\n";
      }
      if (const json* files = Find(s, {"files"}); files && files->is_array() && !files->empty()) {
        h << "<p class=\"files\">Files: ";
        for (const json& f : *files)
          if (f.is_object() && f.contains("path") && f["path"].is_string())
            h << "<a href=\"" << Href(f["path"].get<std::string>(), base) << "\">"
              << HtmlEscape(f.value("label", f["path"].get<std::string>())) << "</a> ";
        h << "</p>\n";
      }
    }
  }
  h << "<p class=\"meta\">Total " << HtmlEscape(Num(result, {"seconds"}, 1)) << " s. Output folder <code>"
    << HtmlEscape(result.value("output", std::string())) << "</code>.</p>\n</body>\n</html>\n";
  return h.str();
}

std::string WriteDemoReport(const json& result, const std::string& report_dir) {
  fs::create_directories(report_dir);
  const std::string page = (fs::path(report_dir) / "index.html").string();
  const std::string report = (fs::path(report_dir) / "report.json").string();
  {
    std::ofstream f(report);
    f << result.dump(1) << "\n";
    if (!f) throw IoError(report, "cannot be written");
  }
  std::ofstream f(page);
  f << DemoHtml(result, report_dir);
  if (!f) throw IoError(page, "cannot be written");
  return page;
}

std::string DemoText(const json& result) {
  std::ostringstream o;
  if (const json* stages = Find(result, {"stages"}); stages && stages->is_array())
    for (const json& s : *stages) o << s.value("name", std::string()) << ": " << Num(s, {"seconds"}, 1) << " s\n";
  o << "total: " << Num(result, {"seconds"}, 1) << " s\n";
  o << "report: " << result.value("report", std::string()) << "\n";
  return o.str();
}

}  // namespace csw::jobs
