#pragma once
// Display decimation for long series (audio at 48 kHz, markers at 120 Hz over
// many minutes): a min/max pyramid answers "what does [t0, t1] look like in N
// pixel columns" in O(N) whatever the length of the series. Used for drawing
// only; analysis always sees the full-rate data.
#include <cstdint>
#include <vector>

namespace csw::gui {

// One displayed point pair: the extremes of the samples in one column.
struct MinMaxBin {
  double time_s = 0.0;  // start of the column
  float min = 0.0f;     // NaN when every sample in the column is missing
  float max = 0.0f;
};

class MinMaxPyramid {
 public:
  MinMaxPyramid() = default;
  // samples at rate_hz, first sample at time 0; NaN marks missing samples.
  MinMaxPyramid(std::vector<float> samples, double rate_hz);

  double rate_hz() const { return rate_hz_; }
  int64_t size() const { return static_cast<int64_t>(samples_.size()); }
  const std::vector<float>& samples() const { return samples_; }
  double duration_s() const { return rate_hz_ > 0 ? static_cast<double>(samples_.size()) / rate_hz_ : 0.0; }

  // Sample value at time t (nearest preceding sample), NaN outside the series.
  float ValueAt(double t) const;

  // The series over [t0, t1] as at most `columns` min/max bins. When the range
  // holds fewer samples than columns, returns each sample as its own bin
  // (min == max) so zooming in shows the real samples.
  std::vector<MinMaxBin> Decimate(double t0, double t1, int columns) const;

 private:
  // Min and max over samples [first, last) using the coarsest fitting levels.
  void Extremes(int64_t first, int64_t last, float* lo, float* hi) const;

  std::vector<float> samples_;
  double rate_hz_ = 0.0;
  // levels_[k] holds min/max pairs over blocks of kBlock^(k+1) samples.
  std::vector<std::vector<float>> levels_;
};

}  // namespace csw::gui
