// Gestural score, phasing and confusion views and File > Export (issue 16,
// items 4 and 6), driven through the real widgets offscreen. The corpus: three
// virtual-cuer sentences whose key recogniser is trained and scored here with
// the same jobs as `csw keys train` / `csw keys score`, so each take stores a
// gestural score ("keys": shape and placement posteriors) and the decoded and
// aligned key tiers. The checks compare what the widgets plot or write with
// what the corpus and the jobs hold: the stored posteriors at given frames,
// label files read back with the io readers, figure files by their magic
// bytes, histogram and confusion totals with the jobs' JSON counts.
#include <gtest/gtest.h>
#include <qcustomplot.h>

#include <QApplication>
#include <QDockWidget>
#include <QMessageBox>
#include <QSignalSpy>
#include <QTest>
#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <memory>
#include <string>
#include <vector>

#include "core/progress.h"
#include "datasets/virtual_cuer.h"
#include "io/corpus/corpus.h"
#include "io/dictionary/dictionary_file.h"
#include "io/formats/eaf.h"
#include "io/formats/textgrid.h"
#include "tests/gui/take_wait.h"
#include "tests/testing/testing.h"
#include "workbench/gui/demo_take.h"
#include "workbench/gui/export_files.h"
#include "workbench/gui/label_session.h"
#include "workbench/gui/main_window.h"
#include "workbench/gui/phasing_view.h"
#include "workbench/gui/playback.h"
#include "workbench/gui/score_lanes.h"
#include "workbench/gui/timeseries_panel.h"
#include "workbench/jobs/keys_job.h"
#include "workbench/jobs/phasing_job.h"

namespace csw::gui {
namespace {

namespace fs = std::filesystem;

std::string FileBytes(const fs::path& path) {
  std::ifstream in(path, std::ios::binary);
  return std::string(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
}

// A figure file of the format its extension names: non-empty, right magic.
void ExpectFigure(const fs::path& path) {
  ASSERT_TRUE(fs::exists(path)) << path;
  const std::string bytes = FileBytes(path);
  ASSERT_GT(bytes.size(), 200u) << path;
  const std::string ext = path.extension().string();
  if (ext == ".png") {
    EXPECT_EQ(bytes.substr(0, 8), std::string("\x89PNG\r\n\x1a\n", 8)) << path;
  } else if (ext == ".pdf") {
    EXPECT_EQ(bytes.substr(0, 5), "%PDF-") << path;
    EXPECT_NE(bytes.find("%%EOF"), std::string::npos) << path;
  } else if (ext == ".svg") {
    EXPECT_NE(bytes.substr(0, 400).find("<svg"), std::string::npos) << path;
    EXPECT_NE(bytes.find("</svg>"), std::string::npos) << path;
  } else {
    ADD_FAILURE() << "unexpected extension " << path;
  }
}

const LabelTier* Find(const std::vector<LabelTier>& tiers, const std::string& name) {
  for (const LabelTier& t : tiers)
    if (t.name == name) return &t;
  return nullptr;
}

std::vector<Label> NonEmpty(const LabelTier& t) {
  std::vector<Label> out;
  for (const Label& l : t.labels)
    if (!l.text.empty()) out.push_back(l);
  return out;
}

class ViewsTest : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    dir_ = new testing::TempDir();
    corpus_ = (*dir_ / "corpus.h5").string();
    keys_ = (*dir_ / "keys.h5").string();
    SimulateOptions s;
    s.seed = 7;
    s.audio = false;
    s.write_truth = false;
    const VirtualCuer cuer(s);
    const std::string set = MarkerSetToJson(DemoMarkerSet());
    const std::vector<std::string> sentences = ShippedSentences();
    ASSERT_GE(sentences.size(), 3u);
    {
      CorpusTransaction tx(corpus_);
      for (int i = 0; i < 3; ++i) {
        Take t = cuer.SimulateSentence("sentence_" + std::to_string(i + 1), sentences[static_cast<size_t>(i)]).take;
        t.markerset_json = set;
        tx.WriteTake(t);
      }
      tx.Commit();
    }
    Progress quiet;
    jobs::KeysTrainOptions train;
    train.corpus = corpus_;
    train.takes = {"sentence_1", "sentence_2", "sentence_3"};
    train.output = keys_;
    jobs::KeysTrain(train, quiet);
    jobs::KeysScoreOptions score;
    score.corpus = corpus_;
    score.keys = keys_;
    jobs::KeysScore(score, quiet);
  }
  static void TearDownTestSuite() {
    delete dir_;
    dir_ = nullptr;
  }

