#include "io/formats/wav.h"

#include <sndfile.h>

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <vector>

#include "core/error.h"

namespace csw {

namespace {

constexpr int kMaxChannels = 4096;
constexpr sf_count_t kBlockFrames = 16384;

// Closes the SNDFILE on scope exit.
class SndFile {
 public:
  SndFile(const std::string& path, int mode, SF_INFO* info) : file_(sf_open(path.c_str(), mode, info)) {}
  ~SndFile() {
    if (file_) sf_close(file_);
  }
  SndFile(const SndFile&) = delete;
  SndFile& operator=(const SndFile&) = delete;
  SNDFILE* get() const { return file_; }
  int Close() {
    int rc = file_ ? sf_close(file_) : 0;
    file_ = nullptr;
    return rc;
  }

 private:
  SNDFILE* file_;
};

}  // namespace

Audio ReadWav(const std::string& path) {
  {
    std::error_code ec;
    if (!std::filesystem::is_regular_file(path, ec)) throw IoError(path, "no such file");
    std::ifstream probe(path, std::ios::binary);
    if (!probe) throw IoError(path, std::string("cannot open: ") + std::strerror(errno));
  }
  SF_INFO info;
  std::memset(&info, 0, sizeof(info));
  SndFile file(path, SFM_READ, &info);
  if (!file.get()) {
    throw ParseError({path, std::nullopt, std::nullopt},
                     std::string("not a readable audio file: ") + sf_strerror(nullptr));
  }
  if (info.samplerate <= 0) throw ParseError({path, std::nullopt, std::nullopt}, "sample rate is not positive");
  if (info.channels <= 0 || info.channels > kMaxChannels) {
    throw ParseError({path, std::nullopt, std::nullopt}, "unsupported channel count " + std::to_string(info.channels));
  }
  const int subtype = info.format & SF_FORMAT_SUBMASK;
  const bool is_float = subtype == SF_FORMAT_FLOAT || subtype == SF_FORMAT_DOUBLE;
  Audio audio;
  audio.rate_hz = info.samplerate;
  audio.channels = info.channels;
  std::vector<float> block(static_cast<size_t>(kBlockFrames) * static_cast<size_t>(info.channels));
  while (true) {
    const sf_count_t got = sf_readf_float(file.get(), block.data(), kBlockFrames);
    if (got <= 0) break;
    const size_t n = static_cast<size_t>(got) * static_cast<size_t>(info.channels);
    if (is_float) {
      for (size_t i = 0; i < n; ++i) {
        if (!std::isfinite(block[i])) {
          const size_t index = audio.samples.size() + i;
          throw ParseError({path, std::nullopt, std::nullopt},
                           "sample " + std::to_string(index / static_cast<size_t>(info.channels)) + " (channel " +
                               std::to_string(index % static_cast<size_t>(info.channels)) + ") is NaN or infinite");
        }
      }
    }
    audio.samples.insert(audio.samples.end(), block.begin(), block.begin() + static_cast<ptrdiff_t>(n));
    if (got < kBlockFrames) break;
  }
  if (sf_error(file.get()) != SF_ERR_NO_ERROR) {
    throw ParseError({path, std::nullopt, std::nullopt},
                     std::string("audio data cannot be decoded: ") + sf_strerror(file.get()));
  }
  return audio;
}

void WriteWav(const std::string& path, const Audio& audio, int bits) {
  if (bits != 16 && bits != 32) {
    throw InvalidInput("WriteWav: bits must be 16 (PCM) or 32 (float), not " + std::to_string(bits));
  }
  if (!(audio.rate_hz > 0) || audio.rate_hz != std::floor(audio.rate_hz) || audio.rate_hz > 1e9) {
    throw InvalidInput("WriteWav: the sample rate must be a positive whole number of hertz");
  }
  if (audio.channels < 1 || audio.channels > kMaxChannels) {
    throw InvalidInput("WriteWav: bad channel count " + std::to_string(audio.channels));
  }
  if (audio.samples.size() % static_cast<size_t>(audio.channels) != 0) {
    throw InvalidInput("WriteWav: the sample count is not a multiple of the channel count");
  }
  for (float s : audio.samples) {
    if (!std::isfinite(s)) throw InvalidInput("WriteWav: NaN or infinite sample");
  }
  SF_INFO info;
  std::memset(&info, 0, sizeof(info));
  info.samplerate = static_cast<int>(audio.rate_hz);
  info.channels = audio.channels;
  info.format = SF_FORMAT_WAV | (bits == 16 ? SF_FORMAT_PCM_16 : SF_FORMAT_FLOAT);
  SndFile file(path, SFM_WRITE, &info);
  if (!file.get()) throw IoError(path, std::string("cannot open for writing: ") + sf_strerror(nullptr));
  const sf_count_t frames = static_cast<sf_count_t>(audio.frames());
  sf_count_t written = 0;
  if (bits == 16) {
    // Our own scaling (x * 32768, rounded, clamped) so that 16-bit data read by
    // ReadWav (x / 32768) is written back unchanged.
    std::vector<short> pcm(audio.samples.size());
    for (size_t i = 0; i < pcm.size(); ++i) {
      const double v = std::nearbyint(static_cast<double>(audio.samples[i]) * 32768.0);
      pcm[i] = static_cast<short>(std::clamp(v, -32768.0, 32767.0));
    }
    written = sf_writef_short(file.get(), pcm.data(), frames);
  } else {
    written = sf_writef_float(file.get(), audio.samples.data(), frames);
  }
  if (written != frames) throw IoError(path, std::string("write failed: ") + sf_strerror(file.get()));
  if (file.Close() != 0) throw IoError(path, "close failed");
}

}  // namespace csw
