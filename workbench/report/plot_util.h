#pragma once
// Drawing helpers shared by the report figures (report.cc, analysis_figures.cc):
// a QCustomPlot canvas drawn only into files, fonts, the title/legend header,
// axis styling and category ticks. Internal to csw_report.
#include <qcustomplot.h>

#include <QApplication>
#include <QFontMetrics>
#include <algorithm>
#include <cmath>
#include <string>
#include <vector>

#include "core/error.h"
#include "workbench/report/figure_file.h"
#include "workbench/report/report.h"

namespace csw::report::plot_util {

inline QColor Colour(Rgb c) { return QColor(c.r, c.g, c.b); }
inline QString Q(const std::string& s) { return QString::fromStdString(s); }

// A QCustomPlot drawn only into files: laid out at the figure's size so that
// ranges depending on pixel sizes (equal aspect) can be set before saving.
class Canvas : public QCustomPlot {
 public:
  Canvas(int width, int height) : width_(width), height_(height) {
    resize(width, height);
    setViewport(QRect(0, 0, width, height));
    QFont f = font();
    f.setPointSizeF(10);
    setFont(f);
  }
  void Layout() {
    setViewport(QRect(0, 0, width_, height_));
    updateLayout();
  }
  void Save(const std::string& path) { SavePlot(*this, Q(path), width_, height_); }

 private:
  int width_, height_;
};

inline QFont Font(double points, bool bold = false) {
  QFont f = QApplication::font();
  f.setPointSizeF(points);
  f.setBold(bold);
  return f;
}

// Row 0: the title; row 1: the legend, its items side by side; below: the rest.
inline void AddHeader(QCustomPlot& plot, const std::string& title, QCPLegend* legend) {
  plot.plotLayout()->insertRow(0);
  plot.plotLayout()->addElement(0, 0, new QCPTextElement(&plot, Q(title), Font(14, true)));
  if (legend == nullptr) return;
  if (legend->layout() != nullptr) legend->layout()->take(legend);
  // Centred at its natural width: empty elements either side take the rest of the row.
  auto* row = new QCPLayoutGrid;
  plot.plotLayout()->insertRow(1);
  plot.plotLayout()->addElement(1, 0, row);
  plot.plotLayout()->setRowStretchFactor(1, 0.001);
  row->addElement(0, 0, new QCPLayoutElement(&plot));
  row->addElement(0, 1, legend);
  row->addElement(0, 2, new QCPLayoutElement(&plot));
  row->setColumnStretchFactors({1, 0.001, 1});
  legend->setVisible(true);
  legend->setFillOrder(QCPLayoutGrid::foColumnsFirst);
  legend->setBorderPen(Qt::NoPen);
  legend->setBrush(Qt::NoBrush);
  legend->setFont(Font(10));
  legend->setColumnSpacing(24);
  legend->setMargins(QMargins(6, 0, 6, 0));
}

inline void StyleAxes(QCPAxisRect* rect) {
  for (QCPAxis* axis : rect->axes()) {
    axis->setTickLabelFont(Font(9));
    axis->setLabelFont(Font(10));
    axis->grid()->setPen(QPen(QColor(225, 225, 225), 1, Qt::SolidLine));
    axis->grid()->setZeroLinePen(Qt::NoPen);
  }
}

// Category labels under bars at 0, 1, ... n−1: horizontal when they fit,
// rotated when not, and only every k-th one when even rotated ones would overlap.
inline void SetCategoryTicks(QCPAxis* axis, const std::vector<QString>& labels, int available_px) {
  QFontMetrics fm(axis->tickLabelFont());
  int widest = 0;
  for (const QString& l : labels) widest = std::max(widest, fm.horizontalAdvance(l));
  int n = static_cast<int>(labels.size());
  double slot = available_px / static_cast<double>(std::max(n, 1));
  int step = 1;
  if (widest + 10 > slot) {
    axis->setTickLabelRotation(-60);
    // Rotated labels need about 1.2 line heights each along the axis.
    double need = fm.height() * 1.2;
    step = std::max(1, static_cast<int>(std::ceil(need / slot)));
  }
  auto ticker = QSharedPointer<QCPAxisTickerText>::create();
  for (int i = 0; i < n; i += step) ticker->addTick(i, labels[static_cast<size_t>(i)]);
  axis->setTicker(ticker);
  axis->setTickLength(0, 3);
  axis->setSubTicks(false);
  axis->grid()->setVisible(false);
  axis->setRange(-0.6, n - 0.4);
}

inline QString Elide(const std::string& s, const QFont& font) {
  return QFontMetrics(font).elidedText(Q(s), Qt::ElideMiddle, 180);
}

inline void CheckFinite(double v, bool allow_negative, const std::string& what) {
  if (!std::isfinite(v) || (!allow_negative && v < 0)) throw InvalidInput(what);
}

}  // namespace csw::report::plot_util
