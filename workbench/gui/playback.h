#pragma once
// Playback at the capture rate: the current frame follows a monotonic clock
// (frames are dropped rather than slowing down when drawing is slow). Audio,
// when the take has some and an output device exists, plays through Qt
// Multimedia from the same position; otherwise playback is silent and says why.
#include <QElapsedTimer>
#include <QObject>
#include <QTimer>
#include <memory>

#include "core/take.h"

class QAudioSink;
class QBuffer;

namespace csw::gui {

class Playback : public QObject {
  Q_OBJECT

 public:
  explicit Playback(QObject* parent = nullptr);
  ~Playback() override;

  // frames at rate_hz; audio may be null or empty. Stops and rewinds to frame 0.
  void SetTake(int64_t frames, double rate_hz, const Audio* audio);
  // Turns audio output off (tests, benchmarks) or back on.
  void SetAudioEnabled(bool on) { audio_enabled_ = on; }

  int64_t frame() const { return frame_; }
  int64_t frames() const { return frames_; }
  double rate_hz() const { return rate_hz_; }
  double time_s() const { return rate_hz_ > 0 ? static_cast<double>(frame_) / rate_hz_ : 0.0; }
  bool playing() const { return timer_.isActive(); }
  bool audio_active() const { return sink_ != nullptr; }

 public slots:
  void Play();
  void Pause();
  void Toggle();
  void Step(int64_t delta);
  void Seek(int64_t frame);
  void SeekTime(double t);

 signals:
  void FrameChanged(qint64 frame);
  void PlayingChanged(bool playing);
  // Something the user should know (e.g. "no audio output: playback is silent").
  void Note(const QString& message);

 private:
  void OnTick();
  void StartAudio();
  void StopAudio();

  int64_t frames_ = 0;
  double rate_hz_ = 0.0;
  int64_t frame_ = 0;
  int64_t start_frame_ = 0;
  QTimer timer_;
  QElapsedTimer clock_;
  const Audio* audio_ = nullptr;
  bool audio_enabled_ = true;
  bool audio_note_given_ = false;
  std::unique_ptr<QBuffer> pcm_;
  std::unique_ptr<QAudioSink> sink_;
};

}  // namespace csw::gui
