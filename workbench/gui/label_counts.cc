#include "workbench/gui/label_counts.h"

#include <QHeaderView>
#include <map>

#include "core/labels.h"

namespace csw::gui {

LabelCountsPanel::LabelCountsPanel(QWidget* parent) : QTableWidget(0, 2, parent) {
  setObjectName("labelCounts");
  setHorizontalHeaderLabels({tr("Key"), tr("Count")});
  verticalHeader()->setVisible(false);
  verticalHeader()->setDefaultSectionSize(fontMetrics().height() + 4);
  horizontalHeader()->setStretchLastSection(true);
  setEditTriggers(QAbstractItemView::NoEditTriggers);
  setSelectionMode(QAbstractItemView::NoSelection);
  setFocusPolicy(Qt::NoFocus);
}

void LabelCountsPanel::Refresh(const LabelModel* model) {
  std::map<std::string, int> counts;  // code order
  total_ = 0;
  if (model != nullptr) {
    for (size_t i = 0; i < model->size(); ++i) {
      ++counts[model->at(i).text];
      ++total_;
    }
  }
  setRowCount(static_cast<int>(counts.size()) + 1);
  int row = 0;
  for (const auto& [code, n] : counts) {
    setItem(row, 0, new QTableWidgetItem(QString::fromStdString(code)));
    auto* count = new QTableWidgetItem(QString::number(n));
    count->setTextAlignment(Qt::AlignRight | Qt::AlignVCenter);
    setItem(row, 1, count);
    ++row;
  }
  auto* label = new QTableWidgetItem(tr("all"));
  QFont bold = label->font();
  bold.setBold(true);
  label->setFont(bold);
  setItem(row, 0, label);
  auto* count = new QTableWidgetItem(QString::number(total_));
  count->setTextAlignment(Qt::AlignRight | Qt::AlignVCenter);
  count->setFont(bold);
  setItem(row, 1, count);
}

int LabelCountsPanel::Count(const QString& code) const {
  for (int row = 0; row + 1 < rowCount(); ++row) {
    if (item(row, 0) != nullptr && item(row, 0)->text() == code) return item(row, 1)->text().toInt();
  }
  return 0;
}

}  // namespace csw::gui
