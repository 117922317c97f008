// Models and errors in the workbench, driven through the real widgets
// offscreen (issue 16, item 5): the fit dialog runs jobs::Fit on a worker
// thread; Cancel pressed while the fit is held midway leaves the model file as
// it was (absent, or byte for byte the same), and the same fit run to the end
// writes a model file that loads. In the reconstruction-error inspector a
// click on the bar of the utterance with the largest mean error shows that
// take at its worst frame, computed here from jobs::Invert's per-frame
// reports (the rows of `csw invert --frames-csv`), not from the widget.
#include <gtest/gtest.h>
#include <qcustomplot.h>

#include <QApplication>
#include <QDockWidget>
#include <QLabel>
#include <QProgressBar>
#include <QPushButton>
#include <QSignalSpy>
#include <QTableWidget>
#include <QTest>
#include <atomic>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <memory>
#include <mutex>
#include <semaphore>
#include <string>
#include <vector>

#include "core/progress.h"
#include "io/corpus/corpus.h"
#include "io/models/model_file.h"
#include "tests/gui/take_wait.h"
#include "tests/testing/testing.h"
#include "workbench/gui/error_inspector.h"
#include "workbench/gui/fit_dialog.h"
#include "workbench/gui/job_runner.h"
#include "workbench/gui/log_panel.h"
#include "workbench/gui/main_window.h"
#include "workbench/gui/marker_view.h"
#include "workbench/gui/playback.h"
#include "workbench/jobs/fit_job.h"
#include "workbench/jobs/import_job.h"
#include "workbench/jobs/invert_job.h"

