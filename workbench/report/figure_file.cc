#include "workbench/report/figure_file.h"

#include <qcustomplot.h>
#include <unistd.h>

#include <QFile>
#include <QFileInfo>
#include <QImage>
#include <QPageSize>
#include <QPainter>
#include <QPdfWriter>
#include <QSvgGenerator>
#include <atomic>
#include <filesystem>
#include <system_error>

#include "core/error.h"
#include "core/file_util.h"

namespace csw::report {

namespace {

std::string Std(const QString& s) { return s.toStdString(); }

// A file next to the destination, written first and renamed over it at the end;
// removed again when anything fails.
class PartFile {
 public:
  explicit PartFile(const QString& path) : path_(path) {
    QFileInfo info(path);
    QFileInfo dir(info.absolutePath());
    if (!dir.exists())
      throw IoError(Std(path), "cannot write the figure: folder " + Std(dir.filePath()) + " does not exist");
    if (!dir.isDir()) throw IoError(Std(path), "cannot write the figure: " + Std(dir.filePath()) + " is not a folder");
    static std::atomic<int> counter{0};
    part_ = info.absolutePath() + "/." + info.completeBaseName() + ".part" + QString::number(::getpid()) + "-" +
            QString::number(counter++) + "." + info.suffix();
    // Opened once here so that an unwritable folder is reported with the
    // system's reason; the file gets the usual permissions (umask), unlike a QTemporaryFile.
    QFile probe(part_);
    if (!probe.open(QIODevice::WriteOnly | QIODevice::Truncate))
      throw IoError(Std(path), "cannot write the figure: " + Std(probe.errorString()));
    probe.close();
  }
  ~PartFile() {
    if (!committed_) {
      std::error_code ec;
      std::filesystem::remove(part_.toStdString(), ec);
    }
  }
  PartFile(const PartFile&) = delete;
  PartFile& operator=(const PartFile&) = delete;

  const QString& name() const { return part_; }

  // ok: whether the writer reported success.
  void Commit(bool ok) {
    if (!ok || QFileInfo(part_).size() == 0) throw IoError(Std(path_), "could not write the figure");
    ReplaceFileDurably(part_.toStdString(), Std(path_));
    committed_ = true;
  }

 private:
  QString path_;
  QString part_;
  bool committed_ = false;
};

}  // namespace

QStringList FigureFormats() { return {"png", "svg", "pdf"}; }

QString FigureFormat(const QString& path) {
  QString ext = QFileInfo(path).suffix().toLower();
  if (!FigureFormats().contains(ext))
    throw InvalidInput(Std(path) + ": unknown figure format (use .png, .svg or .pdf)");
  return ext;
}

void SavePlot(QCustomPlot& plot, const QString& path, int width, int height) {
  QString ext = FigureFormat(path);
  if (width <= 0) width = plot.width();
  if (height <= 0) height = plot.height();
  PartFile part(path);
  bool ok = false;
  if (ext == "png") {
    ok = plot.savePng(part.name(), width, height);
  } else if (ext == "pdf") {
    ok = plot.savePdf(part.name(), width, height);
  } else {
    QSvgGenerator svg;
    svg.setFileName(part.name());
    svg.setSize(QSize(width, height));
    svg.setViewBox(QRect(0, 0, width, height));
    // Fonts are laid out at the screen's resolution: draw them at the same one
    // (QSvgGenerator's default of 72 dpi would shrink every label).
    svg.setResolution(plot.logicalDpiX());
    svg.setTitle(QStringLiteral("csw figure"));
    QCPPainter painter;
    ok = painter.begin(&svg);
    if (ok) {
      plot.toPainter(&painter, width, height);
      ok = painter.end();
    }
  }
  part.Commit(ok);
}

void SavePainted(const std::function<void(QPainter&, QSize)>& render, QSize size, const QString& path) {
  QString ext = FigureFormat(path);
  PartFile part(path);
  bool ok = false;
  if (ext == "png") {
    QImage image(size, QImage::Format_ARGB32_Premultiplied);
    image.fill(Qt::white);
    {
      QPainter painter(&image);
      render(painter, size);
    }
    ok = image.save(part.name(), "PNG");
  } else if (ext == "svg") {
    QSvgGenerator svg;
    svg.setFileName(part.name());
    svg.setSize(size);
    svg.setViewBox(QRect(QPoint(0, 0), size));
    svg.setResolution(96);
    QPainter painter;
    ok = painter.begin(&svg);
    if (ok) {
      render(painter, size);
      ok = painter.end();
    }
  } else {
    QPdfWriter pdf(part.name());
    pdf.setResolution(96);
    pdf.setPageSize(QPageSize(QSizeF(size), QPageSize::Point));
    pdf.setPageMargins(QMarginsF(0, 0, 0, 0));
    QPainter painter;
    ok = painter.begin(&pdf);
    if (ok) {
      // The page is in points at 96 dpi device pixels: scale so the drawing fills it.
      double sx = pdf.width() / static_cast<double>(size.width());
      double sy = pdf.height() / static_cast<double>(size.height());
      painter.scale(sx, sy);
      render(painter, size);
      ok = painter.end();
    }
  }
  part.Commit(ok);
}

}  // namespace csw::report
