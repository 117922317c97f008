#pragma once
// Figures: any plot (or the 3D view) saved as PNG, SVG or PDF, chosen by the
// file's extension (written by workbench/report/figure_file.h: under a temporary
// name, renamed into place). Throws csw::IoError naming the file when writing fails and
// csw::InvalidInput for an unknown extension.
#include <QString>
#include <functional>

class QCustomPlot;
class QPainter;
class QSize;

namespace csw::gui {

// The extensions ExportFigure understands ("png", "svg", "pdf").
QStringList FigureFormats();

// Saves a QCustomPlot at width × height pixels (0 = its current size).
void ExportFigure(QCustomPlot* plot, const QString& path, int width = 0, int height = 0);

// Saves anything that renders itself with a QPainter (the 3D view).
void ExportPainted(const std::function<void(QPainter&, QSize)>& render, QSize size, const QString& path);

}  // namespace csw::gui
