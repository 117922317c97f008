#include "workbench/gui/playback.h"

#include <QAudioDevice>
#include <QAudioFormat>
#include <QAudioSink>
#include <QBuffer>
#include <QMediaDevices>
#include <algorithm>
#include <cmath>

namespace csw::gui {

Playback::Playback(QObject* parent) : QObject(parent) {
  timer_.setTimerType(Qt::PreciseTimer);
  connect(&timer_, &QTimer::timeout, this, &Playback::OnTick);
}

Playback::~Playback() { StopAudio(); }

void Playback::SetTake(int64_t frames, double rate_hz, const Audio* audio) {
  Pause();
  frames_ = std::max<int64_t>(0, frames);
  rate_hz_ = rate_hz;
  audio_ = audio;
  frame_ = 0;
  emit FrameChanged(frame_);
}

void Playback::Play() {
  if (playing() || frames_ <= 0 || rate_hz_ <= 0) return;
  if (frame_ >= frames_ - 1) frame_ = 0;  // play again from the start
  start_frame_ = frame_;
  clock_.start();
  // Tick at twice the frame rate so no frame is skipped when drawing keeps up.
  timer_.start(std::max(1, static_cast<int>(500.0 / rate_hz_)));
  StartAudio();
  emit PlayingChanged(true);
}

void Playback::Pause() {
  if (!playing()) return;
  timer_.stop();
  StopAudio();
  emit PlayingChanged(false);
}

void Playback::Toggle() { playing() ? Pause() : Play(); }

void Playback::Step(int64_t delta) {
  Pause();
  Seek(frame_ + delta);
}

void Playback::Seek(int64_t frame) {
  if (frames_ <= 0) return;
  frame = std::clamp<int64_t>(frame, 0, frames_ - 1);
  bool was_playing = playing();
  if (was_playing) {
    // Keep playing from the new position.
    start_frame_ = frame;
    clock_.restart();
    StopAudio();
  }
  if (frame != frame_) {
    frame_ = frame;
    emit FrameChanged(frame_);
  }
  if (was_playing) StartAudio();
}

void Playback::SeekTime(double t) { Seek(static_cast<int64_t>(std::floor(t * rate_hz_ + 0.5))); }

void Playback::OnTick() {
  auto f = start_frame_ + static_cast<int64_t>(static_cast<double>(clock_.nsecsElapsed()) * 1e-9 * rate_hz_);
  if (f >= frames_ - 1) {
    f = frames_ - 1;
    if (f != frame_) {
      frame_ = f;
      emit FrameChanged(frame_);
    }
    Pause();
    return;
  }
  if (f != frame_) {
    frame_ = f;
    emit FrameChanged(frame_);
  }
}

void Playback::StartAudio() {
  if (!audio_enabled_ || audio_ == nullptr || audio_->samples.empty() || audio_->rate_hz <= 0) return;
  QAudioDevice device = QMediaDevices::defaultAudioOutput();
  QAudioFormat format;
  format.setSampleRate(static_cast<int>(std::lround(audio_->rate_hz)));
  format.setChannelCount(audio_->channels);
  format.setSampleFormat(QAudioFormat::Float);
  if (device.isNull() || !device.isFormatSupported(format)) {
    if (!audio_note_given_) {
      emit Note(
          device.isNull()
              ? tr("No audio output device: playback is silent.")
              : tr("The audio output cannot play %1 Hz float audio: playback is silent.").arg(format.sampleRate()));
      audio_note_given_ = true;
    }
    return;
  }
  int64_t first = std::clamp<int64_t>(static_cast<int64_t>(time_s() * audio_->rate_hz), 0, audio_->frames());
  const auto* begin = reinterpret_cast<const char*>(audio_->samples.data() + first * audio_->channels);
  qsizetype bytes = static_cast<qsizetype>((audio_->frames() - first) * audio_->channels * sizeof(float));
  pcm_ = std::make_unique<QBuffer>();
  pcm_->setData(QByteArray(begin, bytes));
  pcm_->open(QIODevice::ReadOnly);
  sink_ = std::make_unique<QAudioSink>(device, format);
  sink_->start(pcm_.get());
}

void Playback::StopAudio() {
  if (sink_) sink_->stop();
  sink_.reset();
  pcm_.reset();
}

}  // namespace csw::gui
