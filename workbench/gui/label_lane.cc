#include "workbench/gui/label_lane.h"

#include <qcustomplot.h>

#include <QKeyEvent>
#include <QMouseEvent>
#include <QPainter>
#include <algorithm>
#include <cmath>
#include <vector>

#include "workbench/gui/label_session.h"

namespace csw::gui {

namespace {
constexpr int kDefaultLeft = 70;
constexpr int kPickPixels = 6;
}  // namespace

LabelLane::LabelLane(LabelSession* session, QWidget* parent) : QWidget(parent), session_(session) {
  setObjectName("labelLane");
  setFocusPolicy(Qt::StrongFocus);
  setSizePolicy(QSizePolicy::Expanding, QSizePolicy::Fixed);
  connect(session_, &LabelSession::LabelsChanged, this, [this] { update(); });
}

QSize LabelLane::sizeHint() const { return {600, 46}; }
QSize LabelLane::minimumSizeHint() const { return {200, 46}; }

int LabelLane::Left() const {
  if (align_ != nullptr && align_->axisRectCount() > 0) return align_->axisRect(0)->left();
  return kDefaultLeft;
}

int LabelLane::Right() const {
  if (align_ != nullptr && align_->axisRectCount() > 0) return align_->axisRect(0)->right();
  return width() - 10;
}

double LabelLane::X(double t) const {
  const double span = t1_ > t0_ ? t1_ - t0_ : 1.0;
  return Left() + (t - t0_) / span * (Right() - Left());
}

long LabelLane::selected() const { return session_->LabelAtFrame(cursor_frame_); }

void LabelLane::SetCursorFrame(qint64 frame) {
  cursor_frame_ = frame;
  update();
}

void LabelLane::SetTimeRange(double t0, double t1) {
  t0_ = t0;
  t1_ = t1;
  update();
}

void LabelLane::Seek(int64_t frame) {
  if (session_->frames() <= 0) return;
  frame = std::clamp<int64_t>(frame, 0, session_->frames() - 1);
  cursor_frame_ = frame;
  emit SeekRequested(frame);
  update();
}

void LabelLane::paintEvent(QPaintEvent*) {
  QPainter p(this);
  p.fillRect(rect(), palette().base());
  const int left = Left();
  const int right = Right();
  QFont small = font();
  small.setPointSizeF(small.pointSizeF() * 0.9);
  p.setFont(small);
  // The tier name (and the first digit typed) in the left margin.
  QString title = session_->has_take() ? QString::fromStdString(session_->tier_name()) : tr("(no take)");
  if (!pending_.isEmpty()) title += QStringLiteral("  ") + pending_ + QStringLiteral("_");
  p.setPen(hasFocus() ? palette().highlight().color() : palette().text().color());
  p.drawText(QRect(4, 0, std::max(10, left - 8), height()), Qt::AlignVCenter | Qt::AlignLeft, title);
  p.setPen(QPen(palette().mid().color()));
  p.drawLine(left, height() - 1, right, height() - 1);
  p.drawLine(left, 0, right, 0);
  if (!session_->has_take()) return;
  p.setClipRect(QRect(left, 0, right - left + 1, height()));

  // Expected keys: faint bands over their intervals (fainter once labelled), code at the bottom right.
  const auto& expected = session_->expected_keys();
  for (size_t i = 0; i < expected.size(); ++i) {
    const auto& span = expected[i];
    if (span.end_s < t0_ || span.start_s > t1_) continue;
    const bool labelled = session_->ExpectedKeyLabelled(i);
    const QRectF band(QPointF(X(span.start_s), 1), QPointF(X(span.end_s), height() - 1));
    p.fillRect(band.adjusted(0.5, 0, -0.5, 0),
               labelled ? QColor(150, 150, 150, 28) : QColor(230, 150, 30, i % 2 == 0 ? 50 : 36));
    p.setPen(QColor(130, 100, 60, labelled ? 90 : 170));
    p.drawText(band.adjusted(2, 0, -2, -1), Qt::AlignBottom | Qt::AlignRight, span.code);
  }
  // Unsure frames: a red strip along the bottom.
  const std::vector<uint8_t>& unsure = session_->unsure_frames();
  const auto shown_end =
      static_cast<size_t>(std::clamp<int64_t>(session_->TimeFrame(t1_) + 2, 0, static_cast<int64_t>(unsure.size())));
  for (auto f = static_cast<size_t>(
           std::clamp<int64_t>(session_->TimeFrame(t0_) - 1, 0, static_cast<int64_t>(unsure.size())));
       f < shown_end;) {
    if (unsure[f] == 0) {
      ++f;
      continue;
    }
    size_t end = f;
    while (end < shown_end && unsure[end] != 0) ++end;
    const double xa = X(session_->FrameTime(static_cast<int64_t>(f)) - 0.5 / session_->rate_hz());
    const double xb = X(session_->FrameTime(static_cast<int64_t>(end) - 1) + 0.5 / session_->rate_hz());
    p.fillRect(QRectF(QPointF(xa, height() - 5), QPointF(std::max(xb, xa + 1), height() - 1)),
               QColor(210, 40, 40, 150));
    f = end;
  }
  // Suggested targets: hollow circles on a dashed stem, green while open, grey once accepted.
  const auto& suggestions = session_->suggestions();
  for (size_t i = 0; i < suggestions.size(); ++i) {
    const double t = session_->FrameTime(suggestions[i].frame);
    if (t < t0_ || t > t1_) continue;
    const double x = X(t);
    const QColor colour = session_->SuggestionAccepted(i) ? QColor(160, 160, 160) : QColor(0, 150, 70);
    p.setPen(QPen(colour, 1.0, Qt::DashLine));
    p.drawLine(QPointF(x, height() * 0.45), QPointF(x, height() - 2));
    p.setPen(QPen(colour, 1.5));
    p.setBrush(Qt::NoBrush);
    p.drawEllipse(QPointF(x, height() * 0.72), 4.0, 4.0);
  }

  const LabelModel& model = *session_->model();
  const long sel = selected();
  QFont bold = small;
  bold.setBold(true);
  for (size_t i = 0; i < model.size(); ++i) {
    const Label& label = model.at(i);
    if (label.start_s < t0_ || label.start_s > t1_) continue;
    const double x = X(label.start_s);
    const bool is_sel = static_cast<long>(i) == sel;
    QColor colour = is_sel ? QColor(200, 60, 0) : QColor(20, 70, 160);
    p.setPen(QPen(colour, is_sel ? 2.5 : 1.5));
    p.drawLine(QPointF(x, height() * 0.45), QPointF(x, height() - 2));
    p.setFont(is_sel ? bold : small);
    p.drawText(QRectF(x - 20, 1, 40, height() * 0.45), Qt::AlignCenter, QString::fromStdString(label.text));
  }
  // The playback cursor, as in the plots.
  const double xc = X(session_->FrameTime(cursor_frame_));
  p.setPen(QPen(QColor(220, 30, 30), 1.0));
  p.drawLine(QPointF(xc, 0), QPointF(xc, height()));
}

bool LabelLane::event(QEvent* e) {
  // Claim the lane's keys before the window's shortcuts see them.
  if (e->type() == QEvent::ShortcutOverride) {
    auto* k = static_cast<QKeyEvent*>(e);
    const int key = k->key();
    const auto mods = k->modifiers() & ~Qt::KeypadModifier;
    const bool digit = key >= Qt::Key_0 && key <= Qt::Key_9 && mods == Qt::NoModifier;
    const bool arrows =
        (key == Qt::Key_Left || key == Qt::Key_Right) && (mods == Qt::AltModifier || mods == Qt::ControlModifier);
    const bool other = (key == Qt::Key_Delete || key == Qt::Key_Backspace || key == Qt::Key_Escape ||
                        key == Qt::Key_Return || key == Qt::Key_Enter) &&
                       mods == Qt::NoModifier;
    const bool guides = (key == Qt::Key_N || key == Qt::Key_E || key == Qt::Key_U) &&
                        (mods == Qt::NoModifier || mods == Qt::ShiftModifier);
    if (digit || arrows || other || guides) {
      e->accept();
      return true;
    }
  }
  return QWidget::event(e);
}

void LabelLane::keyPressEvent(QKeyEvent* e) {
  if (HandleKey(e->key(), e->modifiers() & ~Qt::KeypadModifier, e->text())) {
    e->accept();
    update();
    return;
  }
  QWidget::keyPressEvent(e);
}

bool LabelLane::HandleKey(int key, Qt::KeyboardModifiers mods, const QString& /*text*/) {
  if (!session_->has_take()) return false;
  if (key >= Qt::Key_0 && key <= Qt::Key_9 && mods == Qt::NoModifier) {
    const QChar digit(QLatin1Char(static_cast<char>('0' + (key - Qt::Key_0))));
    if (pending_.isEmpty()) {
      pending_ = digit;
      return true;
    }
    const QString code = pending_ + digit;
    pending_.clear();
    const long at = selected();
    if (at >= 0) {
      session_->Relabel(at, code);
    } else {
      session_->AddLabel(cursor_frame_, code);
    }
    return true;
  }
  if (key == Qt::Key_S && mods == Qt::NoModifier) {
    emit SnapRequested();
    return true;
  }
  if ((key == Qt::Key_N || key == Qt::Key_E || key == Qt::Key_U) &&
      (mods == Qt::NoModifier || mods == Qt::ShiftModifier)) {
    const int direction = mods == Qt::ShiftModifier ? -1 : 1;
    const int64_t to = key == Qt::Key_N   ? session_->NextOpenSuggestion(cursor_frame_, direction)
                       : key == Qt::Key_E ? session_->NextOpenExpectedKey(cursor_frame_, direction)
                                          : session_->NextUnsureFrame(cursor_frame_, direction);
    if (to >= 0) Seek(to);
    return true;
  }
  if ((key == Qt::Key_Return || key == Qt::Key_Enter) && mods == Qt::NoModifier) {
    pending_.clear();
    const int64_t at = session_->AcceptSuggestion(cursor_frame_);
    if (at < 0) return true;
    const int64_t next = session_->NextOpenSuggestion(at, 1);
    Seek(next >= 0 ? next : at);
    return true;
  }
  if (key == Qt::Key_Escape && mods == Qt::NoModifier) {
    pending_.clear();
    return true;
  }
  if ((key == Qt::Key_Left || key == Qt::Key_Right) && mods == Qt::AltModifier) {
    const long at = selected();
    if (at < 0) return true;
    const int64_t to = cursor_frame_ + (key == Qt::Key_Right ? 1 : -1);
    if (session_->MoveLabel(at, to)) Seek(to);
    return true;
  }
  if ((key == Qt::Key_Delete || key == Qt::Key_Backspace) && mods == Qt::NoModifier) {
    const long at = selected();
    if (at >= 0) session_->DeleteLabel(at);
    return true;
  }
  if ((key == Qt::Key_Left || key == Qt::Key_Right) && mods == Qt::ControlModifier) {
    const LabelModel& model = *session_->model();
    if (key == Qt::Key_Right) {
      for (size_t i = 0; i < model.size(); ++i) {
        const int64_t f = session_->TimeFrame(model.at(i).start_s);
        if (f > cursor_frame_) {
          Seek(f);
          break;
        }
      }
    } else {
      for (size_t i = model.size(); i-- > 0;) {
        const int64_t f = session_->TimeFrame(model.at(i).start_s);
        if (f < cursor_frame_) {
          Seek(f);
          break;
        }
      }
    }
    return true;
  }
  return false;
}

void LabelLane::mousePressEvent(QMouseEvent* e) {
  setFocus(Qt::MouseFocusReason);
  if (!session_->has_take() || e->button() != Qt::LeftButton) return QWidget::mousePressEvent(e);
  const double x = e->position().x();
  // Onto the nearest label within a few pixels, else onto the frame under the mouse.
  const LabelModel& model = *session_->model();
  double best = kPickPixels + 1;
  int64_t frame = -1;
  for (size_t i = 0; i < model.size(); ++i) {
    const double d = std::abs(X(model.at(i).start_s) - x);
    if (d < best) {
      best = d;
      frame = session_->TimeFrame(model.at(i).start_s);
    }
  }
  if (frame < 0) {
    const double span = t1_ > t0_ ? t1_ - t0_ : 1.0;
    const double t = t0_ + (x - Left()) / std::max(1, Right() - Left()) * span;
    frame = session_->TimeFrame(t);
  }
  Seek(frame);
}

}  // namespace csw::gui
