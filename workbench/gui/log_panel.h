#pragma once
// The log panel: timestamped info / warning / error lines (import reports,
// files that could not be opened, playback notes). Errors never stop the app.
#include <QPlainTextEdit>
#include <QStringList>

namespace csw::gui {

class LogPanel : public QPlainTextEdit {
  Q_OBJECT

 public:
  enum class Level { kInfo, kWarning, kError };
  explicit LogPanel(QWidget* parent = nullptr);

  void Add(Level level, const QString& message);
  void Info(const QString& m) { Add(Level::kInfo, m); }
  void Warning(const QString& m) { Add(Level::kWarning, m); }
  void Error(const QString& m) { Add(Level::kError, m); }

  // Messages so far, without timestamps ("error: ...", "warning: ...", "...").
  const QStringList& entries() const { return entries_; }
  int CountLevel(Level level) const;

 signals:
  void ErrorLogged(const QString& message);

 private:
  QStringList entries_;
  std::vector<Level> levels_;
};

}  // namespace csw::gui
