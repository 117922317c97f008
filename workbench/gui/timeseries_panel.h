#pragma once
// The time-series panel: lanes stacked on one shared time axis (QCustomPlot):
// the audio waveform, one lane per label tier (intervals or points), the
// capture's events, and any chosen marker coordinate or speed. All lanes share
// zoom, pan and the playback cursor; long series are decimated for display only.
#include <QWidget>
#include <memory>
#include <vector>

#include "core/take.h"
#include "workbench/gui/minmax.h"

class QCustomPlot;
class QCPAxisRect;
class QCPGraph;
class QCPItemStraightLine;
class QCPItemText;
class QCPRange;
class QCPMarginGroup;

namespace csw::gui {

class TierPlottable;

enum class MarkerQuantity { kX, kY, kZ, kSpeed };
QString QuantityName(MarkerQuantity q);

// Per-frame values of one marker quantity (mm, or mm/s for speed); NaN where missing.
// Speed is the central difference of positions (one-sided at the ends).
std::vector<float> MarkerSeries(const Take& take, int marker, MarkerQuantity q);

class TimeSeriesPanel : public QWidget {
  Q_OBJECT

 public:
  enum class LaneKind { kAudio, kTier, kEvents, kMarker };

  explicit TimeSeriesPanel(QWidget* parent = nullptr);
  ~TimeSeriesPanel() override;

  // Shows a take's audio and tiers (nullptr clears); the view spans the take.
  void SetTake(std::shared_ptr<const Take> take);
  // Series prepared off the GUI thread for a take about to be shown (their
  // costs grow with the take: ~10 M audio samples for 10 minutes at 16 kHz).
  struct Prepared {
    std::shared_ptr<const MinMaxPyramid> audio;  // AudioSeries(take)
    int marker = -1;                             // a marker lane's series, when series is set
    MarkerQuantity quantity = MarkerQuantity::kZ;
    std::shared_ptr<const MinMaxPyramid> series;  // MarkerLaneSeries(take, marker, quantity)
  };
  // The same, with the take's series prepared (any thread) by the functions
  // below; a prepared marker series shows its marker lane at once.
  void SetTake(std::shared_ptr<const Take> take, Prepared prepared);
  // The series shown now (to show the same take again, e.g. with other tiers).
  Prepared Shown() const;
  // The audio lane's series (channels averaged); null without audio.
  static std::shared_ptr<const MinMaxPyramid> AudioSeries(const Take& take);
  // A marker lane's series.
  static std::shared_ptr<const MinMaxPyramid> MarkerLaneSeries(const Take& take, int marker, MarkerQuantity q);
  // Adds (or replaces) the marker lane; marker < 0 removes it.
  void SetMarkerSeries(int marker, MarkerQuantity quantity);
  int marker() const { return marker_; }
  // A tier not drawn as a lane (the key tier the label lane edits); "" = none.
  // Keeps the view and the cursor.
  void SetHiddenTier(const QString& name);
  const QString& hidden_tier() const { return hidden_tier_; }
  MarkerQuantity quantity() const { return quantity_; }

  // The playback cursor (seconds); keeps the cursor inside the visible range.
  void SetCursorTime(double t);
  double cursor_time() const { return cursor_t_; }

  // Shared time axis.
  double view_start() const;
  double view_end() const;
  void SetTimeRange(double t0, double t1);
  void ZoomTime(double factor, double center_t);  // factor < 1 zooms in
  void ShowAll();

  // Introspection (tests, tour, benchmarks).
  QCustomPlot* plot() const { return plot_; }
  int lane_count() const { return static_cast<int>(lanes_.size()); }
  LaneKind lane_kind(int lane) const;
  QString lane_name(int lane) const;
  double LaneViewStart(int lane) const;
  double LaneViewEnd(int lane) const;
  double LaneCursorTime(int lane) const;
  QString LaneReadout(int lane) const;
  int LanePointCount(int lane) const;  // points currently plotted (after decimation)

 signals:
  // The user clicked a time in the plots (seek request).
  void TimeClicked(double t);
  void TimeRangeChanged(double t0, double t1);

 protected:
  void resizeEvent(QResizeEvent* event) override;

 private:
  struct Lane {
    LaneKind kind;
    QString name;
    QString unit;
    QCPAxisRect* rect = nullptr;
    QCPGraph* graph = nullptr;                    // audio and marker lanes
    TierPlottable* tier = nullptr;                // tier and event lanes
    std::shared_ptr<const MinMaxPyramid> series;  // audio and marker lanes
    QCPItemStraightLine* cursor = nullptr;
    QCPItemText* readout = nullptr;
  };

  void Rebuild();
  Lane& AddLane(LaneKind kind, const QString& name, double stretch);
  void OnRangeChanged(const QCPRange& range);
  void Redecimate();
  void UpdateCursor();
  QString ReadoutText(const Lane& lane) const;

  QCustomPlot* plot_ = nullptr;
  QCPMarginGroup* margins_ = nullptr;
  std::shared_ptr<const Take> take_;
  std::shared_ptr<const MinMaxPyramid> audio_;  // the take's audio (channels averaged)
  Prepared prepared_;                           // a marker series prepared with the take
  std::vector<std::unique_ptr<Lane>> lanes_;
  int marker_ = -1;
  QString hidden_tier_;
  MarkerQuantity quantity_ = MarkerQuantity::kZ;
  double cursor_t_ = 0.0;
  double duration_s_ = 0.0;
  bool syncing_ = false;
  QPointF press_pos_;
};

}  // namespace csw::gui
