#pragma once
// The gestural score under the time-series panel (issue 16, item 4): the key
// posteriors a take stores (score set "keys" of `csw keys score`: matrices
// "shape", frames × 9, and "placement", frames × 6) as two lanes of one curve
// per class, and below them the decoded keys (tier "keys_decoded") and the
// expected keys ("expected_keys" of `csw cue`, else "keys_aligned" of
// `csw keys score`) as labelled intervals / points. The lanes share the panel's
// time axis and playback cursor (the window forwards both); a click asks for a
// seek. Each lane is its own QCustomPlot, so that it exports alone as PNG, SVG
// or PDF (ExportLane). The scores are read by the window's take loader (never
// on the GUI thread) and handed over with the take.
#include <QWidget>
#include <optional>
#include <vector>

#include "core/take.h"
#include "io/corpus/corpus.h"

class QCustomPlot;
class QCPItemStraightLine;
class QCPItemText;

namespace csw::gui {

class ScoreLanes : public QWidget {
  Q_OBJECT

 public:
  // The score set and its matrices shown.
  static constexpr const char* kScoreSet = "keys";
  static constexpr const char* kShapeMatrix = "shape";
  static constexpr const char* kPlacementMatrix = "placement";
  static constexpr const char* kDecodedTier = "keys_decoded";
  // The first of these a take has is drawn as its expected keys.
  static std::vector<std::string> ExpectedTierNames() { return {"expected_keys", "keys_aligned"}; }

  enum Lane { kShapeLane = 0, kPlacementLane = 1, kTierLane = 2, kLaneCount = 3 };

  explicit ScoreLanes(QWidget* parent = nullptr);

  // Lines the lanes' left and right edges up with the first axis rectangle of `plot`.
  void AlignWith(QCustomPlot* plot);
  // Shows `scores` (a "keys" set; nullopt = none) of a take whose tiers are
  // `tiers`, lasting `duration_s`. Keeps nothing of the previous take.
  void SetTake(std::optional<TakeScores> scores, const std::vector<LabelTier>& tiers, double duration_s);
  // New tiers of the same take (label edits elsewhere); the view and the cursor stay.
  void SetTiers(const std::vector<LabelTier>& tiers);

  bool has_scores() const { return scores_.has_value(); }
  const std::optional<TakeScores>& scores() const { return scores_; }
  // Names of the tiers drawn as decoded / expected keys ("" = none).
  const QString& decoded_tier() const { return decoded_name_; }
  const QString& expected_tier() const { return expected_name_; }

  // Introspection (tests): the plot of a lane, its number of class curves, the
  // value plotted for `cls` at score row `row` (NaN when there is none), the
  // time of that row.
  QCustomPlot* lane_plot(int lane) const { return plots_[static_cast<size_t>(lane)]; }
  int ClassCount(int lane) const;
  double PlottedValue(int lane, int cls, int64_t row) const;
  double PlottedTime(int lane, int64_t row) const;
  double view_start() const { return t0_; }
  double view_end() const { return t1_; }
  double cursor_time() const { return cursor_t_; }
  // The lane's cursor readout ("shape: 3 (p = 0.97)").
  QString Readout(int lane) const;
  // The labels drawn in the tier lane: row 0 decoded, row 1 expected.
  std::vector<Label> TierLabels(int row) const;

  // Saves one lane (time axis and legend included) as PNG, SVG or PDF.
  // Throws csw::Error as ExportFigure does.
  void ExportLane(int lane, const QString& path, int width = 0, int height = 0);

 public slots:
  void SetTimeRange(double t0, double t1);
  void SetCursorTime(double t);

 signals:
  // The user clicked a time in a lane (seek request).
  void TimeClicked(double t);

 private:
  void Rebuild();
  void BuildPosteriorLane(int lane, const ScoreMatrix* matrix, const QString& title);
  void BuildTierLane();
  void UpdateCursor();
  void UpdateMargins();
  const ScoreMatrix* Matrix(const char* name) const;

  std::vector<QCustomPlot*> plots_;
  std::vector<QCPItemStraightLine*> cursors_;
  std::vector<QCPItemText*> readouts_;
  QCustomPlot* align_ = nullptr;
  std::optional<TakeScores> scores_;
  LabelTier decoded_;
  LabelTier expected_;
  QString decoded_name_;
  QString expected_name_;
  double duration_s_ = 0.0;
  double t0_ = 0.0;
  double t1_ = 1.0;
  double cursor_t_ = 0.0;
  QPointF press_pos_;
};

}  // namespace csw::gui
