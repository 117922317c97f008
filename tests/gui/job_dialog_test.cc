// The Analysis menu's jobs run from the window (issue 16: every model and
// analysis job runs from it, off the GUI thread, with progress and a Cancel
// that really stops them). Each job's result in the corpus is compared with
// the same job run directly (the CLI's function) on a copy of the corpus made
// before: the GUI adds no computation of its own, only the shell.
#include "workbench/gui/job_dialog.h"

#include <gtest/gtest.h>

#include <QApplication>
#include <QLabel>
#include <QLineEdit>
#include <QPlainTextEdit>
#include <QPushButton>
#include <QSignalSpy>
#include <QTest>
#include <atomic>
#include <filesystem>
#include <memory>
#include <semaphore>
#include <string>
#include <vector>

#include "core/progress.h"
#include "io/corpus/corpus.h"
#include "tests/gui/take_wait.h"
#include "tests/keys_job/cuer_corpus.h"
#include "workbench/gui/job_runner.h"
#include "workbench/gui/log_panel.h"
#include "workbench/gui/main_window.h"
#include "workbench/gui/playback.h"
#include "workbench/jobs/cue_job.h"
#include "workbench/jobs/keys_suggest_job.h"

namespace csw::gui {
namespace {

namespace fs = std::filesystem;

// A corpus (index file and take folder) copied to `to`.
void CopyCorpus(const std::string& from, const std::string& to) {
  fs::copy_file(from, to);
  fs::copy(CorpusTransaction::FolderPath(from), CorpusTransaction::FolderPath(to), fs::copy_options::recursive);
}

const LabelTier* FindTier(const std::vector<LabelTier>& tiers, const std::string& name) {
  for (const LabelTier& t : tiers)
    if (t.name == name) return &t;
  return nullptr;
}

void ExpectSameTier(const LabelTier& a, const LabelTier& b) {
  EXPECT_EQ(a.kind, b.kind);
  ASSERT_EQ(a.labels.size(), b.labels.size()) << a.name;
  for (size_t i = 0; i < a.labels.size(); ++i) {
    EXPECT_DOUBLE_EQ(a.labels[i].start_s, b.labels[i].start_s) << a.name << " " << i;
    EXPECT_DOUBLE_EQ(a.labels[i].end_s, b.labels[i].end_s) << a.name << " " << i;
    EXPECT_EQ(a.labels[i].text, b.labels[i].text) << a.name << " " << i;
  }
}

class JobDialogTest : public ::testing::Test {
 protected:
  void SetUp() override {
    cuer_ = std::make_unique<testing::CuerCorpus>(2);
    reference_ = (cuer_->dir / "reference.h5").string();
    CopyCorpus(cuer_->corpus, reference_);
    window_ = std::make_unique<MainWindow>(QString::fromStdString((cuer_->dir / "settings.ini").string()));
    window_->playback()->SetAudioEnabled(false);
    window_->resize(1200, 800);
    window_->show();
    ASSERT_TRUE(OpenAndWait(window_.get(), cuer_->corpus));
    ASSERT_TRUE(SelectAndWait(window_.get(), "s1"));
  }

  // Presses Run and waits for the job's outcome; then, for a job that wrote
  // into the corpus, for the reopened corpus to show its take again.
  QString RunFromDialog(JobDialog* dialog) {
    QSignalSpy finished(dialog, &JobDialog::JobFinished);
    QSignalSpy reopened(window_.get(), &MainWindow::CorpusOpened);
    QTest::mouseClick(dialog->run_button(), Qt::LeftButton);
    EXPECT_TRUE(dialog->running()) << dialog->status_label()->text().toStdString();
    if (!finished.wait(kHangGuardMs)) return QStringLiteral("timeout");
    const QString outcome = finished.at(0).at(0).toString();
    if (outcome == QStringLiteral("succeeded") && dialog->spec().writes_corpus) {
      EXPECT_TRUE(reopened.count() > 0 || reopened.wait(kHangGuardMs));
      EXPECT_TRUE(WaitForTake(window_.get(), "s1"));
    }
    return outcome;
  }