namespace csw::gui {
namespace {

namespace fs = std::filesystem;

std::string FileBytes(const fs::path& path) {
  std::ifstream in(path, std::ios::binary);
  return std::string(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
}

// The demo corpus's first three sentences, remembering their marker set as
// `csw import --markerset` leaves them; made once.
class FitInspectTest : public ::testing::Test {
 protected:
  // The embedded demo corpus's first three sentences (datasets/demo/sentences,
  // imported as the README's main command imports them, with their marker set).
  static void SetUpTestSuite() {
    dir_ = new testing::TempDir();
    corpus_ = (*dir_ / "corpus.h5").string();
    const std::filesystem::path demo = testing::SourceDir() / "datasets" / "demo" / "sentences";
    jobs::ImportOptions o;
    for (const char* name : {"sentence_001", "sentence_002", "sentence_003"}) {
      o.files.push_back((demo / (std::string(name) + ".c3d")).string());
      o.files.push_back((demo / (std::string(name) + ".TextGrid")).string());
    }
    o.markerset = (demo / "markerset.json").string();
    o.corpus = corpus_;
    Progress quiet;
    ASSERT_EQ(jobs::Import(o, quiet).takes.size(), 3u);
  }
  static void TearDownTestSuite() {
    delete dir_;
    dir_ = nullptr;
  }

  std::unique_ptr<MainWindow> OpenWindow() { return OpenWindow(corpus_); }
  std::unique_ptr<MainWindow> OpenWindow(const std::string& corpus) {
    auto w = std::make_unique<MainWindow>(QString::fromStdString((*dir_ / "settings.ini").string()));
    w->playback()->SetAudioEnabled(false);
    w->resize(1400, 900);
    w->show();
    QApplication::setActiveWindow(w.get());
    EXPECT_TRUE(QTest::qWaitForWindowActive(w.get()));
    EXPECT_TRUE(OpenAndWait(w.get(), corpus));
    return w;
  }

  static testing::TempDir* dir_;
  static std::string corpus_;
};

testing::TempDir* FitInspectTest::dir_ = nullptr;
std::string FitInspectTest::corpus_;

// Holds the fit's worker at its first progress report past the first training
// take ("loading takes", fraction > 0) until released, and records the stages
// the worker reports after that. Shared with the worker's hook.
struct FitHold {
  std::atomic<bool> reached{false};
  std::atomic<bool> released{false};
  bool given = false;  // Release() called (GUI thread)
  std::binary_semaphore resume{0};
  std::mutex mutex;
  std::vector<std::string> stages_after;

  void Release() {
    if (given) return;
    given = true;
    resume.release();
  }
};

void InstallHold(JobRunner* runner, const std::shared_ptr<FitHold>& hold) {
  runner->SetWorkerHook([hold](const std::string& stage, double fraction) {
    if (hold->released.load()) {
      std::lock_guard<std::mutex> lock(hold->mutex);
      hold->stages_after.push_back(stage);
      return;
    }
    if (hold->reached.load() || stage != "loading takes" || fraction <= 0.0) return;
    hold->reached = true;
    hold->resume.acquire();
    hold->released = true;
  });
}

// Starts a fit from the dialog's Fit button, holds it midway, presses Cancel,
// and waits for the dialog's outcome.
void FitAndCancelMidway(MainWindow* w, FitDialog* dialog) {
  auto hold = std::make_shared<FitHold>();
  // Never leave the worker held when a check below fails.
  struct Guard {
    std::shared_ptr<FitHold> hold;
    ~Guard() {
      if (hold->reached.load()) hold->Release();
    }
  } guard{hold};
  QSignalSpy finished(dialog, &FitDialog::FitFinished);
  InstallHold(dialog->runner(), hold);
  QTest::mouseClick(dialog->fit_button(), Qt::LeftButton);
  ASSERT_TRUE(dialog->running()) << dialog->status_label()->text().toStdString();
  EXPECT_FALSE(dialog->fit_button()->isEnabled());
  EXPECT_TRUE(dialog->cancel_button()->isEnabled());
  ASSERT_TRUE(QTest::qWaitFor([&] { return hold->reached.load(); }, kHangGuardMs));
  // The window stays usable while the fit runs: step a frame in it.
  QApplication::setActiveWindow(w);
  ASSERT_TRUE(QTest::qWaitForWindowActive(w));
  const int64_t frame = w->playback()->frame();
  QTest::keyClick(w, Qt::Key_Right);
  EXPECT_EQ(w->playback()->frame(), frame + 1);
  QTest::mouseClick(dialog->cancel_button(), Qt::LeftButton);
  hold->Release();
  ASSERT_TRUE(finished.wait(kHangGuardMs));
  ASSERT_EQ(finished.count(), 1);
  EXPECT_EQ(finished.at(0).at(0).toString(), "canceled");
  EXPECT_FALSE(dialog->running());
  EXPECT_TRUE(dialog->fit_button()->isEnabled());
  EXPECT_FALSE(dialog->cancel_button()->isEnabled());
  EXPECT_TRUE(dialog->status_label()->text().startsWith("Fit cancelled"))
      << dialog->status_label()->text().toStdString();
  // Stopped at the next check: the fit never got to save.
  {
    std::lock_guard<std::mutex> lock(hold->mutex);
    for (const std::string& s : hold->stages_after) EXPECT_NE(s, "saving");
  }
  dialog->runner()->SetWorkerHook(nullptr);
}

TEST_F(FitInspectTest, FitCancelledMidwayLeavesTheModelFileThenRunsToTheEnd) {
  auto w = OpenWindow();
  const fs::path models = *dir_ / "dialog-models.h5";
  ASSERT_FALSE(fs::exists(models));
  FitDialog* dialog = w->ShowFitDialog();
  ASSERT_NE(dialog, nullptr);
  EXPECT_TRUE(dialog->isVisible());
  EXPECT_EQ(dialog->take_list()->count(), 3);
  EXPECT_EQ(dialog->CheckedTakes(), (QStringList{"sentence_001", "sentence_002", "sentence_003"}));
  dialog->SetKind(QStringLiteral("face"));
  dialog->SetOutput(QString::fromStdString(models.string()));

  // 1. Cancelled midway: no model file appears.
  FitAndCancelMidway(w.get(), dialog);
  EXPECT_FALSE(fs::exists(models));
  EXPECT_TRUE(w->log()->entries().back().startsWith("Fit cancelled")) << w->log()->entries().back().toStdString();

  // 2. The same fit run to the end: the file holds a face model that loads.
  QSignalSpy finished(dialog, &FitDialog::FitFinished);
  QSignalSpy saved(dialog, &FitDialog::ModelSaved);
  QTest::mouseClick(dialog->fit_button(), Qt::LeftButton);
  ASSERT_TRUE(dialog->running());
  ASSERT_TRUE(finished.wait(kHangGuardMs));
  ASSERT_EQ(finished.at(0).at(0).toString(), "succeeded") << w->log()->entries().back().toStdString();
  ASSERT_EQ(saved.count(), 1);
  EXPECT_EQ(saved.at(0).at(0).toString(), QString::fromStdString(models.string()));
  EXPECT_EQ(dialog->progress_bar()->value(), dialog->progress_bar()->maximum());
  ASSERT_TRUE(fs::exists(models));
  const ModelFile loaded = LoadModelFile(models.string());
  ASSERT_TRUE(loaded.face.has_value());
  EXPECT_FALSE(loaded.hand.has_value());
  EXPECT_EQ(dialog->result()["kind"], "face");
  EXPECT_EQ(dialog->result()["training_takes"], nlohmann::json({"sentence_001", "sentence_002", "sentence_003"}));

  // 3. Another fit into the same file, cancelled midway: the file's bytes are unchanged.
  const std::string before = FileBytes(models);
  dialog->SetKind(QStringLiteral("hand"));
  dialog->SetCheckedTakes({"sentence_001", "sentence_003"});
  FitAndCancelMidway(w.get(), dialog);
  EXPECT_EQ(FileBytes(models), before);
  // ... and no temporary model file is left behind (the lock file stays, as after any write).
  for (const auto& entry : fs::directory_iterator(dir_->path()))
    EXPECT_EQ(entry.path().filename().string().find(".csw-tmp."), std::string::npos) << entry.path();
  EXPECT_TRUE(LoadModelFile(models.string()).face.has_value());
  EXPECT_FALSE(LoadModelFile(models.string()).hand.has_value());
}

// The configuration: a wrong one is refused before any job starts (the reason
// in the status line and the log); a loaded file is what the fit uses, as
// `csw fit --config FILE` would.
TEST_F(FitInspectTest, FitDialogChecksAndUsesTheConfiguration) {
  auto w = OpenWindow();
  FitDialog* dialog = w->ShowFitDialog();
  dialog->SetKind(QStringLiteral("face"));
  const fs::path models = *dir_ / "config-models.h5";
  dialog->SetOutput(QString::fromStdString(models.string()));
  dialog->SetConfigText(QStringLiteral(R"({"face": {"components": "six"}})"));
  QTest::mouseClick(dialog->fit_button(), Qt::LeftButton);
  EXPECT_FALSE(dialog->running());
  EXPECT_TRUE(dialog->status_label()->text().startsWith("Not started: "))
      << dialog->status_label()->text().toStdString();
  EXPECT_TRUE(w->log()->entries().back().startsWith("error: Fit not started"))
      << w->log()->entries().back().toStdString();
  EXPECT_FALSE(fs::exists(models));

  const fs::path config = *dir_ / "three.json";
  {
    std::ofstream out(config);
    out << R"({"format": "csw-model-config", "face": {"components": 3}})";
  }
  ASSERT_TRUE(dialog->LoadConfigFile(QString::fromStdString(config.string())));
  QSignalSpy finished(dialog, &FitDialog::FitFinished);
  QTest::mouseClick(dialog->fit_button(), Qt::LeftButton);
  ASSERT_TRUE(dialog->running()) << dialog->status_label()->text().toStdString();
  ASSERT_TRUE(finished.wait(kHangGuardMs));
  ASSERT_EQ(finished.at(0).at(0).toString(), "succeeded") << w->log()->entries().back().toStdString();
  // The same fit by the job itself.
  jobs::FitOptions fit;
  fit.corpus = corpus_;
  fit.kind = "face";
  fit.config = config.string();
  fit.output = (*dir_ / "config-models-job.h5").string();
  Progress progress;
  const nlohmann::json expected = jobs::Fit(fit, progress);
  ASSERT_TRUE(expected.contains("face"));
  EXPECT_EQ(expected["face"]["parameters"].size(), 3u);  // not the default 6
  EXPECT_EQ(dialog->result()["face"]["parameters"], expected["face"]["parameters"]);
  EXPECT_EQ(LoadModelFile(models.string()).face->info.config_json, LoadModelFile(fit.output).face->info.config_json);
}

TEST_F(FitInspectTest, ClickingTheWorstUtteranceShowsItsWorstFrame) {
  // The three sentences and a foreign take (two markers of another marker
  // set), which the inspector leaves out by itself.
  const std::string corpus = (*dir_ / "mixed.h5").string();
  {
    const Corpus sentences = Corpus::Open(corpus_);
    CorpusTransaction tx(corpus);
    for (const TakeSummary& t : sentences.Takes()) tx.WriteTake(sentences.LoadTake(t.name));
    Take foreign;
    foreign.name = "zz_foreign";
    foreign.rate_hz = 100;
    foreign.marker_names = {"a", "b"};
    foreign.markers.Resize(20, 2);
    for (int64_t f = 0; f < 20; ++f)
      for (int k = 0; k < 2; ++k) {
        float* p = foreign.markers.at(f, k);
        p[0] = static_cast<float>(k);
        p[1] = static_cast<float>(f);
        p[2] = 0.0f;
      }
    tx.WriteTake(foreign);
    tx.Commit();
  }
  const std::vector<std::string> sentences = {"sentence_001", "sentence_002", "sentence_003"};
  // A face model fitted on the first two sentences (the third is held out).
  const std::string models = (*dir_ / "inspect-models.h5").string();
  {
    jobs::FitOptions fit;
    fit.corpus = corpus;
    fit.kind = "face";
    fit.takes = {"sentence_001", "sentence_002"};
    fit.output = models;
    Progress progress;
    jobs::Fit(fit, progress);
  }
  // Expected, from the job's own reports: the utterance with the largest mean
  // visible error, and its frame with the largest max visible error.
  jobs::InvertOptions invert;
  invert.corpus = corpus;
  invert.models = models;
  invert.takes = sentences;
  std::vector<jobs::FrameReport> frames;
  Progress progress;
  const nlohmann::json summary = jobs::Invert(invert, progress, &frames);
  ASSERT_TRUE(summary.contains("face"));
  const nlohmann::json& takes = summary["face"]["takes"];
  ASSERT_EQ(takes.size(), 3u);
  size_t worst = 0;
  for (size_t i = 1; i < takes.size(); ++i) {
    if (takes[i]["visible"]["mean_mm"].get<double>() > takes[worst]["visible"]["mean_mm"].get<double>()) worst = i;
  }
  const std::string worst_take = takes[worst]["name"].get<std::string>();
  int64_t worst_frame = -1;
  double worst_error = -1;
  for (const jobs::FrameReport& r : frames) {
    if (r.model != "face" || r.take != worst_take || !std::isfinite(r.max_error_mm)) continue;
    if (r.max_error_mm > worst_error) {
      worst_error = r.max_error_mm;
      worst_frame = r.frame;
    }
  }
  ASSERT_GE(worst_frame, 0);
  // Not the frame the window shows anyway.
  ASSERT_GT(worst_frame, 0);

  auto w = OpenWindow(corpus);
  ErrorInspector* inspector = w->error_inspector();
  // An inspection cancelled midway (its Cancel button) shows nothing.
  {
    auto hold = std::make_shared<FitHold>();
    struct Guard {
      std::shared_ptr<FitHold> hold;
      ~Guard() {
        if (hold->reached.load()) hold->Release();
      }
    } guard{hold};
    InstallHold(inspector->runner(), hold);
    QSignalSpy cancelled(inspector, &ErrorInspector::Finished);
    ASSERT_TRUE(w->InspectErrors(QString::fromStdString(models)));
    ASSERT_TRUE(QTest::qWaitFor([&] { return hold->reached.load(); }, kHangGuardMs));
    auto* cancel = inspector->findChild<QPushButton*>("errorCancelButton");
    ASSERT_NE(cancel, nullptr);
    EXPECT_TRUE(cancel->isVisible());
    QTest::mouseClick(cancel, Qt::LeftButton);
    hold->Release();
    ASSERT_TRUE(cancelled.wait(kHangGuardMs));
    EXPECT_EQ(cancelled.at(0).at(0).toString(), "canceled");
    EXPECT_TRUE(inspector->results().empty());
    EXPECT_EQ(inspector->BarCount(), 0);
    EXPECT_FALSE(cancel->isVisible());
    inspector->runner()->SetWorkerHook(nullptr);
  }
  QSignalSpy finished(inspector, &ErrorInspector::Finished);
  ASSERT_TRUE(w->InspectErrors(QString::fromStdString(models)));
  EXPECT_TRUE(w->errors_dock()->isVisible());
  EXPECT_TRUE(inspector->running());
  ASSERT_TRUE(finished.wait(kHangGuardMs));
  ASSERT_EQ(finished.at(0).at(0).toString(), "succeeded") << w->log()->entries().back().toStdString();
  EXPECT_EQ(inspector->skipped(), QStringList{"zz_foreign"});
  EXPECT_TRUE(w->log()->entries().filter("Left out of the error inspection").size() == 1);

  // Bars in selection order, one per sentence, as the job's summary lists them.
  ASSERT_NE(inspector->shown(), nullptr);
  EXPECT_EQ(inspector->shown()->kind, "face");
  ASSERT_EQ(inspector->BarCount(), 3);
  for (size_t i = 0; i < takes.size(); ++i) {
    const UtteranceError& u = inspector->shown()->utterances[i];
    EXPECT_EQ(u.take, takes[i]["name"].get<std::string>());
    EXPECT_EQ(u.role, takes[i]["role"].get<std::string>());
    EXPECT_DOUBLE_EQ(u.mean_mm, takes[i]["visible"]["mean_mm"].get<double>());
  }
  EXPECT_EQ(inspector->shown()->utterances[2].role, "held_out");
  // The per-marker table: one row per marker of the model, largest mean first.
  const nlohmann::json& markers = summary["face"]["markers"];
  QTableWidget* table = inspector->marker_table();
  ASSERT_EQ(table->rowCount(), static_cast<int>(markers.size()));
  std::string largest;
  double largest_mean = -1;
  for (const nlohmann::json& m : markers) {
    if (m["visible"].contains("mean_mm") && m["visible"]["mean_mm"].is_number() &&
        m["visible"]["mean_mm"].get<double>() > largest_mean) {
      largest_mean = m["visible"]["mean_mm"].get<double>();
      largest = m["marker"].get<std::string>();
    }
  }
  EXPECT_EQ(table->item(0, 0)->text().toStdString(), largest);

  // Click the tallest bar where it is drawn.
  QSignalSpy chosen(inspector, &ErrorInspector::UtteranceChosen);
  const auto centre = inspector->BarCenter(static_cast<int>(worst));
  ASSERT_TRUE(centre.has_value());
  ASSERT_EQ(inspector->BarAt(*centre), static_cast<int>(worst));
  QTest::mouseClick(inspector->plot(), Qt::LeftButton, Qt::NoModifier, centre->toPoint());
  ASSERT_EQ(chosen.count(), 1);
  EXPECT_EQ(chosen.at(0).at(0).toString().toStdString(), worst_take);
  EXPECT_EQ(chosen.at(0).at(1).toLongLong(), worst_frame);
  // The take loads off the GUI thread; it is shown at that frame when it arrives.
  ASSERT_TRUE(WaitForTake(w.get(), worst_take));
  ASSERT_NE(w->take(), nullptr);
  EXPECT_EQ(w->take()->name, worst_take);
  EXPECT_EQ(w->playback()->frame(), worst_frame);
  EXPECT_EQ(w->marker_view()->frame(), worst_frame);
  EXPECT_EQ(inspector->chosen(), static_cast<int>(worst));

  // The 3D view then draws the model's reconstruction of that take with its
  // observed markers: reconstructed markers where they are seen (and, when
  // the frame has gaps in face markers, where they are missing).
  ASSERT_TRUE(QTest::qWaitFor(
      [&] {
        return w->marker_view()->has_reconstruction() && inspector->reconstruction_take().toStdString() == worst_take;
      },
      kHangGuardMs));
  EXPECT_GT(w->marker_view()->DrawnReconstructedCount(true), 0);
  int missing_face = 0;
  for (int64_t k = 0; k < w->take()->markers.markers(); ++k) {
    const std::string& name = w->take()->marker_names[static_cast<size_t>(k)];
    bool in_model = false;
    for (const nlohmann::json& m : markers) in_model = in_model || m["marker"] == name;
    missing_face += in_model && !w->take()->markers.Visible(worst_frame, k);
  }
  EXPECT_LE(w->marker_view()->DrawnReconstructedCount(false), missing_face);
}

}  // namespace
}  // namespace csw::gui