  std::unique_ptr<MainWindow> OpenWindow() {
    auto w = std::make_unique<MainWindow>(QString::fromStdString((*dir_ / "settings.ini").string()));
    w->playback()->SetAudioEnabled(false);
    w->resize(1400, 900);
    w->show();
    EXPECT_TRUE(QTest::qWaitForWindowExposed(w.get()));
    EXPECT_TRUE(OpenAndWait(w.get(), corpus_));
    return w;
  }

  static testing::TempDir* dir_;
  static std::string corpus_;
  static std::string keys_;
};

testing::TempDir* ViewsTest::dir_ = nullptr;
std::string ViewsTest::corpus_;
std::string ViewsTest::keys_;

// The lanes plot the take's stored posteriors, row for row, on the take's
// time; the key tiers are the stored keys_decoded and keys_aligned; the
// cursor follows playback; each lane exports as PNG, SVG and PDF.
TEST_F(ViewsTest, ScoreLanesShowTheStoredPosteriors) {
  auto w = OpenWindow();
  ASSERT_TRUE(SelectAndWait(w.get(), "sentence_2"));
  const Corpus corpus = Corpus::Open(corpus_);
  const std::optional<TakeScores> stored = corpus.LoadScores("sentence_2", "keys");
  ASSERT_TRUE(stored.has_value());
  const Take take = corpus.LoadTake("sentence_2");
  ScoreLanes* lanes = w->score_lanes();
  ASSERT_TRUE(lanes->has_scores());
  EXPECT_TRUE(lanes->isVisible());
  EXPECT_EQ(lanes->ClassCount(ScoreLanes::kShapeLane), 9);
  EXPECT_EQ(lanes->ClassCount(ScoreLanes::kPlacementLane), 6);
  int compared = 0;
  for (const ScoreMatrix& m : stored->matrices) {
    const int lane = m.name == "shape" ? ScoreLanes::kShapeLane : ScoreLanes::kPlacementLane;
    ASSERT_TRUE(m.name == "shape" || m.name == "placement") << m.name;
    ASSERT_EQ(m.rows, take.frames());
    for (int64_t row : {int64_t{0}, m.rows / 3, m.rows / 2, m.rows - 1}) {
      EXPECT_NEAR(lanes->PlottedTime(lane, row), stored->start_s + static_cast<double>(row) / stored->rate_hz, 1e-12);
      for (int64_t c = 0; c < m.cols; ++c) {
        EXPECT_EQ(lanes->PlottedValue(lane, static_cast<int>(c), row), m.values[static_cast<size_t>(row * m.cols + c)])
            << m.name << " row " << row << " class " << c;
        ++compared;
      }
    }
  }
  EXPECT_EQ(compared, 4 * (9 + 6));
  // Decoded and expected key tiers as stored by csw keys score.
  EXPECT_EQ(lanes->decoded_tier(), "keys_decoded");
  EXPECT_EQ(lanes->expected_tier(), "keys_aligned");
  const LabelTier* decoded = Find(take.tiers, "keys_decoded");
  const LabelTier* aligned = Find(take.tiers, "keys_aligned");
  ASSERT_NE(decoded, nullptr);
  ASSERT_NE(aligned, nullptr);
  ASSERT_FALSE(decoded->labels.empty());
  ASSERT_EQ(lanes->TierLabels(0).size(), decoded->labels.size());
  ASSERT_EQ(lanes->TierLabels(1).size(), aligned->labels.size());
  for (size_t k = 0; k < decoded->labels.size(); ++k) {
    EXPECT_EQ(lanes->TierLabels(0)[k].text, decoded->labels[k].text);
    EXPECT_EQ(lanes->TierLabels(0)[k].start_s, decoded->labels[k].start_s);
  }
  // The cursor follows playback; the readout names the class with the largest posterior there.
  const ScoreMatrix* shape = nullptr;
  for (const ScoreMatrix& m : stored->matrices)
    if (m.name == "shape") shape = &m;
  ASSERT_NE(shape, nullptr);
  const int64_t frame = take.frames() / 2;
  w->playback()->Seek(frame);
  EXPECT_NEAR(lanes->cursor_time(), static_cast<double>(frame) / take.rate_hz, 1e-9);
  int best = 0;
  for (int c = 1; c < 9; ++c)
    if (shape->values[static_cast<size_t>(frame * 9 + c)] > shape->values[static_cast<size_t>(frame * 9 + best)])
      best = c;
  EXPECT_TRUE(lanes->Readout(ScoreLanes::kShapeLane).startsWith(QStringLiteral("shape: %1 (").arg(best)))
      << lanes->Readout(ScoreLanes::kShapeLane).toStdString();
  // The shared time axis: zooming the time-series panel zooms the lanes.
  w->plots()->SetTimeRange(0.5, 1.25);
  EXPECT_NEAR(lanes->view_start(), w->plots()->view_start(), 1e-9);
  EXPECT_NEAR(lanes->view_end(), w->plots()->view_end(), 1e-9);
  EXPECT_NEAR(lanes->lane_plot(ScoreLanes::kPlacementLane)->xAxis->range().lower, w->plots()->view_start(), 1e-9);
  // Each lane alone as a figure.
  for (int lane = 0; lane < ScoreLanes::kLaneCount; ++lane)
    for (const char* ext : {"png", "svg", "pdf"}) {
      const fs::path path = *dir_ / ("lane" + std::to_string(lane) + "." + ext);
      lanes->ExportLane(lane, QString::fromStdString(path.string()));
      ExpectFigure(path);
    }
  // A take without a gestural score hides the lanes.
  {
    CorpusTransaction tx(corpus_);
    Take plain = take;
    plain.name = "no_scores";
    plain.tiers.clear();
    tx.WriteTake(plain);
    tx.Commit();
  }
  ASSERT_TRUE(OpenAndWait(w.get(), corpus_));
  ASSERT_TRUE(SelectAndWait(w.get(), "no_scores"));
  EXPECT_FALSE(w->score_lanes()->has_scores());
  EXPECT_FALSE(w->score_lanes()->isVisible());
  {
    CorpusTransaction tx(corpus_);
    tx.RemoveTake("no_scores");
    tx.Commit();
  }
}

// File > Export of the label tiers: TextGrid and EAF written on a worker read
// back (io readers) as the tiers the window holds, including a label edit not
// yet autosaved.
TEST_F(ViewsTest, ExportedLabelTiersReadBackAsTheTakesTiers) {
  auto w = OpenWindow();
  ASSERT_TRUE(SelectAndWait(w.get(), "sentence_1"));
  w->labels()->SetAutosaveDelay(600000);  // the edit below stays unsaved
  ASSERT_TRUE(w->SetLabelTier(QStringLiteral("my_targets")));
  ASSERT_TRUE(w->labels()->AddLabel(30, QStringLiteral("25")));
  ASSERT_TRUE(w->labels()->HasUnsavedEdits());
  std::vector<LabelTier> expected = Corpus::Open(corpus_).LoadTiers("sentence_1");
  ASSERT_EQ(Find(expected, "my_targets"), nullptr);  // not in the corpus yet
  const double rate = w->take()->rate_hz;
  LabelTier mine{"my_targets", LabelTier::Kind::kPoint, 0.0, w->take()->duration_s(), {}};
  mine.labels.push_back({30 / rate, 30 / rate, "25"});
  expected.push_back(mine);

  for (const char* ext : {"TextGrid", "eaf"}) {
    const fs::path path = *dir_ / (std::string("sentence_1.") + ext);
    QSignalSpy finished(w->exporter(), &ExportRunner::Finished);
    ASSERT_TRUE(w->ExportLabels(QString::fromStdString(path.string())));
    ASSERT_TRUE(finished.wait(kHangGuardMs));
    ASSERT_TRUE(finished.at(0).at(0).toBool()) << finished.at(0).at(2).toString().toStdString();
    const bool textgrid = std::string(ext) == "TextGrid";
    const std::vector<LabelTier> back = textgrid ? ReadTextGrid(path.string()) : ReadEaf(path.string());
    ASSERT_EQ(back.size(), expected.size()) << ext;
    for (size_t i = 0; i < expected.size(); ++i) {
      const LabelTier& want = expected[i];
      const LabelTier& got = back[i];
      EXPECT_EQ(got.name, want.name) << ext;
      EXPECT_EQ(got.kind, want.kind) << ext << " " << want.name;
      if (textgrid) {
        // Written exactly, interval tiers made contiguous for Praat.
        const LabelTier filled = FillIntervalGaps(want);
        ASSERT_EQ(got.labels.size(), filled.labels.size()) << want.name;
        for (size_t k = 0; k < filled.labels.size(); ++k) {
          EXPECT_EQ(got.labels[k].start_s, filled.labels[k].start_s) << want.name << " " << k;
          EXPECT_EQ(got.labels[k].end_s, filled.labels[k].end_s) << want.name << " " << k;
          EXPECT_EQ(got.labels[k].text, filled.labels[k].text) << want.name << " " << k;
        }
      } else {
        // EAF: whole milliseconds, labels with text only, in time order (a
        // tier's points may be out of order, e.g. overlapping aligned keys).
        std::vector<Label> a = NonEmpty(want), b = NonEmpty(got);
        auto by_time = [](const Label& x, const Label& y) { return x.start_s < y.start_s; };
        std::stable_sort(a.begin(), a.end(), by_time);
        std::stable_sort(b.begin(), b.end(), by_time);
        ASSERT_EQ(b.size(), a.size()) << want.name;
        for (size_t k = 0; k < a.size(); ++k) {
          EXPECT_NEAR(b[k].start_s, a[k].start_s, 0.0005 + 1e-9) << want.name << " " << k;
          EXPECT_NEAR(b[k].end_s, a[k].end_s, 0.0005 + 1e-9) << want.name << " " << k;
          EXPECT_EQ(b[k].text, a[k].text) << want.name << " " << k;
        }
      }
    }
  }
  // An unknown extension fails with a message and writes nothing.
  QSignalSpy finished(w->exporter(), &ExportRunner::Finished);
  const fs::path bad = *dir_ / "labels.csv";
  ASSERT_TRUE(w->ExportLabels(QString::fromStdString(bad.string())));
  ASSERT_TRUE(finished.wait(kHangGuardMs));
  EXPECT_FALSE(finished.at(0).at(0).toBool());
  EXPECT_FALSE(fs::exists(bad));
}

// File > Export of a key-recogniser file: the copy has the same bytes and its
// summary names what it holds (the classes csw keys train fitted).
TEST_F(ViewsTest, ExportedModelFileIsCopiedWithASummaryOfItsContents) {
  auto w = OpenWindow();
  const fs::path copy = *dir_ / "exported-keys.h5";
  QSignalSpy finished(w->exporter(), &ExportRunner::Finished);
  ASSERT_TRUE(w->ExportModelFile(QString::fromStdString(keys_), QString::fromStdString(copy.string())));
  ASSERT_TRUE(finished.wait(kHangGuardMs));
  ASSERT_TRUE(finished.at(0).at(0).toBool()) << finished.at(0).at(2).toString().toStdString();
  EXPECT_EQ(FileBytes(copy), FileBytes(keys_));
  const FileSummary& s = w->exporter()->summary();
  EXPECT_EQ(s.kind, "key recogniser");
  EXPECT_EQ(s.facts["file"], copy.string());
  EXPECT_EQ(s.facts["model_count"], 0);  // no face, hand or rigid model in a key-recogniser file
  ASSERT_TRUE(s.facts.contains("key_recogniser"));
  // The training takes and the shape classes csw keys train reported.
  EXPECT_EQ(s.facts["key_recogniser"]["training_takes"], nlohmann::json({"sentence_1", "sentence_2", "sentence_3"}));
  EXPECT_NE(s.text.find("key recogniser:"), std::string::npos) << s.text;
  EXPECT_NE(s.text.find("training takes: sentence_1, sentence_2, sentence_3"), std::string::npos) << s.text;
  int64_t frames = 0;
  for (const auto& c : s.facts["key_recogniser"]["shape_classes"]) frames += c["count"].get<int64_t>();
  EXPECT_EQ(frames, s.facts["key_recogniser"]["training_frames"].get<int64_t>());
  ASSERT_NE(w->exporter()->summary_box(), nullptr);
  EXPECT_TRUE(w->exporter()->summary_box()->isVisible());
  EXPECT_TRUE(w->exporter()->summary_box()->informativeText().contains("key recogniser:"));
  // A corpus is not a model file: refused, nothing written.
  const fs::path wrong = *dir_ / "not-a-model.h5";
  ASSERT_TRUE(w->ExportModelFile(QString::fromStdString(corpus_), QString::fromStdString(wrong.string())));
  ASSERT_TRUE(finished.wait(kHangGuardMs));
  EXPECT_FALSE(finished.at(1).at(0).toBool());
  EXPECT_FALSE(fs::exists(wrong));
}

// A dictionary file exported the same way: its summary counts its units and
// names what it was built from.
TEST_F(ViewsTest, ExportedDictionaryFileSummaryNamesItsUnits) {
  dict::Dictionary d;
  d.models_fingerprint = std::string(64, 'b');
  d.corpus = "corpus.h5";
  d.models_file = "models.h5";
  d.keys_file = "keys.h5";
  d.key_tier = "keys_aligned";
  d.hand_parameter_names = {"h1", "h2"};
  for (int i = 0; i < 2; ++i) {
    dict::DikeyUnit u;
    u.take = "s" + std::to_string(i);
    u.index = i;
    u.from = KeyCode{1, 2 + i};
    u.to = KeyCode{3, 4};
    u.start_s = 0.5 + i;
    u.end_s = 0.8 + i;
    u.first_frame = 60 + 120 * i;
    u.rate_hz = 120;
    u.phasing_s = -0.05;
    u.hand_params = Eigen::MatrixXd::Constant(3, 2, 1.0 + i);
    u.forearm_in_head = Eigen::MatrixXd::Zero(3, 6);
    u.head_pose = Eigen::MatrixXd::Zero(3, 6);
    d.dikeys.push_back(u);
  }
  const fs::path source = *dir_ / "dict.h5";
  SaveDictionaryFile(source.string(), d);
  auto w = OpenWindow();
  const fs::path copy = *dir_ / "exported-dict.h5";
  QSignalSpy finished(w->exporter(), &ExportRunner::Finished);
  ASSERT_TRUE(w->ExportModelFile(QString::fromStdString(source.string()), QString::fromStdString(copy.string())));
  ASSERT_TRUE(finished.wait(kHangGuardMs));
  ASSERT_TRUE(finished.at(0).at(0).toBool()) << finished.at(0).at(2).toString().toStdString();
  EXPECT_EQ(FileBytes(copy), FileBytes(source));
  const FileSummary& s = w->exporter()->summary();
  EXPECT_EQ(s.kind, "dictionary");
  EXPECT_EQ(s.facts["dikey_units"], 2);
  EXPECT_EQ(s.facts["diphone_units"], 0);
  EXPECT_EQ(s.facts["hand_parameters"], 2);
  EXPECT_NE(s.text.find("dikey units: 2 (2 hand parameters)"), std::string::npos) << s.text;
  EXPECT_NE(s.text.find("key recogniser: keys.h5 (tier keys_aligned)"), std::string::npos) << s.text;
}

// Models > Phasing and Confusion run on the corpus with the key recogniser:
// the confusion matrices are those of csw keys score, the histograms count
// exactly the keys csw phasing's statistics count, and both figures export.
TEST_F(ViewsTest, PhasingAndConfusionViewsShowTheJobsResults) {
  auto w = OpenWindow();
  PhasingView* view = w->phasing_view();
  QSignalSpy finished(view, &PhasingView::Finished);
  ASSERT_TRUE(w->ShowPhasing(QString::fromStdString(keys_)));
  EXPECT_TRUE(w->phasing_dock()->isVisible());
  ASSERT_TRUE(finished.wait(kHangGuardMs));
  ASSERT_EQ(finished.at(0).at(0).toString(), "succeeded") << view->status_label()->text().toStdString();
  const AnalysisData& data = view->data();
  ASSERT_FALSE(data.keys_score.is_null()) << data.notes.join("; ").toStdString();
  ASSERT_FALSE(data.phasing.is_null()) << data.notes.join("; ").toStdString();

  // Confusion: csw keys score (dry run) computed here independently.
  Progress quiet;
  jobs::KeysScoreOptions ks;
  ks.corpus = corpus_;
  ks.keys = keys_;
  ks.dry_run = true;
  const nlohmann::json score = jobs::KeysScore(ks, quiet);
  const char* which[2] = {"shape", "placement"};
  for (int w2 = 0; w2 < 2; ++w2) {
    const nlohmann::json& rows = score[which[w2]]["confusion"];
    int64_t total = 0;
    for (size_t t = 0; t < rows.size(); ++t)
      for (size_t d = 0; d < rows[t].size(); ++d) {
        EXPECT_EQ(view->ConfusionCell(w2, static_cast<int>(t), static_cast<int>(d)), rows[t][d].get<int>())
            << which[w2] << " " << t << " " << d;
        total += view->ConfusionCell(w2, static_cast<int>(t), static_cast<int>(d));
      }
    EXPECT_EQ(total, score[which[w2]]["count"].get<int64_t>());
    EXPECT_GT(total, 0);
  }

  // Histograms (per-key CSV) count what the JSON summary counts, per key type and landmark.
  const char* comp[4][2] = {{"placement", "onset"}, {"placement", "target"}, {"shape", "onset"}, {"shape", "target"}};
  int counted = 0;
  for (int method = 0; method < 2; ++method) {
    view->SetMethod(method);
    const nlohmann::json& summary = data.phasing[method == 0 ? "kinematic" : "posterior"];
    for (int t = 0; t < 3; ++t)
      for (int c = 0; c < 4; ++c) {
        const int n = summary[PhasingView::kTypes[t]][comp[c][0]][comp[c][1]]["count"].get<int>();
        EXPECT_EQ(view->HistogramTotal(t, c), n) << method << " " << PhasingView::kTypes[t] << " " << c;
        counted += n;
      }
  }
  EXPECT_GT(counted, 0);

  // Both figures, each format.
  for (const char* ext : {"png", "svg", "pdf"}) {
    const fs::path p = *dir_ / (std::string("phasing.") + ext);
    const fs::path c = *dir_ / (std::string("confusion.") + ext);
    view->ExportPhasing(QString::fromStdString(p.string()));
    view->ExportConfusion(QString::fromStdString(c.string()));
    ExpectFigure(p);
    ExpectFigure(c);
  }

  // A result opened from csw phasing's JSON (with its CSV).
  const fs::path csv = *dir_ / "phasing.csv";
  jobs::PhasingOptions po;
  po.corpus = corpus_;
  po.keys = keys_;
  po.takes = {"sentence_1"};  // one take is enough here (and quicker)
  po.csv = csv.string();
  const nlohmann::json phasing = jobs::Phasing(po, quiet);
  const fs::path json_path = *dir_ / "phasing.json";
  std::ofstream(json_path) << phasing.dump(1);
  view->SetMethod(0);
  ASSERT_TRUE(view->OpenJson(QString::fromStdString(json_path.string())));
  ASSERT_TRUE(finished.wait(kHangGuardMs));
  ASSERT_EQ(finished.at(1).at(0).toString(), "succeeded") << view->status_label()->text().toStdString();
  EXPECT_TRUE(view->data().keys_score.is_null());
  EXPECT_EQ(view->data().keys.size(), phasing["keys_measured"].get<size_t>());
  for (int t = 0; t < 3; ++t)
    for (int c = 0; c < 4; ++c)
      EXPECT_EQ(view->HistogramTotal(t, c),
                phasing["kinematic"][PhasingView::kTypes[t]][comp[c][0]][comp[c][1]]["count"].get<int>());
  // Not a result of either job: a failure in the status line, the view unchanged.
  const fs::path other = *dir_ / "other.json";
  std::ofstream(other) << R"({"hello": 1})";
  ASSERT_TRUE(view->OpenJson(QString::fromStdString(other.string())));
  ASSERT_TRUE(finished.wait(kHangGuardMs));
  EXPECT_EQ(finished.at(2).at(0).toString(), "failed");
  EXPECT_EQ(view->data().keys.size(), phasing["keys_measured"].get<size_t>());
}

}  // namespace
}  // namespace csw::gui