  std::unique_ptr<testing::CuerCorpus> cuer_;
  std::string reference_;
  std::unique_ptr<MainWindow> window_;
};

TEST_F(JobDialogTest, ExpectedKeysFromTheAnalysisMenuEqualTheCueJobsAndShowInTheWindow) {
  JobDialog* dialog = window_->ShowJobDialog(QStringLiteral("cue"));
  ASSERT_NE(dialog, nullptr);
  EXPECT_EQ(dialog->corpus().toStdString(), cuer_->corpus);
  dialog->SetValue(QStringLiteral("tier"), QStringLiteral("expected_gui"));
  ASSERT_EQ(RunFromDialog(dialog), QStringLiteral("succeeded"));

  jobs::CueOptions direct;
  direct.input = reference_;
  direct.tier = "expected_gui";
  Progress quiet;
  const nlohmann::json expected = jobs::Cue(direct, quiet);
  EXPECT_EQ(dialog->result()["keys"], expected["keys"]);
  EXPECT_EQ(dialog->output()->toPlainText().trimmed().toStdString(),
            QString::fromStdString(jobs::CueText(dialog->result())).trimmed().toStdString());
  const Corpus gui = Corpus::Open(cuer_->corpus), ref = Corpus::Open(reference_);
  for (const std::string take : {"s0", "s1"}) {
    const std::vector<LabelTier> a = gui.LoadTiers(take), b = ref.LoadTiers(take);
    const LabelTier* ta = FindTier(a, "expected_gui");
    const LabelTier* tb = FindTier(b, "expected_gui");
    ASSERT_NE(ta, nullptr) << take;
    ASSERT_NE(tb, nullptr) << take;
    EXPECT_GT(tb->labels.size(), 5u) << take;
    ExpectSameTier(*ta, *tb);
  }
  // The window shows the reopened corpus's take with the new tier.
  ASSERT_TRUE(window_->take());
  EXPECT_NE(FindTier(window_->take()->tiers, "expected_gui"), nullptr);
}

TEST_F(JobDialogTest, SuggestedTargetsRunFromTheWindowAndACancelMidwayWritesNothing) {
  JobDialog* dialog = window_->ShowJobDialog(QStringLiteral("keys-suggest"));
  ASSERT_NE(dialog, nullptr);

  // Held at its first progress report, then cancelled: the corpus is unchanged.
  struct Hold {
    std::atomic<bool> reached{false};
    std::binary_semaphore resume{0};
  };
  auto hold = std::make_shared<Hold>();
  dialog->runner()->SetWorkerHook([hold](const std::string&, double) {
    if (hold->reached.exchange(true)) return;
    hold->resume.acquire();
  });
  QSignalSpy finished(dialog, &JobDialog::JobFinished);
  QTest::mouseClick(dialog->run_button(), Qt::LeftButton);
  ASSERT_TRUE(QTest::qWaitFor([&] { return hold->reached.load(); }, kHangGuardMs));
  EXPECT_TRUE(dialog->cancel_button()->isEnabled());
  EXPECT_FALSE(dialog->run_button()->isEnabled());
  QTest::mouseClick(dialog->cancel_button(), Qt::LeftButton);
  hold->resume.release();
  ASSERT_TRUE(finished.wait(kHangGuardMs));
  EXPECT_EQ(finished.at(0).at(0).toString(), QStringLiteral("canceled"));
  EXPECT_EQ(FindTier(Corpus::Open(cuer_->corpus).LoadTiers("s0"), "keys_suggested"), nullptr);
  EXPECT_TRUE(dialog->run_button()->isEnabled());

  // Run to the end: the tiers equal those of jobs::KeysSuggest on the copy.
  dialog->runner()->SetWorkerHook(nullptr);
  ASSERT_EQ(RunFromDialog(dialog), QStringLiteral("succeeded"));
  jobs::KeysSuggestOptions direct;
  direct.corpus = reference_;
  Progress quiet;
  const nlohmann::json expected = jobs::KeysSuggest(direct, quiet);
  EXPECT_EQ(dialog->result()["suggested"], expected["suggested"]);
  EXPECT_GT(expected["suggested"].get<int>(), 10);
  const Corpus gui = Corpus::Open(cuer_->corpus), ref = Corpus::Open(reference_);
  for (const std::string take : {"s0", "s1"}) {
    for (const std::string tier : {"keys_suggested", "placement_suggested"}) {
      const std::vector<LabelTier> a = gui.LoadTiers(take), b = ref.LoadTiers(take);
      const LabelTier* ta = FindTier(a, tier);
      const LabelTier* tb = FindTier(b, tier);
      ASSERT_NE(ta, nullptr) << take << " " << tier;
      ASSERT_NE(tb, nullptr) << take << " " << tier;
      ExpectSameTier(*ta, *tb);
    }
  }
  EXPECT_NE(FindTier(window_->take()->tiers, "keys_suggested"), nullptr);
}

TEST_F(JobDialogTest, MissingOrInvalidChoicesAreRefusedBeforeAnythingRuns) {
  // Every Analysis job has a dialog whose fields hold the CLI's defaults.
  for (const JobSpec& spec : AnalysisJobs()) {
    JobDialog* d = window_->ShowJobDialog(spec.id);
    ASSERT_NE(d, nullptr) << spec.id.toStdString();
    for (const JobField& f : spec.fields) {
      ASSERT_NE(d->field(f.key), nullptr) << spec.id.toStdString() << " " << f.key.toStdString();
      EXPECT_EQ(d->Value(f.key), f.value);
    }
  }
  // keys train needs takes and an output file.
  JobDialog* train = window_->ShowJobDialog(QStringLiteral("keys-train"));
  ASSERT_NE(train, nullptr);
  EXPECT_FALSE(train->Start());
  EXPECT_FALSE(train->running());
  EXPECT_TRUE(train->status_label()->text().contains(QStringLiteral("required")))
      << train->status_label()->text().toStdString();
  // clean: a cut-off that is not a number is named.
  JobDialog* clean = window_->ShowJobDialog(QStringLiteral("clean"));
  ASSERT_NE(clean, nullptr);
  clean->SetValue(QStringLiteral("cutoff_hz"), QStringLiteral("fast"));
  EXPECT_FALSE(clean->Start());
  EXPECT_TRUE(clean->status_label()->text().contains(QStringLiteral("cutoff_hz")))
      << clean->status_label()->text().toStdString();
  // An unknown job id gives no dialog.
  EXPECT_EQ(window_->ShowJobDialog(QStringLiteral("no-such-job")), nullptr);
  EXPECT_EQ(SplitTakes(QStringLiteral(" s0, s1  s2,,")), (std::vector<std::string>{"s0", "s1", "s2"}));
}

}  // namespace
}  // namespace csw::gui
