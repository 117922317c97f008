// csw-workbench [CORPUS.h5]: the Cued Speech Workbench's desktop viewer.
#include <QApplication>
#include <QCommandLineParser>
#include <QDir>
#include <cstdio>

#include "workbench/gui/main_window.h"
#include "workbench/gui/tour.h"

int main(int argc, char** argv) {
  QApplication app(argc, argv);
  QApplication::setOrganizationName("csw");
  QApplication::setApplicationName("csw-workbench");
  QApplication::setApplicationVersion(CSW_VERSION);

  QCommandLineParser parser;
  parser.setApplicationDescription("Cued Speech Workbench: corpus browser, 3D markers and synchronised plots.");
  parser.addHelpOption();
  parser.addVersionOption();
  parser.addPositionalArgument("corpus", "Corpus (.h5) to open.", "[CORPUS.h5]");
  QCommandLineOption tour(QStringLiteral("tour"), "Run the screenshot tour, writing PNGs into DIR, then exit.", "DIR");
  QCommandLineOption tour_work(QStringLiteral("tour-work"), "Scratch folder for the tour's demo corpus.", "DIR");
  QCommandLineOption tour_capture(QStringLiteral("tour-capture"), "A real capture the tour imports (repeatable).",
                                  "FILE");
  QCommandLineOption tour_markerset(QStringLiteral("tour-markerset"), "Marker set for the tour's captures.", "JSON");
  parser.addOptions({tour, tour_work, tour_capture, tour_markerset});
  parser.process(app);

  if (parser.isSet(tour)) {
    csw::gui::TourOptions options;
    options.out_dir = parser.value(tour);
    options.work_dir = parser.isSet(tour_work) ? parser.value(tour_work) : QDir::temp().filePath("csw-tour");
    options.captures = parser.values(tour_capture);
    options.markerset = parser.value(tour_markerset);
    try {
      for (const QString& path : csw::gui::RunTour(options)) std::printf("%s\n", qPrintable(path));
    } catch (const std::exception& e) {
      std::fprintf(stderr, "csw-workbench: tour failed: %s\n", e.what());
      return 2;
    }
    return 0;
  }

  csw::gui::MainWindow window;
  window.show();
  const QStringList args = parser.positionalArguments();
  if (!args.isEmpty()) window.OpenCorpus(args.front());
  return app.exec();
}
