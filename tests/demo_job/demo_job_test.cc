// csw demo (workbench/jobs/demo_job.h): option checks; the page written for a
// hand-made result JSON (every <img src> and <a href> resolves to a file the
// test made, every text is escaped); the whole pipeline end to end on the
// first 6 cued takes of the shipped demo corpus and one sentence, its page's
// links checked and, when `chromium` is on PATH, the page opened in headless
// Chromium with every image loaded; a failing stage names itself and its file.
#include "workbench/jobs/demo_job.h"

#include <gtest/gtest.h>

#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <regex>
#include <sstream>

#include "core/error.h"
#include "tests/testing/testing.h"
#include "workbench/jobs/job_util.h"

namespace csw::jobs {
namespace {

namespace fs = std::filesystem;
using nlohmann::json;

::testing::AssertionResult Holds(const std::string& message, const std::string& part) {
  if (message.find(part) != std::string::npos) return ::testing::AssertionSuccess();
  return ::testing::AssertionFailure() << "'" << message << "' does not hold '" << part << "'";
}

std::string ReadText(const fs::path& p) {
  std::ifstream f(p);
  std::stringstream s;
  s << f.rdbuf();
  return s.str();
}

void Touch(const fs::path& p) {
  fs::create_directories(p.parent_path());
  std::ofstream(p) << "x";
}

std::string Unescape(std::string s) {
  const std::pair<const char*, const char*> entities[] = {
      {"&lt;", "<"}, {"&gt;", ">"}, {"&quot;", "\""}, {"&#39;", "'"}, {"&amp;", "&"}};
  for (const auto& [from, to] : entities)
    for (size_t i = s.find(from); i != std::string::npos; i = s.find(from, i + 1)) s.replace(i, strlen(from), to);
  std::string out;
  for (size_t i = 0; i < s.size(); ++i) {
    if (s[i] == '%' && i + 2 < s.size()) {
      out += static_cast<char>(std::stoi(s.substr(i + 1, 2), nullptr, 16));
      i += 2;
    } else {
      out += s[i];
    }
  }
  return out;
}

// Every src="..." and href="..." of the page (anchors "#..." left out), and
// the ones that do not name an existing file relative to the page.
struct Links {
  std::vector<std::string> all, images, missing;
};
Links PageLinks(const fs::path& page) {
  Links links;
  const std::string html = ReadText(page);
  const std::regex attr(R"re((src|href)="([^"]*)")re");
  for (auto it = std::sregex_iterator(html.begin(), html.end(), attr); it != std::sregex_iterator(); ++it) {
    const std::string value = (*it)[2];
    if (!value.empty() && value[0] == '#') continue;
    links.all.push_back(value);
    if ((*it)[1] == "src" && fs::path(Unescape(value)).extension() == ".png") links.images.push_back(value);
    if (!fs::is_regular_file(page.parent_path() / Unescape(value))) links.missing.push_back(value);
  }
  return links;
}

// Headless Chromium (Debian's `chromium`) on a page: a copy of it next to it
// (relative paths hold) with a script that, once the page has loaded, counts
// the images and lists those that did not load (naturalWidth 0), read back
// from --dump-dom. False when chromium is not on PATH.
bool HaveChromium() { return std::system("command -v chromium > /dev/null 2>&1") == 0; }

struct Loaded {
  int images = -1, broken = -1;
  std::string broken_src, output;
};
Loaded OpenInChromium(const fs::path& page) {
  std::string html = ReadText(page);
  const std::string script =
      "<script>window.addEventListener('load',()=>{const b=[...document.images].filter(i=>!i.complete||"
      "i.naturalWidth===0).map(i=>i.getAttribute('src'));const d=document.body;d.setAttribute('data-images',"
      "document.images.length);d.setAttribute('data-broken',b.length);d.setAttribute('data-broken-src',b.join(' '));"
      "});</script>";
  const size_t end = html.rfind("</body>");
  html.insert(end == std::string::npos ? html.size() : end, script);
  const fs::path check = page.parent_path() / "chromium_check.html";
  std::ofstream(check) << html;
  const fs::path dom = page.parent_path() / "chromium_check.dom";
  const std::string cmd =
      "timeout 120 chromium --headless --disable-gpu --no-sandbox --virtual-time-budget=10000 "
      "--dump-dom 'file://" +
      fs::absolute(check).string() + "' > '" + dom.string() + "' 2> /dev/null";
  Loaded r;
  const int rc = std::system(cmd.c_str());
  r.output = ReadText(dom);
  fs::remove(check);
  fs::remove(dom);
  if (rc != 0) return r;
  std::smatch m;
  if (std::regex_search(r.output, m, std::regex(R"re(data-images="(\d+)")re"))) r.images = std::stoi(m[1]);
  if (std::regex_search(r.output, m, std::regex(R"re(data-broken="(\d+)")re"))) r.broken = std::stoi(m[1]);
  if (std::regex_search(r.output, m, std::regex(R"re(data-broken-src="([^"]*)")re"))) r.broken_src = m[1];
  return r;
}

// A 1 x 1 grey PNG.
const std::string kPng(
    "\x89\x50\x4e\x47\x0d\x0a\x1a\x0a\x00\x00\x00\x0d\x49\x48\x44\x52\x00\x00\x00\x01\x00\x00\x00\x01\x08\x00"
    "\x00\x00\x00\x3a\x7e\x9b\x55\x00\x00\x00\x0a\x49\x44\x41\x54\x78\x9c\x63\x68\x00\x00\x00\x82\x00\x81\x77"
    "\xcd\x72\xb6\x00\x00\x00\x00\x49\x45\x4e\x44\xae\x42\x60\x82",
    67);

TEST(DemoOptions, RequiredOptionsAndReasons) {
  DemoOptions o;
  o.output = "out";
  EXPECT_EQ(o.Check(), "");
  o.output.clear();
  EXPECT_EQ(o.Check(), "no output folder given (-o)");
  o.output = "out";
  o.sentences = -1;
  EXPECT_EQ(o.Check(), "--sentences must be 0 (none) or more");
  o.sentences = 0;
  o.cued_takes = -2;
  EXPECT_EQ(o.Check(), "--takes must be 0 (all) or more");
  o.cued_takes = 0;
  o.cued.clear();
  EXPECT_EQ(o.Check(), "no folder of cued takes given (--cued)");
  o.cued = "sentences";
  o.threads = -1;
  EXPECT_EQ(o.Check(), "--threads must be 0 (hardware threads) or more");
  Progress progress;
  try {
    Demo(o, progress);
    FAIL() << "no error";
  } catch (const UsageError& e) {
    EXPECT_TRUE(Holds(e.what(), "--threads"));
  }
}

TEST(DemoDataDir, FindsTheShippedDemoCorpus) {
  const std::string data = DemoDataDir();
  ASSERT_FALSE(data.empty());
  EXPECT_TRUE(fs::is_directory(fs::path(data) / "demo"));
}

TEST(HtmlEscape, EscapesMarkup) {
  EXPECT_EQ(HtmlEscape("a<b>&\"c'"), "a&lt;b&gt;&amp;&quot;c&#39;");
  EXPECT_EQ(HtmlEscape("élève"), "élève");
}

TEST(DemoHtml, EveryLinkResolvesAndEveryTextIsEscaped) {
  testing::TempDir dir;
  const fs::path out = dir / "out dir";
  const std::string evil = "<script>alert('x')</script> & \"so\"";
  for (const char* f : {"figures/face_variance.png", "figures/a b#c.png", "corpus.h5", "models.h5",
                        "say/001/speech.wav", "say/001/cues.TextGrid", "say/001/markers.c3d", "say/001/pointlight.mp4"})
    Touch(out / f);
  const auto P = [&](const char* f) { return (out / f).string(); };
  json import_stage = {{"name", "import"}, {"title", "Import"}, {"seconds", 1.0}};
  import_stage["result"] = {{"takes", 2}, {"frames", 100}};
  import_stage["result"]["folders"] = json::array({{{"folder", evil}, {"takes", {"t1", "t2"}}, {"frames", 100}}});
  import_stage["figures"] = json::array();
  import_stage["files"] = json::array({{{"label", evil}, {"path", P("corpus.h5")}}});
  json fit_stage = {{"name", "fit"}, {"title", evil}};
  fit_stage["result"]["face"]["face"] = {
      {"parameters", {"a", "b"}}, {"variance_explained", {0.5, 0.25}}, {"training_rms_mm", 0.3}};
  fit_stage["figures"] = {P("figures/face_variance.png"), P("figures/a b#c.png")};
  fit_stage["files"] = json::array({{{"label", "models"}, {"path", P("models.h5")}}});
  json phasing_stage = {{"name", "phasing"}};
  phasing_stage["result"]["kinematic"]["CV"]["shape"]["onset"] = {{"mean_ms", -190.0}, {"sd_ms", 50.0}, {"count", 3}};
  json sentence = {{"text", evil}};
  sentence["files"] = {{"wav", P("say/001/speech.wav")},
                       {"textgrid", P("say/001/cues.TextGrid")},
                       {"c3d", P("say/001/markers.c3d")},
                       {"video", P("say/001/pointlight.mp4")}};
  json say_stage = {{"name", "say"}};
  say_stage["result"]["sentences"] = json::array({sentence});
  say_stage["result"]["check"]["keys"]["accuracy"] = 0.75;
  json result = {{"source", evil}, {"output", out.string()}, {"seconds", 12.5}};
  result["stages"] = json::array({import_stage, fit_stage, phasing_stage, say_stage});
  const std::string page = WriteDemoReport(result, (out / "report").string());
  EXPECT_EQ(page, (out / "report" / "index.html").string());
  ASSERT_TRUE(fs::is_regular_file(out / "report" / "report.json"));
  EXPECT_EQ(json::parse(ReadText(out / "report" / "report.json")), result);
  const Links links = PageLinks(page);
  EXPECT_TRUE(links.missing.empty()) << "missing: " << json(links.missing).dump();
  EXPECT_EQ(links.images.size(), 2u);
  // Figures, model files, the sentence's four files and its video, report.json.
  EXPECT_GE(links.all.size(), 2u * 2 + 2 + 5 + 1);
  for (const std::string& l : links.all) EXPECT_FALSE(fs::path(Unescape(l)).is_absolute()) << l;
  const std::string html = ReadText(page);
  EXPECT_EQ(html.find("<script>"), std::string::npos);
  EXPECT_NE(html.find(HtmlEscape(evil)), std::string::npos);
  EXPECT_NE(html.find("<video"), std::string::npos);
  EXPECT_TRUE(Holds(html, "75.0 %"));
  EXPECT_TRUE(Holds(html, "75.0 %"));  // variance explained by both face parameters
  EXPECT_TRUE(Holds(html, "-190 ± 50 (n = 3)"));
  EXPECT_TRUE(Holds(html, "–"));  // the numbers the result lacks
}

// The check itself: of two images, the missing one is reported.
TEST(DemoChromium, TheCheckSeesABrokenImage) {
  if (!HaveChromium()) GTEST_SKIP() << "chromium is not on PATH (Debian's chromium): the page is not opened";
  testing::TempDir dir;
  std::ofstream(dir / "good.png", std::ios::binary) << kPng;
  std::ofstream(dir / "page.html") << "<!DOCTYPE html><html><body><img src=\"good.png\"><img src=\"missing.png\">"
                                      "</body></html>";
  const Loaded r = OpenInChromium(dir / "page.html");
  EXPECT_EQ(r.images, 2) << r.output;
  EXPECT_EQ(r.broken, 1) << r.output;
  EXPECT_EQ(r.broken_src, "missing.png");
}

TEST(Demo, AFailingStageNamesItselfAndItsFile) {
  testing::TempDir dir;
  fs::create_directories(dir / "empty");
  DemoOptions o;
  o.source = (dir / "empty").string();
  o.output = (dir / "out").string();
  o.sentences = 0;
  Progress progress;
  try {
    Demo(o, progress);
    FAIL() << "no error";
  } catch (const InvalidInput& e) {
    EXPECT_TRUE(Holds(e.what(), "demo: stage import (" + o.source + "): no sub-folder with a markerset.json"));
  }
}

// Cancelling while a stage runs stops the run with Cancelled (not a stage
// error), after the stages before it, whose progress was reported by name.
TEST(Demo, CancelStopsTheRun) {
  testing::TempDir dir;
  DemoOptions o;
  o.output = (dir / "demo").string();
  o.cued_takes = 3;
  o.sentences = 0;
  std::vector<std::string> stages;
  Progress* self = nullptr;
  Progress progress([&](const std::string& stage, double) {
    if (stage.rfind("demo: ", 0) == 0 && (stages.empty() || stages.back() != stage)) stages.push_back(stage);
    if (stage == "demo: fit") self->Cancel();
  });
  self = &progress;
  EXPECT_THROW(Demo(o, progress), Cancelled);
  EXPECT_EQ(stages, (std::vector<std::string>{"demo: import", "demo: fit"}));
  EXPECT_FALSE(fs::exists(dir / "demo" / "report" / "index.html"));
}

// The pipeline on 6 cued takes of the shipped corpus and one sentence, in
// one test (ctest runs each test in its own process): the stages, the page's
// links, then the page in headless Chromium when it is on PATH. About 50 s;
// "Acceptance" in the name leaves it out of the sanitizer stage of
// scripts/test.sh, where it would take many minutes.
TEST(DemoAcceptance, TheWholePipelineAndItsPageInHeadlessChromium) {
  testing::TempDir dir;
  DemoOptions o;
  o.output = (dir / "demo").string();
  o.cued_takes = 6;
  o.sentences = 1;
  Progress progress;
  const json r = Demo(o, progress);
  std::vector<std::string> names;
  for (const json& s : r["stages"]) names.push_back(s["name"]);
  EXPECT_EQ(names, (std::vector<std::string>{"import", "fit", "invert", "keys", "phasing", "dict", "say"}));
  const json& stages = r["stages"];
  EXPECT_EQ(stages[0]["result"]["cued_takes"].size(), 6u);
  EXPECT_GT(stages[0]["result"]["frames"].get<int64_t>(), 0);
  EXPECT_GE(stages[1]["figures"].size(), 4u);                   // variance and parameters of both models
  EXPECT_GE(stages[4]["figures"].size(), 2u);                   // histograms
  EXPECT_EQ(stages[3]["result"]["train"]["takes"].size(), 2u);  // the first third
  ASSERT_EQ(stages[6]["result"]["sentences"].size(), 1u);
  for (const char* f : {"wav", "textgrid", "c3d", "video"})
    EXPECT_TRUE(fs::is_regular_file(stages[6]["result"]["sentences"][0]["files"][f].get<std::string>())) << f;
  EXPECT_TRUE(fs::is_regular_file(stages[6]["result"]["sentences"][0]["frame_png"].get<std::string>()));
  const fs::path page = r["report"].get<std::string>();
  ASSERT_TRUE(fs::is_regular_file(page));
  EXPECT_EQ(json::parse(ReadText(r["report_json"].get<std::string>()))["stages"].size(), 7u);
  const Links links = PageLinks(page);
  EXPECT_TRUE(links.missing.empty()) << "missing: " << json(links.missing).dump();
  EXPECT_GE(links.images.size(), 10u);
  const std::string html = ReadText(page);
  for (const char* heading : {"Import", "Face and hand models", "Key recogniser", "Dictionaries", "<video"})
    EXPECT_TRUE(Holds(html, heading));

  if (!HaveChromium()) GTEST_SKIP() << "chromium is not on PATH (Debian's chromium): the page was not opened";
  const Loaded loaded = OpenInChromium(page);
  EXPECT_GE(loaded.images, 10) << loaded.output.substr(0, 2000);
  EXPECT_EQ(loaded.broken, 0) << "images that did not load: " << loaded.broken_src;
}

}  // namespace
}  // namespace csw::jobs
