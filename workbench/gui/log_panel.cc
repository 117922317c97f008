#include "workbench/gui/log_panel.h"

#include <QDateTime>
#include <QFontDatabase>

namespace csw::gui {

LogPanel::LogPanel(QWidget* parent) : QPlainTextEdit(parent) {
  setObjectName("logPanel");
  setReadOnly(true);
  setMaximumBlockCount(5000);
  setFont(QFontDatabase::systemFont(QFontDatabase::FixedFont));
}

void LogPanel::Add(Level level, const QString& message) {
  QString prefix = level == Level::kError     ? QStringLiteral("error: ")
                   : level == Level::kWarning ? QStringLiteral("warning: ")
                                              : QString();
  entries_.push_back(prefix + message);
  levels_.push_back(level);
  QString color = level == Level::kError ? "#c0392b" : level == Level::kWarning ? "#b9770e" : "#303030";
  QString time = QDateTime::currentDateTime().toString("HH:mm:ss");
  appendHtml(QStringLiteral("<span style='color:#808080'>%1</span> <span style='color:%2'>%3</span>")
                 .arg(time, color, (prefix + message).toHtmlEscaped()));
  if (level == Level::kError) emit ErrorLogged(message);
}

int LogPanel::CountLevel(Level level) const {
  int n = 0;
  for (Level l : levels_) n += l == level;
  return n;
}

}  // namespace csw::gui
