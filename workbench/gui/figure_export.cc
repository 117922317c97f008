#include "workbench/gui/figure_export.h"

#include <QSize>

#include "workbench/report/figure_file.h"

// The file writing (formats, temporary file renamed into place, errors) is
// shared with the CLI's report figures in workbench/report.
namespace csw::gui {

QStringList FigureFormats() { return report::FigureFormats(); }

void ExportFigure(QCustomPlot* plot, const QString& path, int width, int height) {
  report::SavePlot(*plot, path, width, height);
}

void ExportPainted(const std::function<void(QPainter&, QSize)>& render, QSize size, const QString& path) {
  report::SavePainted(render, size, path);
}

}  // namespace csw::gui
