// The key-label lane driven from the keyboard through the real window,
// offscreen: targets set, moved, relabelled, deleted and jumped between; undo
// and redo on the window's QUndoStack; autosave to the corpus on a worker
// thread, checked by reopening the corpus; an edit made while the test holds
// the corpus's writer lock is kept and saved once the lock is released. Every
// check compares with the frames and codes typed (100 Hz take: frame f is at
// f / 100 s).
#include "workbench/gui/label_lane.h"

#include <gtest/gtest.h>
#include <unistd.h>

#include <QAction>
#include <QApplication>
#include <QComboBox>
#include <QImage>
#include <QLineEdit>
#include <QPixmap>
#include <QSignalSpy>
#include <QTest>
#include <QUndoStack>
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <map>
#include <memory>
#include <string>
#include <utility>
#include <vector>

#include "core/file_util.h"
#include "core/progress.h"
#include "io/corpus/corpus.h"
#include "tests/gui/take_wait.h"
#include "tests/testing/testing.h"
#include "workbench/gui/demo_take.h"
#include "workbench/gui/label_counts.h"
#include "workbench/gui/label_session.h"
#include "workbench/gui/log_panel.h"
#include "workbench/gui/main_window.h"
#include "workbench/gui/playback.h"
#include "workbench/gui/timeseries_panel.h"
#include "workbench/jobs/import_job.h"
#include "workbench/jobs/keys_suggest_job.h"

namespace csw::gui {
namespace {

constexpr double kRate = 100.0;
constexpr int kFrames = 50;
constexpr int kAutosaveMs = 300;       // the tests shorten the default few seconds
constexpr int kWaitMs = kHangGuardMs;  // upper bound for a save on a loaded test machine

Take MakeTake() {
  Take t;
  t.name = "alpha";
  t.rate_hz = kRate;
  t.marker_names = {"m0", "m1"};
  t.markers.Resize(kFrames, 2);
  // m0 moves at a constant speed (no speed minimum); m1 swings along x with a
  // 20-frame period, so its speed (central differences) is zero at every 10th frame.
  for (int f = 0; f < kFrames; ++f) {
    float* p = t.markers.at(f, 0);
    p[0] = static_cast<float>(f);
    p[1] = 0.0f;
    p[2] = 5.0f;
    p = t.markers.at(f, 1);
    p[0] = static_cast<float>(100.0 * std::cos(2.0 * M_PI * f / 20.0));
    p[1] = 10.0f;
    p[2] = 5.0f;
  }
  t.tiers = {LabelTier{"words", LabelTier::Kind::kInterval, 0.0, 0.5, {{0.0, 0.2, "bonjour"}, {0.2, 0.5, "papa"}}}};
  return t;
}

// (frame, code) of every label of `tier` of take alpha as stored in the corpus;
// the times must fall exactly on frames.
std::vector<std::pair<int, std::string>> StoredLabels(const std::string& corpus, const std::string& tier) {
  std::vector<std::pair<int, std::string>> out;
  const Take take = Corpus::Open(corpus).LoadTake("alpha");
  for (const LabelTier& t : take.tiers) {
    if (t.name != tier) continue;
    EXPECT_EQ(t.kind, LabelTier::Kind::kPoint);
    for (const Label& l : t.labels) {
      const double f = l.start_s * kRate;
      EXPECT_NEAR(f, std::round(f), 1e-9) << "label not on a frame: " << l.start_s;
      out.emplace_back(static_cast<int>(std::lround(f)), l.text);
    }
  }
  return out;
}

std::vector<std::pair<int, std::string>> ModelLabels(const LabelSession& s) {
  std::vector<std::pair<int, std::string>> out;
  for (size_t i = 0; i < s.model()->size(); ++i)
    out.emplace_back(static_cast<int>(s.TimeFrame(s.model()->at(i).start_s)), s.model()->at(i).text);
  return out;
}

using Labels = std::vector<std::pair<int, std::string>>;

QStringList PlotTierLanes(const TimeSeriesPanel& plots) {
  QStringList names;
  for (int lane = 0; lane < plots.lane_count(); ++lane) {
    if (plots.lane_kind(lane) == TimeSeriesPanel::LaneKind::kTier) names << plots.lane_name(lane);
  }
  return names;
}

class LabelLaneTest : public ::testing::Test {
 protected:
  void SetUp() override {
    corpus_ = (dir_ / "corpus.h5").string();
    CorpusTransaction tx(corpus_);
    tx.WriteTake(MakeTake());
    tx.Commit();
  }

  std::unique_ptr<MainWindow> OpenWindow(const std::string& tier, const std::string& take = "alpha") {
    auto w = std::make_unique<MainWindow>(QString::fromStdString((dir_ / "settings.ini").string()));
    w->playback()->SetAudioEnabled(false);
    w->resize(1200, 800);
    w->show();
    QApplication::setActiveWindow(w.get());
    EXPECT_TRUE(QTest::qWaitForWindowActive(w.get()));
    EXPECT_TRUE(OpenAndWait(w.get(), corpus_));
    EXPECT_TRUE(SelectAndWait(w.get(), take));
    EXPECT_TRUE(w->SetLabelTier(QString::fromStdString(tier)));
    w->labels()->SetAutosaveDelay(kAutosaveMs);
    w->labels()->SetRetryDelay(100);
    w->label_lane()->setFocus();
    EXPECT_TRUE(QTest::qWaitFor([&] { return w->label_lane()->hasFocus(); }, 2000));
    return w;
  }

  // Types a two-digit code into the lane.
  static void Type(MainWindow& w, const char* code) {
    QTest::keyClick(w.label_lane(), static_cast<Qt::Key>(Qt::Key_0 + (code[0] - '0')));
    QTest::keyClick(w.label_lane(), static_cast<Qt::Key>(Qt::Key_0 + (code[1] - '0')));
  }
  static void Key(MainWindow& w, Qt::Key key, Qt::KeyboardModifiers mods = Qt::NoModifier) {
    QTest::keyClick(w.label_lane(), key, mods);
  }

