#pragma once
// The label counts panel: how many targets of each key code the labelled tier
// holds (one row per code present, in code order), and the total.
#include <QTableWidget>

namespace csw {
class LabelModel;
}

namespace csw::gui {

class LabelCountsPanel : public QTableWidget {
  Q_OBJECT

 public:
  explicit LabelCountsPanel(QWidget* parent = nullptr);
  // Recounts `model` (nullptr empties the table).
  void Refresh(const LabelModel* model);
  // Count shown for `code` ("13"), 0 when the code has no row.
  int Count(const QString& code) const;
  int total() const { return total_; }

 private:
  int total_ = 0;
};

}  // namespace csw::gui
