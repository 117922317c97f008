// The GUI's demo take comes from the virtual cuer: its markers, marker set and
// tiers are the virtual cuer's, checked against the simulation's own ground
// truth (clean markers, cue keys, words), and the window shows it.
#include "workbench/gui/demo_take.h"

#include <gtest/gtest.h>

#include <QApplication>
#include <algorithm>
#include <cmath>
#include <string>
#include <vector>

#include "io/corpus/corpus.h"
#include "tests/gui/take_wait.h"
#include "tests/testing/testing.h"
#include "workbench/gui/main_window.h"
#include "workbench/gui/playback.h"

namespace csw::gui {
namespace {

// One simulation shared by the tests (espeak-ng and the cuer take ~1 s).
const SimulationResult& Demo() {
  static const SimulationResult r = SimulateDemoTake(DemoTakeOptions{});
  return r;
}

TEST(DemoTake, IsTheVirtualCuersFirstShippedSentence) {
  const SimulationResult& r = Demo();
  const Take& t = r.take;
  EXPECT_EQ(t.name, "virtual_cuer_demo");
  EXPECT_EQ(t.rate_hz, 120.0);
  EXPECT_EQ(DemoText(DemoTakeOptions{}), ShippedSentences().at(0));
  EXPECT_EQ(r.utterance.text, ShippedSentences().at(0));
  // 113 markers named as the virtual cuer names them, face first then hand.
  const VirtualCuer cuer(SimulateOptions{});
  EXPECT_EQ(t.marker_names, cuer.AllMarkerNames());
  EXPECT_EQ(t.markers.markers(), 113);
  // The demo marker set binds every marker of the take.
  const MarkerBinding b = BindMarkerSet(DemoMarkerSet(), t.marker_names, true, t.name);
  EXPECT_TRUE(b.missing.empty());
  EXPECT_EQ(DemoMarkerSet().AllMarkers().size(), 113u);
  // Audio: espeak-ng's voice after the 0.6 s lead-in of silence, inside the take.
  ASSERT_GT(t.audio.rate_hz, 0.0);
  EXPECT_EQ(t.audio.samples, r.utterance.audio.samples);
  const auto lead = static_cast<size_t>(std::llround(0.6 * t.audio.rate_hz));
  ASSERT_GT(t.audio.samples.size(), lead);
  for (size_t i = 0; i < lead; ++i) ASSERT_EQ(t.audio.samples[i], 0.0f) << i;
  EXPECT_LE(t.audio.duration_s(), t.duration_s() + 1.0 / t.rate_hz);
  // One sentence at 80 words per minute: 2-8 s of speech.
  EXPECT_GT(r.utterance.duration_s(), 2.0);
  EXPECT_LT(r.utterance.duration_s(), 8.0);
}

// Captured markers = clean markers + noise (σ 0.2 mm per coordinate): every
// visible coordinate within 6σ of the clean one, and the noise's RMS within
// 10% of 0.2 mm.
TEST(DemoTake, MarkersAreTheCleanTrajectoriesPlusCaptureNoise) {
  const SimulationResult& r = Demo();
  const Take& t = r.take;
  ASSERT_EQ(r.clean.frames(), t.frames());
  ASSERT_EQ(r.clean.markers(), t.markers.markers());
  double sum2 = 0.0;
  int64_t n = 0, visible = 0;
  for (int64_t f = 0; f < t.frames(); ++f) {
    for (int64_t m = 0; m < t.markers.markers(); ++m) {
      if (!t.markers.Visible(f, m)) continue;
      ++visible;
      for (int k = 0; k < 3; ++k) {
        const double d = static_cast<double>(t.markers.at(f, m)[k]) - static_cast<double>(r.clean.at(f, m)[k]);
        ASSERT_LT(std::abs(d), 6 * 0.2) << "frame " << f << " marker " << t.marker_names[static_cast<size_t>(m)];
        sum2 += d * d;
        ++n;
      }
    }
  }
  ASSERT_GT(n, 0);
  EXPECT_NEAR(std::sqrt(sum2 / static_cast<double>(n)), 0.2, 0.02);
  // Occlusions hide some samples, most stay visible.
  const auto total = static_cast<double>(t.frames() * t.markers.markers());
  EXPECT_LT(static_cast<double>(visible), total);
  EXPECT_GT(static_cast<double>(visible), 0.8 * total);
}

// The tiers are the ground truth's: words in order, one "keys" point per cue
// key at its shape target time, or 0.1 ms after the previous point when
// overlapping gestures put the targets out of order (points must increase).
TEST(DemoTake, TiersMatchTheGroundTruth) {
  const SimulationResult& r = Demo();
  const std::vector<LabelTier>& tiers = r.take.tiers;
  auto find = [&](const std::string& name) -> const LabelTier* {
    for (const LabelTier& t : tiers)
      if (t.name == name) return &t;
    return nullptr;
  };
  const LabelTier* words = find("words");
  ASSERT_NE(words, nullptr);
  std::vector<std::string> texts;
  for (const Label& l : words->labels)
    if (!l.text.empty()) texts.push_back(l.text);
  ASSERT_EQ(texts.size(), r.utterance.words.size());
  for (size_t i = 0; i < texts.size(); ++i) EXPECT_EQ(texts[i], r.utterance.words[i].text) << i;
  const LabelTier* keys = find("keys");
  ASSERT_NE(keys, nullptr);
  ASSERT_EQ(keys->labels.size(), r.keys.size());
  ASSERT_GE(r.keys.size(), 5u);  // rest, at least three keys, rest
  double previous = -1.0;
  for (size_t i = 0; i < r.keys.size(); ++i) {
    const double expected = std::max(r.keys[i].timing.shape_target_s, previous + 1e-4);
    EXPECT_EQ(keys->labels[i].text, r.keys[i].key.Code()) << i;
    EXPECT_NEAR(keys->labels[i].start_s, expected, 1e-12) << i;
    previous = expected;
  }
}

TEST(DemoTake, LongerDemoJoinsShippedSentencesInOrder) {
  DemoTakeOptions o;
  o.seconds = 10.0;
  const std::string text = DemoText(o);
  const std::vector<std::string> s = ShippedSentences();
  ASSERT_GE(s.size(), 3u);
  // 65 ms per character: at least 10 s / 0.065 ≈ 154 characters, sentences in file order.
  EXPECT_GE(text.size(), 154u);
  EXPECT_EQ(text.rfind(s[0] + " " + s[1], 0), 0u) << text;
}

// The window opens a corpus holding the demo take and shows all of it.
TEST(DemoTake, OpensInTheWorkbench) {
  testing::TempDir dir;
  const std::string corpus = (dir / "demo.h5").string();
  {
    CorpusTransaction tx(corpus);
    tx.WriteTake(Demo().take);
    tx.Commit();
  }
  MainWindow w(QString::fromStdString((dir / "settings.ini").string()));
  w.playback()->SetAudioEnabled(false);
  w.resize(1200, 800);
  w.show();
  ASSERT_TRUE(OpenAndWait(&w, corpus));
  ASSERT_NE(w.take(), nullptr);
  EXPECT_EQ(w.take()->name, Demo().take.name);
  EXPECT_EQ(w.take()->frames(), Demo().take.frames());
  EXPECT_EQ(w.take()->marker_names, Demo().take.marker_names);
  EXPECT_EQ(w.playback()->frames(), Demo().take.frames());
}

}  // namespace
}  // namespace csw::gui
