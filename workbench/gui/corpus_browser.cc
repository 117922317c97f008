#include "workbench/gui/corpus_browser.h"

#include <QHeaderView>
#include <cmath>

namespace csw::gui {

QString FormatDuration(double seconds) {
  if (!(seconds >= 0)) seconds = 0;
  int minutes = static_cast<int>(seconds / 60);
  double rest = seconds - minutes * 60.0;
  return QStringLiteral("%1:%2").arg(minutes).arg(rest, 4, 'f', 1, QChar('0'));
}

CorpusBrowser::CorpusBrowser(QWidget* parent) : QTreeWidget(parent) {
  setObjectName("corpusBrowser");
  setColumnCount(kColumnCount);
  setHeaderLabels(
      {tr("Take"), tr("Duration"), tr("Rate (Hz)"), tr("Frames"), tr("Markers"), tr("Gaps"), tr("Tiers"), tr("Audio")});
  setRootIsDecorated(false);
  setUniformRowHeights(true);
  setAlternatingRowColors(true);
  setSortingEnabled(true);
  sortByColumn(kName, Qt::AscendingOrder);
  header()->setSectionResizeMode(QHeaderView::ResizeToContents);
  connect(this, &QTreeWidget::currentItemChanged, this, [this](QTreeWidgetItem* item, QTreeWidgetItem*) {
    if (item != nullptr) emit TakeSelected(item->text(kName));
  });
}

void CorpusBrowser::SetTakes(const std::vector<TakeSummary>& takes) {
  blockSignals(true);
  clear();
  for (const TakeSummary& t : takes) {
    auto* item = new QTreeWidgetItem(this);
    QStringList tiers;
    for (const auto& n : t.tier_names) tiers << QString::fromStdString(n);
    item->setText(kName, QString::fromStdString(t.name));
    item->setText(kDuration, FormatDuration(t.duration_s));
    item->setText(kRate, QString::number(t.rate_hz, 'g', 6));
    item->setText(kFrames, QString::number(t.frames));
    item->setText(kMarkers, QString::number(t.markers));
    item->setText(kGaps, QString::number(t.gaps));
    item->setText(kTiers, tiers.isEmpty() ? QStringLiteral("—") : tiers.join(", "));
    item->setText(kAudio, t.has_audio ? tr("yes") : tr("no"));
    for (int c : {kDuration, kRate, kFrames, kMarkers, kGaps})
      item->setTextAlignment(c, Qt::AlignRight | Qt::AlignVCenter);
    item->setToolTip(kName, tr("%1 analog channel(s)").arg(t.analog_channels));
  }
  blockSignals(false);
}

bool CorpusBrowser::SelectTake(const QString& name) {
  auto found = findItems(name, Qt::MatchExactly, kName);
  if (found.isEmpty()) return false;
  if (currentItem() == found.front()) {
    emit TakeSelected(name);
  } else {
    setCurrentItem(found.front());
  }
  return true;
}

QString CorpusBrowser::current_take() const { return currentItem() ? currentItem()->text(kName) : QString(); }

QString CorpusBrowser::Cell(int row, Column column) const {
  QTreeWidgetItem* item = topLevelItem(row);
  return item ? item->text(column) : QString();
}

}  // namespace csw::gui
