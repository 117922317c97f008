#pragma once
// `csw demo -o DIR` (issue 15 item 7): the whole cued-speech pipeline on the
// demo corpus, in-process, then one HTML page a newcomer opens in a browser.
// Stages, each one a job of this folder with its JSON kept:
//   import   every sub-folder of the source holding a markerset.json
//            (captures, labels and audio) into DIR/corpus.h5 (replaced);
//   fit      face and hand models on the first third of the cued takes (the
//            takes of the `cued` sub-folder) into DIR/models.h5;
//   invert   both models on every cued take, gaps filled as "<take>.filled";
//   keys     the key recogniser trained on the labelled targets (the key tier)
//            of the filled training takes (DIR/keys.h5), scored on every
//            filled take;
//   phasing  gesture timing relative to the acoustic syllable (DIR/phasing.json);
//   dict     the dikey and diphone dictionaries (DIR/dict.h5, labelled keys);
//   say      a few new sentences synthesised (DIR/say/001, ...: speech.wav,
//            cues.TextGrid, markers.c3d, pointlight.mp4) and checked with the
//            recogniser, continuity and timing against the corpus's.
// Figures in DIR/figures. Writes DIR/report/index.html (plain HTML and CSS:
// per stage its numbers, figures and files, by relative paths) and
// DIR/report/report.json (the result below). A failing stage throws the
// error's type with "demo: stage <name> (<file>): <message>".
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "core/progress.h"

namespace csw::jobs {

struct DemoOptions {
  std::string source;              // demo corpus folder; "" = DemoDataDir()/demo
  std::string output;              // output folder (created); required
  std::string cued = "sentences";  // the source's sub-folder of cued takes (with a key tier)
  int cued_takes = 0;              // use the first N cued takes (0 = all)
  std::string config;  // model configuration for csw fit; "" = DemoDataDir()/configs/virtual-cuer.json when there
  std::string sentences_file;  // sentences to synthesise; "" = DemoDataDir()/unseen_sentences_fr.txt
  int sentences = 3;           // the first N of them (0 = no say stage)
  bool video = true;           // pointlight.mp4 per synthesised sentence
  int threads = 0;             // inversion threads (0 = hardware threads)
  std::string Check() const;   // "" or the reason
};

// The project's datasets folder: $CSW_SOURCE_DIR/datasets, else the source
// tree the program was built from, else ./datasets; "" when none exists.
std::string DemoDataDir();

// {"source", "output", "corpus", "seconds",
//  "stages": [{"name", "title", "seconds", "result": <the job's JSON>,
//              "figures": [PNG paths], "files": [{"label", "path"}]}],
//  "report": "DIR/report/index.html", "report_json": "DIR/report/report.json"}.
// Stage names: import, fit, invert, keys, phasing, dict, say; the result of
// import is {"folders": [{"folder", <ImportReportJson>}], "takes", "frames"},
// of fit {"face", "hand"}, of keys {"train", "score"}.
nlohmann::json Demo(const DemoOptions& options, Progress& progress);
std::string DemoText(const nlohmann::json& result);

// The page for a result (the JSON above; any missing number shows as "–"),
// with every path relative to `report_dir`. Every text is HTML-escaped.
std::string DemoHtml(const nlohmann::json& result, const std::string& report_dir);
// Writes report_dir/index.html and report_dir/report.json; returns the page's path.
std::string WriteDemoReport(const nlohmann::json& result, const std::string& report_dir);
std::string HtmlEscape(const std::string& text);

}  // namespace csw::jobs
