#include "workbench/gui/figure_export.h"

#include <qcustomplot.h>

#include <QFileInfo>
#include <QImage>
#include <QPageSize>
#include <QPainter>
#include <QPdfWriter>
#include <QSvgGenerator>

#include "core/error.h"

namespace csw::gui {

namespace {

QString Extension(const QString& path) { return QFileInfo(path).suffix().toLower(); }

void CheckFormat(const QString& path) {
  if (!FigureFormats().contains(Extension(path)))
    throw InvalidInput(path.toStdString() + ": unknown figure format (use .png, .svg or .pdf)");
}

void Fail(const QString& path, const std::string& what) { throw IoError(path.toStdString(), what); }

}  // namespace

QStringList FigureFormats() { return {"png", "svg", "pdf"}; }

void ExportFigure(QCustomPlot* plot, const QString& path, int width, int height) {
  CheckFormat(path);
  if (width <= 0) width = plot->width();
  if (height <= 0) height = plot->height();
  QString ext = Extension(path);
  bool ok = false;
  if (ext == "png") {
    ok = plot->savePng(path, width, height);
  } else if (ext == "pdf") {
    ok = plot->savePdf(path, width, height);
  } else {
    QSvgGenerator svg;
    svg.setFileName(path);
    svg.setSize(QSize(width, height));
    svg.setViewBox(QRect(0, 0, width, height));
    svg.setTitle(QStringLiteral("csw-workbench figure"));
    QCPPainter painter;
    ok = painter.begin(&svg);
    if (ok) {
      plot->toPainter(&painter, width, height);
      ok = painter.end();
    }
    ok = ok && QFileInfo(path).size() > 0;
  }
  if (!ok) Fail(path, "could not write the figure");
}

void ExportPainted(const std::function<void(QPainter&, QSize)>& render, QSize size, const QString& path) {
  CheckFormat(path);
  QString ext = Extension(path);
  bool ok = false;
  if (ext == "png") {
    QImage image(size, QImage::Format_ARGB32_Premultiplied);
    image.fill(Qt::white);
    {
      QPainter painter(&image);
      render(painter, size);
    }
    ok = image.save(path, "PNG");
  } else if (ext == "svg") {
    QSvgGenerator svg;
    svg.setFileName(path);
    svg.setSize(size);
    svg.setViewBox(QRect(QPoint(0, 0), size));
    QPainter painter;
    ok = painter.begin(&svg);
    if (ok) {
      render(painter, size);
      ok = painter.end();
    }
  } else {
    QPdfWriter pdf(path);
    pdf.setResolution(96);
    pdf.setPageSize(QPageSize(QSizeF(size), QPageSize::Point));
    pdf.setPageMargins(QMarginsF(0, 0, 0, 0));
    QPainter painter;
    ok = painter.begin(&pdf);
    if (ok) {
      // The page is in points at 96 dpi device pixels: scale so the widget fills it.
      double sx = pdf.width() / static_cast<double>(size.width());
      double sy = pdf.height() / static_cast<double>(size.height());
      painter.scale(sx, sy);
      render(painter, size);
      ok = painter.end();
    }
  }
  if (!ok || QFileInfo(path).size() == 0) Fail(path, "could not write the figure");
}

}  // namespace csw::gui
