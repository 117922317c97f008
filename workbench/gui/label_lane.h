#pragma once
// The key-label lane: the marks of the key tier being labelled (a
// LabelSession), drawn on the time-series panel's shared time axis with the
// playback cursor, and edited from the keyboard. The label "selected" is the
// one on the cursor frame; every edit moves the cursor with the label.
//
//   two digits PS        set a target PS at the cursor frame (relabels the
//                        label already there); Esc forgets a first digit
//   Alt+Left / Alt+Right move the label on the cursor frame by one frame
//   Delete / Backspace   delete the label on the cursor frame
//   Ctrl+Right / Ctrl+Left  jump to the next / previous label
//   S                    snap the label on the cursor frame to the nearest
//                        speed minimum of the marker lane's marker (SnapRequested)
//   N / Shift+N          jump to the next / previous open suggested target
//                        (LabelSession::suggestions: no label within 2 frames)
//   Enter (Return)       accept the open suggestion on the cursor frame or
//                        within 2 frames of it (one undoable add of its code at
//                        its frame), then jump to the next open suggestion
//   E / Shift+E          jump to the middle of the next / previous expected key
//                        with no label inside its interval
//   U / Shift+U          jump to the start of the next / previous run of frames
//                        where the key recogniser is unsure (stored posteriors;
//                        LabelSession::NextUnsureFrame)
//   click                move the cursor there (onto a label within 6 px)
// Undo / redo are the window's Ctrl+Z / Ctrl+Shift+Z (the session's QUndoStack).
// Suggested targets are drawn as hollow green circles (grey once accepted),
// expected keys as faint bands over their intervals with their code, unsure
// frames as a red strip along the bottom.
#include <QWidget>

class QCustomPlot;

namespace csw::gui {

class LabelSession;

class LabelLane : public QWidget {
  Q_OBJECT

 public:
  explicit LabelLane(LabelSession* session, QWidget* parent = nullptr);

  // The plot whose axis rectangle the lane lines up with (left and right edges).
  void AlignWith(QCustomPlot* plot) { align_ = plot; }
  QSize sizeHint() const override;
  QSize minimumSizeHint() const override;

  int64_t cursor_frame() const { return cursor_frame_; }
  // The first digit typed, "" when none.
  QString pending_digit() const { return pending_; }
  double view_start() const { return t0_; }
  double view_end() const { return t1_; }
  // Index of the label on the cursor frame, or -1.
  long selected() const;
  // The lane's x (pixels) of a time, as drawn.
  double XOfTime(double t) const { return X(t); }

 public slots:
  void SetCursorFrame(qint64 frame);
  void SetTimeRange(double t0, double t1);

 signals:
  // The lane asks the playback to put the cursor on `frame`.
  void SeekRequested(qint64 frame);
  // S was pressed: the window snaps the label on the cursor frame.
  void SnapRequested();

 protected:
  void paintEvent(QPaintEvent* event) override;
  void keyPressEvent(QKeyEvent* event) override;
  void mousePressEvent(QMouseEvent* event) override;
  bool event(QEvent* event) override;

 private:
  int Left() const;
  int Right() const;
  double X(double t) const;
  bool HandleKey(int key, Qt::KeyboardModifiers mods, const QString& text);
  void Seek(int64_t frame);

  LabelSession* session_;
  QCustomPlot* align_ = nullptr;
  int64_t cursor_frame_ = 0;
  double t0_ = 0.0;
  double t1_ = 1.0;
  QString pending_;
};

}  // namespace csw::gui
