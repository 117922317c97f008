#pragma once
// The scripted screenshot tour (scripts/tour.sh): builds a demo corpus (the
// synthetic cued-speech take, plus any real captures given, imported through
// the same background import job as File > Import), drives the main window
// through its views and writes PNG screenshots for docs/user-guide.md.
#include <QString>
#include <QStringList>

namespace csw::gui {

struct TourOptions {
  QString out_dir;       // screenshots are written here
  QString work_dir;      // demo corpus and scratch files
  QStringList captures;  // captures (+ their .TextGrid/.wav) to import, e.g. the demo corpus
  QString markerset;     // marker-set JSON drawn with the imported captures (optional)
  QString damaged_file;  // a damaged or foreign file to open (optional; one is made when empty)
};

// Returns the paths written; throws csw::Error when a step fails.
QStringList RunTour(const TourOptions& options);

}  // namespace csw::gui