  testing::TempDir dir_;
  std::string corpus_;
};

TEST_F(LabelLaneTest, FiveTargetsFromKeyboardUndoTwoRedoOneAutosaveAndReopenFindFour) {
  auto w = OpenWindow("my_keys");
  LabelSession& s = *w->labels();
  ASSERT_TRUE(s.has_take());
  EXPECT_EQ(s.model()->size(), 0u);  // a new tier

  // Frames reached with the window's playback keys (Shift+Right = 10 frames).
  Key(*w, Qt::Key_Home);
  Key(*w, Qt::Key_Right, Qt::ShiftModifier);  // 10
  EXPECT_EQ(w->playback()->frame(), 10);
  Type(*w, "13");
  Key(*w, Qt::Key_Right, Qt::ShiftModifier);  // 20
  Key(*w, Qt::Key_Right);
  Key(*w, Qt::Key_Right);  // 22
  Type(*w, "25");
  Key(*w, Qt::Key_Right, Qt::ShiftModifier);  // 32
  Type(*w, "41");
  Key(*w, Qt::Key_Right, Qt::ShiftModifier);
  Key(*w, Qt::Key_Left);  // 41
  Type(*w, "00");
  Key(*w, Qt::Key_End);  // 49, the last frame
  Type(*w, "58");
  EXPECT_EQ(ModelLabels(s), (Labels{{10, "13"}, {22, "25"}, {32, "41"}, {41, "00"}, {49, "58"}}));
  EXPECT_EQ(s.undo_stack()->count(), 5);
  EXPECT_EQ(w->label_counts()->total(), 5);

  Key(*w, Qt::Key_Z, Qt::ControlModifier);
  Key(*w, Qt::Key_Z, Qt::ControlModifier);
  EXPECT_EQ(ModelLabels(s), (Labels{{10, "13"}, {22, "25"}, {32, "41"}}));
  Key(*w, Qt::Key_Z, Qt::ControlModifier | Qt::ShiftModifier);
  const Labels four{{10, "13"}, {22, "25"}, {32, "41"}, {41, "00"}};
  EXPECT_EQ(ModelLabels(s), four);
  EXPECT_EQ(s.undo_stack()->index(), 4);
  // The counts panel follows: one of each code left, none of the undone 58.
  EXPECT_EQ(w->label_counts()->total(), 4);
  for (const char* code : {"13", "25", "41", "00"}) EXPECT_EQ(w->label_counts()->Count(code), 1) << code;
  EXPECT_EQ(w->label_counts()->Count("58"), 0);

  // Nothing is saved before the autosave delay; then it is, without a user action.
  EXPECT_TRUE(s.HasUnsavedEdits());
  QSignalSpy saved(&s, &LabelSession::Saved);
  ASSERT_TRUE(QTest::qWaitFor([&] { return !s.HasUnsavedEdits(); }, kWaitMs));
  ASSERT_GE(saved.count(), 1);
  std::printf("autosave commit of one take's tiers: %.1f ms\n", saved.back().at(1).toDouble());
  EXPECT_EQ(StoredLabels(corpus_, "my_keys"), four);
  // The take's other tier is kept as it was.
  const Take stored = Corpus::Open(corpus_).LoadTake("alpha");
  ASSERT_EQ(stored.tiers.size(), 2u);
  EXPECT_EQ(stored.tiers[0].name, "words");
  ASSERT_EQ(stored.tiers[0].labels.size(), 2u);
  EXPECT_EQ(stored.tiers[0].labels[1].text, "papa");

  // Reopened in a new window, the lane shows the four labels.
  w.reset();
  auto again = OpenWindow("my_keys");
  EXPECT_EQ(ModelLabels(*again->labels()), four);
  EXPECT_EQ(again->labels()->undo_stack()->count(), 0);
  EXPECT_EQ(again->log()->CountLevel(LogPanel::Level::kError), 0);
}

TEST_F(LabelLaneTest, MoveRelabelDeleteAndJumpFromTheKeyboard) {
  auto w = OpenWindow("keys");
  LabelSession& s = *w->labels();
  Key(*w, Qt::Key_Home);
  for (int i = 0; i < 5; ++i) Key(*w, Qt::Key_Right);  // 5
  Type(*w, "21");
  Key(*w, Qt::Key_Right, Qt::ShiftModifier);  // 15
  Type(*w, "32");
  Key(*w, Qt::Key_Right, Qt::ShiftModifier);  // 25
  Type(*w, "43");
  EXPECT_EQ(ModelLabels(s), (Labels{{5, "21"}, {15, "32"}, {25, "43"}}));

  // Jumps: previous twice from 25 lands on 5; next lands on 15; next past the last stays.
  Key(*w, Qt::Key_Left, Qt::ControlModifier);
  EXPECT_EQ(w->playback()->frame(), 15);
  Key(*w, Qt::Key_Left, Qt::ControlModifier);
  EXPECT_EQ(w->playback()->frame(), 5);
  Key(*w, Qt::Key_Left, Qt::ControlModifier);
  EXPECT_EQ(w->playback()->frame(), 5);
  Key(*w, Qt::Key_Right, Qt::ControlModifier);
  EXPECT_EQ(w->playback()->frame(), 15);
  EXPECT_EQ(w->label_lane()->selected(), 1);

  // Alt+Right three times, Alt+Left once: 15 -> 17, the cursor follows.
  Key(*w, Qt::Key_Right, Qt::AltModifier);
  Key(*w, Qt::Key_Right, Qt::AltModifier);
  Key(*w, Qt::Key_Right, Qt::AltModifier);
  Key(*w, Qt::Key_Left, Qt::AltModifier);
  EXPECT_EQ(w->playback()->frame(), 17);
  EXPECT_EQ(ModelLabels(s), (Labels{{5, "21"}, {17, "32"}, {25, "43"}}));

  // Two digits on a labelled frame relabel it; a bad code (shape 9) is refused.
  Type(*w, "35");
  EXPECT_EQ(ModelLabels(s), (Labels{{5, "21"}, {17, "35"}, {25, "43"}}));
  const int errors = w->log()->CountLevel(LogPanel::Level::kError);
  const int commands = s.undo_stack()->count();
  Type(*w, "69");
  EXPECT_EQ(ModelLabels(s), (Labels{{5, "21"}, {17, "35"}, {25, "43"}}));
  EXPECT_EQ(w->log()->CountLevel(LogPanel::Level::kError), errors + 1);
  EXPECT_EQ(s.undo_stack()->count(), commands);
  // Esc forgets a first digit.
  QTest::keyClick(w->label_lane(), Qt::Key_4);
  EXPECT_EQ(w->label_lane()->pending_digit(), "4");
  Key(*w, Qt::Key_Escape);
  EXPECT_EQ(w->label_lane()->pending_digit(), "");

  // Delete on the cursor frame; on an empty frame nothing happens.
  Key(*w, Qt::Key_Delete);
  EXPECT_EQ(ModelLabels(s), (Labels{{5, "21"}, {25, "43"}}));
  Key(*w, Qt::Key_Delete);
  EXPECT_EQ(ModelLabels(s), (Labels{{5, "21"}, {25, "43"}}));

  // Undo back through delete, relabel and the four moves: the label is at 15 as "32" again.
  for (int i = 0; i < 6; ++i) Key(*w, Qt::Key_Z, Qt::ControlModifier);
  EXPECT_EQ(ModelLabels(s), (Labels{{5, "21"}, {15, "32"}, {25, "43"}}));
  EXPECT_EQ(s.undo_stack()->undoText(), "add key 43 at 0.250 s");
  // Ctrl+Y redoes too.
  Key(*w, Qt::Key_Y, Qt::ControlModifier);
  EXPECT_EQ(ModelLabels(s), (Labels{{5, "21"}, {16, "32"}, {25, "43"}}));
}

TEST_F(LabelLaneTest, LabelsSurviveReopenAndAnEditMadeUnderAnotherWritersLockIsSavedAfterIt) {
  {
    auto w = OpenWindow("keys");
    Key(*w, Qt::Key_Home);
    for (int i = 0; i < 5; ++i) Key(*w, Qt::Key_Right);
    Type(*w, "12");
    ASSERT_TRUE(QTest::qWaitFor([&] { return !w->labels()->HasUnsavedEdits(); }, kWaitMs));
  }
  EXPECT_EQ(StoredLabels(corpus_, "keys"), (Labels{{5, "12"}}));

  auto w = OpenWindow("keys");
  LabelSession& s = *w->labels();
  EXPECT_EQ(ModelLabels(s), (Labels{{5, "12"}}));  // survived the reopen

  // Another writer (here the test) holds the corpus's one-writer lock.
  auto lock = std::make_unique<WriterLock>(corpus_, "corpus");
  Key(*w, Qt::Key_Home);
  Key(*w, Qt::Key_Right, Qt::ShiftModifier);
  Key(*w, Qt::Key_Right, Qt::ShiftModifier);  // 20
  Type(*w, "34");
  EXPECT_EQ(ModelLabels(s), (Labels{{5, "12"}, {20, "34"}}));
  LogPanel& log = *w->log();
  ASSERT_TRUE(QTest::qWaitFor([&] { return log.CountLevel(LogPanel::Level::kWarning) >= 1; }, kWaitMs));
  EXPECT_TRUE(log.entries().back().contains("another writer holds the corpus")) << log.entries().back().toStdString();
  // ... and names it: here this test program, by its pid.
  EXPECT_TRUE(log.entries().back().contains(QStringLiteral("(pid %1) since ").arg(::getpid())))
      << log.entries().back().toStdString();
  // Several retries later: still waiting, one warning only, the corpus unchanged.
  QTest::qWait(600);
  EXPECT_TRUE(s.HasUnsavedEdits());
  EXPECT_EQ(log.CountLevel(LogPanel::Level::kWarning), 1);
  EXPECT_EQ(StoredLabels(corpus_, "keys"), (Labels{{5, "12"}}));

  lock.reset();  // the other writer is done
  ASSERT_TRUE(QTest::qWaitFor([&] { return !s.HasUnsavedEdits(); }, kWaitMs));
  EXPECT_EQ(StoredLabels(corpus_, "keys"), (Labels{{5, "12"}, {20, "34"}}));
  EXPECT_TRUE(log.entries().back().contains("saved now that the corpus is free")) << log.entries().back().toStdString();
  EXPECT_EQ(log.CountLevel(LogPanel::Level::kError), 0);
}

// Play and mark: two digits typed while the take plays set a target at the
// frame playing when the second digit is pressed. Closing the window with an
// edit not yet saved waits for the save, then closes.
TEST_F(LabelLaneTest, DigitsTypedWhilePlayingMarkThePlayingFrameAndClosingSavesFirst) {
  auto w = OpenWindow("keys");
  w->labels()->SetAutosaveDelay(60000);  // only the close saves
  Key(*w, Qt::Key_Home);
  Key(*w, Qt::Key_Space);  // play (the window's shortcut)
  ASSERT_TRUE(w->playback()->playing());
  ASSERT_TRUE(QTest::qWaitFor([&] { return w->playback()->frame() >= 10; }, kWaitMs));
  Type(*w, "23");
  const int frame = static_cast<int>(w->playback()->frame());  // no event loop ran between the digits and here
  EXPECT_GE(frame, 10);
  EXPECT_EQ(ModelLabels(*w->labels()), (Labels{{frame, "23"}}));
  Key(*w, Qt::Key_Space);  // pause
  EXPECT_EQ(StoredLabels(corpus_, "keys"), Labels{});

  EXPECT_FALSE(w->close());  // waits for the save
  EXPECT_TRUE(w->isVisible());
  ASSERT_TRUE(QTest::qWaitFor([&] { return !w->isVisible(); }, kWaitMs));
  EXPECT_EQ(StoredLabels(corpus_, "keys"), (Labels{{frame, "23"}}));
}

// A new tier typed into the Key tier box (Enter) starts an empty tier; the
// pending edits of the previous tier are saved at the switch, not lost.
TEST_F(LabelLaneTest, ANewTierTypedInTheTierBoxSavesThePreviousTiersEditsFirst) {
  auto w = OpenWindow("keys");
  w->labels()->SetAutosaveDelay(60000);  // only the switch saves
  Key(*w, Qt::Key_Home);
  Key(*w, Qt::Key_Right, Qt::ShiftModifier);
  Type(*w, "51");
  EXPECT_TRUE(w->undo_action()->isEnabled());
  QComboBox* box = w->label_tier_combo();
  box->setFocus();
  box->lineEdit()->selectAll();
  QTest::keyClicks(box->lineEdit(), "second");
  QTest::keyClick(box->lineEdit(), Qt::Key_Return);
  EXPECT_EQ(w->labels()->tier_name(), "second");
  EXPECT_EQ(w->labels()->model()->size(), 0u);
  EXPECT_EQ(w->labels()->undo_stack()->count(), 0);
  EXPECT_FALSE(w->undo_action()->isEnabled());  // the history of the tier left is gone
  ASSERT_TRUE(QTest::qWaitFor([&] { return !w->labels()->HasUnsavedEdits(); }, kWaitMs));
  EXPECT_EQ(StoredLabels(corpus_, "keys"), (Labels{{10, "51"}}));
  // The plots now draw keys, with its new label.
  EXPECT_TRUE(PlotTierLanes(*w->plots()).contains("keys"));
  EXPECT_FALSE(PlotTierLanes(*w->plots()).contains("second"));
  ASSERT_EQ(w->take()->tiers.size(), 2u);
  EXPECT_EQ(w->take()->tiers[1].name, "keys");
  EXPECT_EQ(w->take()->tiers[1].labels.size(), 1u);

  // A label on the second tier, then back to keys: its label is there, and an
  // edit of keys keeps the second tier's label in the corpus.
  Key(*w, Qt::Key_Right, Qt::ShiftModifier);  // 20
  w->label_lane()->setFocus();
  Type(*w, "02");
  ASSERT_TRUE(w->SetLabelTier("keys"));
  EXPECT_EQ(ModelLabels(*w->labels()), (Labels{{10, "51"}}));
  Key(*w, Qt::Key_Right, Qt::ShiftModifier);  // 30
  Type(*w, "03");
  w->labels()->SaveNow();
  ASSERT_TRUE(QTest::qWaitFor([&] { return !w->labels()->HasUnsavedEdits(); }, kWaitMs));
  EXPECT_EQ(StoredLabels(corpus_, "keys"), (Labels{{10, "51"}, {30, "03"}}));
  EXPECT_EQ(StoredLabels(corpus_, "second"), (Labels{{20, "02"}}));
  const Take stored = Corpus::Open(corpus_).LoadTake("alpha");
  ASSERT_EQ(stored.tiers.size(), 3u);
  EXPECT_EQ(stored.tiers[0].name, "words");
  EXPECT_EQ(stored.tiers[0].labels.size(), 2u);
}

// Autosave writes only the tiers edited in the window: a tier another writer
// (here the test, as a CLI command would) stored meanwhile stays in the corpus.
TEST_F(LabelLaneTest, ATierAnotherWriterStoredMeanwhileIsKeptByTheNextAutosave) {
  auto w = OpenWindow("keys");
  Key(*w, Qt::Key_Home);
  Key(*w, Qt::Key_Right, Qt::ShiftModifier);  // 10
  Type(*w, "14");
  ASSERT_TRUE(QTest::qWaitFor([&] { return !w->labels()->HasUnsavedEdits(); }, kWaitMs));
  {
    CorpusTransaction tx(corpus_);
    std::vector<LabelTier> tiers = Corpus::Open(corpus_).LoadTake("alpha").tiers;
    tiers.push_back({"decoded_keys", LabelTier::Kind::kPoint, 0.0, 0.5, {{0.3, 0.3, "22"}}});
    tx.WriteTiers("alpha", tiers);
    tx.Commit();
  }
  Key(*w, Qt::Key_Right, Qt::ShiftModifier);  // 20
  Type(*w, "15");
  ASSERT_TRUE(QTest::qWaitFor([&] { return !w->labels()->HasUnsavedEdits(); }, kWaitMs));
  EXPECT_EQ(StoredLabels(corpus_, "keys"), (Labels{{10, "14"}, {20, "15"}}));
  EXPECT_EQ(StoredLabels(corpus_, "decoded_keys"), (Labels{{30, "22"}}));
  const std::vector<LabelTier> tiers = Corpus::Open(corpus_).LoadTiers("alpha");
  ASSERT_EQ(tiers.size(), 3u);
  EXPECT_EQ(tiers[0].name, "words");
  EXPECT_EQ(tiers[1].name, "keys");
  EXPECT_EQ(tiers[2].name, "decoded_keys");
  // LoadTiers reads what LoadTake reads.
  const Take take = Corpus::Open(corpus_).LoadTake("alpha");
  ASSERT_EQ(take.tiers.size(), tiers.size());
  for (size_t i = 0; i < tiers.size(); ++i) {
    EXPECT_EQ(take.tiers[i].name, tiers[i].name);
    EXPECT_EQ(take.tiers[i].labels.size(), tiers[i].labels.size());
  }
}

// Guides for labelling stored with take alpha, as `csw keys suggest` and `csw cue`
// write them: suggested targets at frames 8, 19, 30 (stored 0.1 frame late, at
// 0.301 s) and 44; expected keys 13 [0, 0.10), a pause, 25 [0.18, 0.30),
// 41 [0.30, 0.42), 00 [0.42, 0.50), whose middle frames are 5, 24, 36 and 46.
void StoreGuideTiers(const std::string& corpus) {
  std::vector<LabelTier> tiers = Corpus::Open(corpus).LoadTiers("alpha");
  tiers.push_back({"keys_suggested",
                   LabelTier::Kind::kPoint,
                   0.0,
                   0.5,
                   {{0.08, 0.08, "13"}, {0.19, 0.19, "25"}, {0.301, 0.301, "41"}, {0.44, 0.44, "00"}}});
  tiers.push_back({"expected_keys",
                   LabelTier::Kind::kInterval,
                   0.0,
                   0.5,
                   {{0.0, 0.10, "13"}, {0.10, 0.18, ""}, {0.18, 0.30, "25"}, {0.30, 0.42, "41"}, {0.42, 0.50, "00"}}});
  CorpusTransaction tx(corpus);
  tx.WriteTiers("alpha", tiers);
  tx.Commit();
}

// Pixels of `colour` in the lane's columns within 6 px of time t.
int PixelsNear(LabelLane& lane, double t, QColor colour) {
  const QImage image = lane.grab().toImage();
  const int x = static_cast<int>(std::lround(lane.XOfTime(t)));
  int n = 0;
  for (int dx = -6; dx <= 6; ++dx) {
    for (int y = 0; y < image.height(); ++y) {
      if (x + dx >= 0 && x + dx < image.width() && image.pixelColor(x + dx, y).rgb() == colour.rgb()) ++n;
    }
  }
  return n;
}

// N jumps to the next suggested target with no label within 2 frames; Enter
// accepts the one on (or within 2 frames of) the cursor and moves on; one
// acceptance undone disappears; the three accepted are autosaved and found at
// the suggested frames with the suggested codes after reopening.
TEST_F(LabelLaneTest, EnterAcceptsThreeSuggestedTargetsAndNSkipsTheAccepted) {
  StoreGuideTiers(corpus_);
  auto w = OpenWindow("accepted_keys");
  LabelSession& s = *w->labels();
  ASSERT_EQ(s.suggestions().size(), 4u);
  EXPECT_EQ(s.suggestions()[2].frame, 30);  // 0.301 s is on frame 30
  EXPECT_EQ(s.model()->size(), 0u);
  const QColor open(0, 150, 70), accepted(160, 160, 160);
  EXPECT_GT(PixelsNear(*w->label_lane(), 0.08, open), 0);
  EXPECT_EQ(PixelsNear(*w->label_lane(), 0.08, accepted), 0);

  Key(*w, Qt::Key_Home);
  Key(*w, Qt::Key_N);
  EXPECT_EQ(w->playback()->frame(), 8);
  Key(*w, Qt::Key_Return);  // accepts 13 at 8, moves to 19
  EXPECT_EQ(ModelLabels(s), (Labels{{8, "13"}}));
  EXPECT_EQ(w->playback()->frame(), 19);
  EXPECT_EQ(PixelsNear(*w->label_lane(), 0.08, open), 0);
  EXPECT_GT(PixelsNear(*w->label_lane(), 0.08, accepted), 0);
  Key(*w, Qt::Key_Return);  // 25 at 19, moves to 30
  EXPECT_EQ(w->playback()->frame(), 30);
  // Two frames off the suggestion still accepts it, at its own frame.
  Key(*w, Qt::Key_Right);
  Key(*w, Qt::Key_Right);  // 32
  Key(*w, Qt::Key_Enter);  // the keypad's Enter too
  EXPECT_EQ(ModelLabels(s), (Labels{{8, "13"}, {19, "25"}, {30, "41"}}));
  EXPECT_EQ(w->playback()->frame(), 44);
  // Three frames off accepts nothing (a line in the log).
  Key(*w, Qt::Key_Left);
  Key(*w, Qt::Key_Left);
  Key(*w, Qt::Key_Left);  // 41
  const int infos = w->log()->CountLevel(LogPanel::Level::kInfo);
  Key(*w, Qt::Key_Return);
  EXPECT_EQ(s.model()->size(), 3u);
  EXPECT_EQ(w->log()->CountLevel(LogPanel::Level::kInfo), infos + 1);
  EXPECT_EQ(w->playback()->frame(), 41);
  Key(*w, Qt::Key_Right);  // 42
  Key(*w, Qt::Key_Return);
  EXPECT_EQ(ModelLabels(s), (Labels{{8, "13"}, {19, "25"}, {30, "41"}, {44, "00"}}));
  EXPECT_EQ(w->playback()->frame(), 44);  // no open suggestion left: the cursor stays
  EXPECT_EQ(s.undo_stack()->count(), 4);
  EXPECT_EQ(s.undo_stack()->undoText(), "add key 00 at 0.440 s");
  Key(*w, Qt::Key_N);
  Key(*w, Qt::Key_N, Qt::ShiftModifier);
  EXPECT_EQ(w->playback()->frame(), 44);  // every suggestion is accepted

  // The last acceptance undone: it disappears, and N finds that suggestion again.
  Key(*w, Qt::Key_Z, Qt::ControlModifier);
  const Labels three{{8, "13"}, {19, "25"}, {30, "41"}};
  EXPECT_EQ(ModelLabels(s), three);
  Key(*w, Qt::Key_Home);
  Key(*w, Qt::Key_N);
  EXPECT_EQ(w->playback()->frame(), 44);
  Key(*w, Qt::Key_N, Qt::ShiftModifier);
  EXPECT_EQ(w->playback()->frame(), 44);

  ASSERT_TRUE(QTest::qWaitFor([&] { return !s.HasUnsavedEdits(); }, kWaitMs));
  EXPECT_EQ(StoredLabels(corpus_, "accepted_keys"), three);
  for (const LabelTier& t : Corpus::Open(corpus_).LoadTiers("alpha")) {
    if (t.name == "keys_suggested") {
      EXPECT_EQ(t.labels.size(), 4u);  // the suggestions are not edited
    }
  }
  w.reset();
  auto again = OpenWindow("accepted_keys");
  EXPECT_EQ(ModelLabels(*again->labels()), three);
  Key(*again, Qt::Key_Home);
  Key(*again, Qt::Key_N);
  EXPECT_EQ(again->playback()->frame(), 44);
  EXPECT_EQ(again->log()->CountLevel(LogPanel::Level::kError), 0);
  EXPECT_EQ(again->log()->CountLevel(LogPanel::Level::kWarning), 0);
}

// E / Shift+E jump to the middle frame of the next / previous expected key with
// no label in its interval; the suggestion tier can be another one.
TEST_F(LabelLaneTest, EJumpsToTheNextExpectedKeyWithoutALabel) {
  StoreGuideTiers(corpus_);
  auto w = OpenWindow("keys");
  LabelSession& s = *w->labels();
  ASSERT_EQ(s.expected_keys().size(), 4u);  // the pause is no key
  Key(*w, Qt::Key_Home);
  Key(*w, Qt::Key_Right, Qt::ShiftModifier);
  Key(*w, Qt::Key_Right, Qt::ShiftModifier);
  for (int i = 0; i < 6; ++i) Key(*w, Qt::Key_Right);  // 26, inside 25's interval
  Type(*w, "25");
  Key(*w, Qt::Key_Home);
  std::vector<int64_t> visited;
  for (int i = 0; i < 4; ++i) {
    Key(*w, Qt::Key_E);
    visited.push_back(w->playback()->frame());
  }
  EXPECT_EQ(visited, (std::vector<int64_t>{5, 36, 46, 46}));  // 24 is labelled; after 46 none
  visited.clear();
  for (int i = 0; i < 3; ++i) {
    Key(*w, Qt::Key_E, Qt::ShiftModifier);
    visited.push_back(w->playback()->frame());
  }
  EXPECT_EQ(visited, (std::vector<int64_t>{36, 5, 5}));
  Type(*w, "13");  // on 5: its key is labelled now
  Key(*w, Qt::Key_End);
  Key(*w, Qt::Key_E, Qt::ShiftModifier);
  EXPECT_EQ(w->playback()->frame(), 46);
  Key(*w, Qt::Key_E, Qt::ShiftModifier);
  EXPECT_EQ(w->playback()->frame(), 36);
  Key(*w, Qt::Key_E, Qt::ShiftModifier);
  EXPECT_EQ(w->playback()->frame(), 36);
  // The expected keys are drawn: 41's band (unlabelled) is tinted, not the lane's plain base.
  const QImage image = w->label_lane()->grab().toImage();
  const QColor base = w->label_lane()->palette().base().color();
  const int x = static_cast<int>(std::lround(w->label_lane()->XOfTime(0.33)));
  EXPECT_NE(image.pixelColor(x, image.height() / 4).rgb(), base.rgb());
  const int x_pause = static_cast<int>(std::lround(w->label_lane()->XOfTime(0.14)));
  EXPECT_EQ(image.pixelColor(x_pause, image.height() / 4).rgb(), base.rgb());

  // Another suggestion tier: a missing one gives no suggestions, N does nothing.
  ASSERT_EQ(s.suggestions().size(), 4u);
  s.SetSuggestionTier("placement_suggested");
  EXPECT_TRUE(s.suggestions().empty());
  Key(*w, Qt::Key_Home);
  Key(*w, Qt::Key_N);
  EXPECT_EQ(w->playback()->frame(), 0);
  s.SetSuggestionTier("keys_suggested");
  Key(*w, Qt::Key_N);
  EXPECT_EQ(w->playback()->frame(), 8);
  // An interval tier of words is no suggestion tier: a warning, no suggestions.
  const int warnings = w->log()->CountLevel(LogPanel::Level::kWarning);
  s.SetSuggestionTier("words");
  EXPECT_TRUE(s.suggestions().empty());
  EXPECT_EQ(w->log()->CountLevel(LogPanel::Level::kWarning), warnings + 1);
}

// U / Shift+U jump to the first frame of the next / previous run of frames where
// the stored key posteriors (score set "keys", as `csw keys score` stores it,
// read by the take loader) have a largest value below 0.6: shape unsure on
// frames 12-14 and 33-34, placement on frame 40 (its score rows start at
// 0.002 s, so frame f is row f, rounded).
TEST_F(LabelLaneTest, UJumpsToTheNextFrameWhereTheRecogniserIsUnsure) {
  TakeScores scores;
  scores.name = "keys";
  scores.rate_hz = kRate;
  scores.start_s = 0.002;
  ScoreMatrix shape{"shape", kFrames, 3, {}, {}};
  ScoreMatrix placement{"placement", kFrames, 2, {}, {}};
  for (int f = 0; f < kFrames; ++f) {
    const bool unsure = (f >= 12 && f <= 14) || f == 33 || f == 34;
    shape.values.insert(shape.values.end(), {unsure ? 0.5 : 0.9, unsure ? 0.3 : 0.05, unsure ? 0.2 : 0.05});
    placement.values.insert(placement.values.end(), {f == 40 ? 0.55 : 0.7, f == 40 ? 0.45 : 0.3});
  }
  scores.matrices = {placement, shape};
  {
    CorpusTransaction tx(corpus_);
    tx.WriteScores("alpha", scores);
    tx.Commit();
  }
  std::vector<uint8_t> expected(kFrames, 0);
  for (int f : {12, 13, 14, 33, 34, 40}) expected[static_cast<size_t>(f)] = 1;
  EXPECT_EQ(UnsureFrames(scores, kFrames, kRate, LabelSession::kUnsurePosterior), expected);

  auto w = OpenWindow("keys");
  EXPECT_EQ(w->labels()->unsure_frames(), expected);
  Key(*w, Qt::Key_Home);
  std::vector<int64_t> visited;
  for (int i = 0; i < 4; ++i) {
    Key(*w, Qt::Key_U);
    visited.push_back(w->playback()->frame());
  }
  EXPECT_EQ(visited, (std::vector<int64_t>{12, 33, 40, 40}));
  Key(*w, Qt::Key_Left);  // 39
  visited.clear();
  for (int i = 0; i < 3; ++i) {
    Key(*w, Qt::Key_U, Qt::ShiftModifier);
    visited.push_back(w->playback()->frame());
  }
  EXPECT_EQ(visited, (std::vector<int64_t>{33, 12, 12}));
  // Drawn as a red strip under the unsure frames only.
  const QImage image = w->label_lane()->grab().toImage();
  const QColor base = w->label_lane()->palette().base().color();
  const int y = image.height() - 3;
  const auto x = [&](double t) { return static_cast<int>(std::lround(w->label_lane()->XOfTime(t))); };
  EXPECT_NE(image.pixelColor(x(0.13), y).rgb(), base.rgb());
  EXPECT_EQ(image.pixelColor(x(0.25), y).rgb(), base.rgb());
  // Another tier of the same take keeps them.
  ASSERT_TRUE(w->SetLabelTier("other"));
  EXPECT_EQ(w->labels()->unsure_frames(), expected);
}

TEST(NearestSpeedMinimum, FindsTheNearestLocalMinimumWithinTheWindow) {
  // |sin| sampled 20 frames a period: minima (zeros) at 0, 10, 20, 30.
  std::vector<float> speed;
  for (int f = 0; f < 35; ++f) speed.push_back(static_cast<float>(std::abs(std::sin(2.0 * M_PI * f / 20.0))));
  EXPECT_EQ(NearestSpeedMinimum(speed, 13, 5), 10);
  EXPECT_EQ(NearestSpeedMinimum(speed, 16, 5), 20);
  EXPECT_EQ(NearestSpeedMinimum(speed, 15, 5), 10);  // a tie goes to the earlier one
  EXPECT_EQ(NearestSpeedMinimum(speed, 20, 5), 20);
  EXPECT_EQ(NearestSpeedMinimum(speed, 15, 4), -1);  // none within 4 frames
  // A flat minimum stands at its middle; missing frames are skipped.
  const float nan = std::nanf("");
  EXPECT_EQ(NearestSpeedMinimum({5, 3, 1, 1, 1, 3, 5}, 0, 10), 3);
  EXPECT_EQ(NearestSpeedMinimum({5, 4, 3, nan, nan, 9}, 4, 10), 2);
  // A constant speed has no minimum.
  EXPECT_EQ(NearestSpeedMinimum({2, 2, 2, 2}, 1, 10), -1);
}

// S snaps the label on the cursor frame to the nearest speed minimum of the
// marker lane's marker (m1: zero speed at every 10th frame), within 0.25 s.
TEST_F(LabelLaneTest, SSnapsTheLabelToTheNearestSpeedMinimumOfTheMarkerLane) {
  auto w = OpenWindow("keys");
  LabelSession& s = *w->labels();
  w->plots()->SetMarkerSeries(1, MarkerQuantity::kSpeed);
  Key(*w, Qt::Key_Home);
  Key(*w, Qt::Key_Right, Qt::ShiftModifier);
  for (int i = 0; i < 3; ++i) Key(*w, Qt::Key_Right);  // 13
  Type(*w, "12");
  Key(*w, Qt::Key_S);
  EXPECT_EQ(w->playback()->frame(), 10);
  Key(*w, Qt::Key_Right, Qt::ShiftModifier);
  Key(*w, Qt::Key_Right, Qt::ShiftModifier);
  Key(*w, Qt::Key_Right, Qt::ShiftModifier);  // 40
  Key(*w, Qt::Key_Left);
  Key(*w, Qt::Key_Left);
  Key(*w, Qt::Key_Left);
  Key(*w, Qt::Key_Left);  // 36
  Type(*w, "34");
  Key(*w, Qt::Key_S);
  EXPECT_EQ(w->playback()->frame(), 40);
  EXPECT_EQ(ModelLabels(s), (Labels{{10, "12"}, {40, "34"}}));
  // Already on a minimum: nothing to do.
  const int commands = s.undo_stack()->count();
  Key(*w, Qt::Key_S);
  EXPECT_EQ(s.undo_stack()->count(), commands);
  // m0's constant speed has no minimum; without a marker lane there is nothing to snap to.
  Key(*w, Qt::Key_Left);
  Type(*w, "45");  // a label at 39
  w->plots()->SetMarkerSeries(0, MarkerQuantity::kSpeed);
  Key(*w, Qt::Key_S);
  w->plots()->SetMarkerSeries(-1, MarkerQuantity::kSpeed);
  const int warnings = w->log()->CountLevel(LogPanel::Level::kWarning);
  Key(*w, Qt::Key_S);
  EXPECT_EQ(w->log()->CountLevel(LogPanel::Level::kWarning), warnings + 1);
  EXPECT_EQ(ModelLabels(s), (Labels{{10, "12"}, {39, "45"}, {40, "34"}}));
  // A snap is one undoable move.
  Key(*w, Qt::Key_Delete);
  Key(*w, Qt::Key_Z, Qt::ControlModifier);
  Key(*w, Qt::Key_Z, Qt::ControlModifier);
  Key(*w, Qt::Key_Z, Qt::ControlModifier);
  EXPECT_EQ(ModelLabels(s), (Labels{{10, "12"}, {36, "34"}}));
}

// Issue 16's first "done when", on the embedded demo corpus itself
// (datasets/demo/sentences, imported as the README's main command imports it):
// on a new tier of one take, five targets typed from the keyboard, two undone,
// one redone; autosave stores four without a user action, the take's own tiers
// are kept, and a new window finds the four.
class LabelLaneDemoCorpusTest : public LabelLaneTest {
 protected:
  void SetUp() override {
    namespace fs = std::filesystem;
    const fs::path demo = testing::SourceDir() / "datasets" / "demo" / "sentences";
    ASSERT_TRUE(fs::exists(demo / "markerset.json")) << demo;
    jobs::ImportOptions o;
    for (const fs::directory_entry& e : fs::directory_iterator(demo)) {
      const std::string ext = e.path().extension().string();
      if (ext == ".c3d" || ext == ".TextGrid" || ext == ".wav") o.files.push_back(e.path().string());
    }
    ASSERT_GE(o.files.size(), 6u);
    o.markerset = (demo / "markerset.json").string();
    corpus_ = (dir_ / "demo.h5").string();
    o.corpus = corpus_;
    Progress quiet;
    const jobs::ImportResult r = jobs::Import(o, quiet);
    ASSERT_GE(r.takes.size(), 2u);
  }
};

TEST_F(LabelLaneDemoCorpusTest, FiveTargetsOnANewTierUndoTwoRedoOneAutosaveAndReopenFindFour) {
  const std::string take = "sentence_002";
  const Corpus before = Corpus::Open(corpus_);
  const std::vector<LabelTier> tiers_before = before.LoadTiers(take);
  const double rate = before.Summary(take).rate_hz;
  const int64_t last = before.Summary(take).frames - 1;
  ASSERT_GT(rate, 0.0);
  ASSERT_GT(last, 100);
  for (const LabelTier& t : tiers_before) ASSERT_NE(t.name, "my_keys");

  auto w = OpenWindow("my_keys", take);
  LabelSession& s = *w->labels();
  ASSERT_TRUE(s.has_take());
  EXPECT_EQ(s.model()->size(), 0u);  // a new tier
  Key(*w, Qt::Key_Home);
  for (int i = 0; i < 3; ++i) Key(*w, Qt::Key_Right, Qt::ShiftModifier);  // 30
  Type(*w, "15");
  Key(*w, Qt::Key_Right, Qt::ShiftModifier);
  Key(*w, Qt::Key_Right);  // 41
  Type(*w, "23");
  for (int i = 0; i < 5; ++i) Key(*w, Qt::Key_Right, Qt::ShiftModifier);  // 91
  Type(*w, "31");
  Key(*w, Qt::Key_Right, Qt::ShiftModifier);
  Key(*w, Qt::Key_Left);  // 100
  Type(*w, "00");
  Key(*w, Qt::Key_End);  // the last frame
  Type(*w, "44");
  const int end = static_cast<int>(last);
  EXPECT_EQ(ModelLabels(s), (Labels{{30, "15"}, {41, "23"}, {91, "31"}, {100, "00"}, {end, "44"}}));
  Key(*w, Qt::Key_Z, Qt::ControlModifier);
  Key(*w, Qt::Key_Z, Qt::ControlModifier);
  Key(*w, Qt::Key_Z, Qt::ControlModifier | Qt::ShiftModifier);
  const Labels four{{30, "15"}, {41, "23"}, {91, "31"}, {100, "00"}};
  EXPECT_EQ(ModelLabels(s), four);
  EXPECT_EQ(w->label_counts()->total(), 4);

  ASSERT_TRUE(QTest::qWaitFor([&] { return !s.HasUnsavedEdits(); }, kWaitMs));
  // Stored: the new point tier at exactly those frames, the take's own tiers as they were.
  const std::vector<LabelTier> tiers_after = Corpus::Open(corpus_).LoadTiers(take);
  ASSERT_EQ(tiers_after.size(), tiers_before.size() + 1);
  Labels stored;
  for (const LabelTier& t : tiers_after) {
    if (t.name != "my_keys") {
      const auto it =
          std::find_if(tiers_before.begin(), tiers_before.end(), [&](const LabelTier& b) { return b.name == t.name; });
      ASSERT_NE(it, tiers_before.end()) << t.name;
      EXPECT_EQ(t.labels.size(), it->labels.size()) << t.name;
      continue;
    }
    EXPECT_EQ(t.kind, LabelTier::Kind::kPoint);
    for (const Label& l : t.labels) {
      const double f = l.start_s * rate;
      EXPECT_NEAR(f, std::round(f), 1e-6) << l.start_s;
      stored.emplace_back(static_cast<int>(std::lround(f)), l.text);
    }
  }
  EXPECT_EQ(stored, four);
  // The other takes are untouched.
  for (const std::string other : {"sentence_001", "sentence_003"})
    EXPECT_EQ(Corpus::Open(corpus_).LoadTiers(other).size(), before.LoadTiers(other).size()) << other;

  w.reset();
  auto again = OpenWindow("my_keys", take);
  EXPECT_EQ(ModelLabels(*again->labels()), four);
  EXPECT_EQ(again->log()->CountLevel(LogPanel::Level::kError), 0);
}

// Suggested targets on the demo corpus: Analysis > Suggest Target Frames's job
// (jobs::KeysSuggest, run here directly) writes keys_suggested; N goes to the
// first and Enter accepts three in a row, each at its suggestion's frame with
// its code, and autosave stores them.
TEST_F(LabelLaneDemoCorpusTest, EnterAcceptsThreeSuggestedTargetsOfTheSuggestJob) {
  const std::string take = "sentence_002";
  jobs::KeysSuggestOptions o;
  o.corpus = corpus_;
  o.takes = {take};
  Progress quiet;
  const nlohmann::json r = jobs::KeysSuggest(o, quiet);
  ASSERT_GE(r["suggested"].get<int>(), 4) << r.dump();
  const Corpus c = Corpus::Open(corpus_);
  const double rate = c.Summary(take).rate_hz;
  Labels suggested;  // (frame, code) of the job's tier, in time order, after frame 0
  for (const LabelTier& t : c.LoadTiers(take)) {
    if (t.name != "keys_suggested") continue;
    for (const Label& l : t.labels) {
      const int frame = static_cast<int>(std::lround(l.start_s * rate));
      if (frame > 0) suggested.emplace_back(frame, l.text);
    }
  }
  std::sort(suggested.begin(), suggested.end());
  // Suggestions alone on their frame (the job may propose one speed minimum for
  // two successive keys; Enter there would accept either): the first three.
  Labels alone;
  for (size_t i = 0; i < suggested.size(); ++i) {
    const bool near_prev = i > 0 && suggested[i].first - suggested[i - 1].first <= 2;
    const bool near_next = i + 1 < suggested.size() && suggested[i + 1].first - suggested[i].first <= 2;
    if (!near_prev && !near_next) alone.push_back(suggested[i]);
  }
  ASSERT_GE(alone.size(), 3u) << ::testing::PrintToString(suggested);

  auto w = OpenWindow("accepted_keys", take);
  LabelSession& s = *w->labels();
  ASSERT_EQ(s.suggestions().size(), suggested.size());
  Key(*w, Qt::Key_Home);
  Key(*w, Qt::Key_N);
  EXPECT_EQ(w->playback()->frame(), suggested[0].first);
  const Labels three(alone.begin(), alone.begin() + 3);
  for (const auto& [frame, code] : three) {
    // N (next open suggestion) until the cursor is on it, then one Enter.
    for (int n = 0; n < 10 && w->playback()->frame() < frame; ++n) Key(*w, Qt::Key_N);
    ASSERT_EQ(w->playback()->frame(), frame) << code;
    Key(*w, Qt::Key_Return);
  }
  EXPECT_EQ(ModelLabels(s), three);
  ASSERT_TRUE(QTest::qWaitFor([&] { return !s.HasUnsavedEdits(); }, kWaitMs));
  Labels stored;
  for (const LabelTier& t : Corpus::Open(corpus_).LoadTiers(take))
    if (t.name == "accepted_keys")
      for (const Label& l : t.labels) stored.emplace_back(static_cast<int>(std::lround(l.start_s * rate)), l.text);
  EXPECT_EQ(stored, three);
}

// The demo corpus's take (the virtual cuer's first sentence): its `keys` tier
// opens in the lane mark for mark and leaves the plots; another point tier can
// be chosen; an interval tier is refused with a log line and nothing hidden.
TEST(LabelLaneDemo, TheVirtualCuersKeysTierOpensInTheLane) {
  testing::TempDir dir;
  const std::string corpus = (dir / "demo.h5").string();
  DemoTakeOptions options;
  options.audio = false;
  const Take demo = MakeDemoTake(options);
  {
    CorpusTransaction tx(corpus);
    tx.WriteTake(demo);
    tx.Commit();
  }
  const LabelTier* keys = nullptr;
  const LabelTier* placement = nullptr;
  for (const LabelTier& t : demo.tiers) {
    if (t.name == "keys") keys = &t;
    if (t.name == "placement_targets") placement = &t;
  }
  ASSERT_NE(keys, nullptr);
  ASSERT_NE(placement, nullptr);
  ASSERT_GE(keys->labels.size(), 5u);

  MainWindow w(QString::fromStdString((dir / "settings.ini").string()));
  w.playback()->SetAudioEnabled(false);
  w.resize(1200, 800);
  w.show();
  ASSERT_TRUE(OpenAndWait(&w, corpus));
  const LabelSession& s = *w.labels();
  ASSERT_TRUE(s.has_take());
  EXPECT_EQ(s.tier_name(), "keys");
  ASSERT_EQ(s.model()->size(), keys->labels.size());
  for (size_t i = 0; i < keys->labels.size(); ++i) {
    EXPECT_EQ(s.model()->at(i).text, keys->labels[i].text) << i;
    EXPECT_DOUBLE_EQ(s.model()->at(i).start_s, keys->labels[i].start_s) << i;
  }
  // The counts panel: as many rows as distinct codes (plus the total), each count as in the tier.
  EXPECT_EQ(w.label_counts()->total(), static_cast<int>(keys->labels.size()));
  std::map<std::string, int> expected;
  for (const Label& l : keys->labels) ++expected[l.text];
  EXPECT_EQ(w.label_counts()->rowCount(), static_cast<int>(expected.size()) + 1);
  for (const auto& [code, n] : expected) EXPECT_EQ(w.label_counts()->Count(QString::fromStdString(code)), n) << code;
  QStringList lanes = PlotTierLanes(*w.plots());
  EXPECT_FALSE(lanes.contains("keys"));
  EXPECT_TRUE(lanes.contains("placement_targets"));
  EXPECT_TRUE(lanes.contains("words"));

  ASSERT_TRUE(w.SetLabelTier("placement_targets"));
  EXPECT_EQ(s.model()->size(), placement->labels.size());
  lanes = PlotTierLanes(*w.plots());
  EXPECT_TRUE(lanes.contains("keys"));
  EXPECT_FALSE(lanes.contains("placement_targets"));

  const int errors = w.log()->CountLevel(LogPanel::Level::kError);
  EXPECT_FALSE(w.SetLabelTier("words"));
  EXPECT_EQ(w.log()->CountLevel(LogPanel::Level::kError), errors + 1);
  EXPECT_TRUE(w.log()->entries().back().contains("interval tier")) << w.log()->entries().back().toStdString();
  EXPECT_FALSE(s.has_take());
  EXPECT_EQ(PlotTierLanes(*w.plots()).size(), static_cast<int>(demo.tiers.size()));
}

}  // namespace
}  // namespace csw::gui
