#pragma once
// The corpus browser: one row per take with its duration, rate, frames,
// marker count, gap count, tiers and audio.
#include <QTreeWidget>
#include <vector>

#include "io/corpus/corpus.h"

namespace csw::gui {

class CorpusBrowser : public QTreeWidget {
  Q_OBJECT

 public:
  enum Column { kName, kDuration, kRate, kFrames, kMarkers, kGaps, kTiers, kAudio, kColumnCount };
  explicit CorpusBrowser(QWidget* parent = nullptr);

  void SetTakes(const std::vector<TakeSummary>& takes);
  // Makes a take current (emits TakeSelected); false when there is no such take.
  bool SelectTake(const QString& name);
  QString current_take() const;
  int take_count() const { return topLevelItemCount(); }
  // The text shown in one cell (tests, tour).
  QString Cell(int row, Column column) const;

 signals:
  void TakeSelected(const QString& name);
};

// "m:ss.s" for the browser's duration column.
QString FormatDuration(double seconds);

}  // namespace csw::gui
