#pragma once
// Writing a drawing to a figure file: PNG, SVG or PDF, chosen by the file's
// extension. Shared by csw-workbench's "Export figure" and the CLI's reports.
// The file is written next to its destination under a temporary name and
// renamed over it once complete, so a failed write never leaves half a figure.
// Throws csw::InvalidInput naming the path for an unknown extension and
// csw::IoError naming the path when the file cannot be written.
// Needs a QApplication (EnsureGuiApplication in report.h) and the GUI thread.
#include <QString>
#include <QStringList>
#include <functional>

class QCustomPlot;
class QPainter;
class QSize;

namespace csw::report {

// The extensions understood, lower case: "png", "svg", "pdf".
QStringList FigureFormats();

// The lower-case extension of path; InvalidInput when it is not one of FigureFormats().
QString FigureFormat(const QString& path);

// Saves a QCustomPlot laid out at width × height pixels (0 = its current size).
void SavePlot(QCustomPlot& plot, const QString& path, int width = 0, int height = 0);

// Saves anything that renders itself with a QPainter into a size.width ×
// size.height rectangle (white background for PNG).
void SavePainted(const std::function<void(QPainter&, QSize)>& render, QSize size, const QString& path);

}  // namespace csw::report
