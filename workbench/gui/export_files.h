#pragma once
// File > Export (issue 16, item 6): the label tiers of the shown take to
// TextGrid or EAF, and a models / key-recogniser / dictionary file copied to a
// chosen path with a summary of what it holds (the facts `csw inspect` prints
// for a model file, plus the key recogniser's classes and a dictionary's
// units). Reading and writing run on a worker thread (JobRunner); the outcome
// is a signal, and a file's summary shows in a dialog that does not block.
#include <QObject>
#include <QString>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "core/progress.h"
#include "core/take.h"

class QMessageBox;
class QWidget;

namespace csw::gui {

class JobRunner;
class LabelSession;
class LogPanel;

// The tiers of `take` as the window shows them: those `labels` last wrote for
// it (LabelSession::KnownTiers) or else the take's, with the tier being
// labelled as it is now (edits not yet autosaved included).
std::vector<LabelTier> TiersToExport(const Take& take, const LabelSession* labels, const std::string& corpus);

// Writes `tiers` as a TextGrid (.TextGrid) or an EAF (.eaf), chosen by the
// extension (case-insensitive) under a temporary name renamed into place.
// TextGrid interval tiers are written contiguous (io/formats FillIntervalGaps).
// Throws InvalidInput for another extension, the writers' errors otherwise.
void WriteLabelFile(const std::string& path, const std::vector<LabelTier>& tiers, double xmin, double xmax);

struct FileSummary {
  std::string kind;  // "models", "key recogniser", "models and key recogniser", "dictionary"
  nlohmann::json facts;
  std::string text;  // human-readable, one fact per line
};
// What a models, key-recogniser or dictionary file holds. Throws csw::Error
// when it is none of them.
FileSummary SummariseModelFile(const std::string& path);
// Copies `source` to `destination` (temporary sibling renamed into place;
// source == destination is refused) and summarises the copy.
FileSummary CopyModelFile(const std::string& source, const std::string& destination, Progress& progress);

class ExportRunner : public QObject {
  Q_OBJECT

 public:
  // dialog_parent: the window the summary dialog belongs to (null = no dialog).
  ExportRunner(LogPanel* log, QWidget* dialog_parent, QObject* parent = nullptr);

  // Start one export in the background; false when one runs or nothing to do.
  bool ExportLabels(const QString& path, std::vector<LabelTier> tiers, double xmin, double xmax);
  bool ExportModelFile(const QString& source, const QString& destination);

  bool running() const;
  JobRunner* runner() const { return runner_; }
  // The last file export's summary (empty before one succeeded).
  const FileSummary& summary() const { return summary_; }
  QMessageBox* summary_box() const { return box_; }

 signals:
  // ok false: message is the error.
  void Finished(bool ok, const QString& path, const QString& message);

 private:
  LogPanel* log_;
  QWidget* dialog_parent_;
  JobRunner* runner_;
  QString path_;
  bool file_export_ = false;
  std::shared_ptr<FileSummary> pending_;
  FileSummary summary_;
  QMessageBox* box_ = nullptr;
};

}  // namespace csw::gui
