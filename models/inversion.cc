#include "models/inversion.h"

#include <cmath>
#include <string>

#include "core/error.h"

namespace csw {

ErrorStats SummariseErrors(const Eigen::MatrixXd& error_mm, const std::vector<int>& columns, int64_t first,
                           int64_t count) {
  const int64_t rows = error_mm.rows();
  if (first < 0 || first > rows) {
    throw InvalidInput("error summary: first frame " + std::to_string(first) + " outside 0.." + std::to_string(rows));
  }
  const int64_t last = count < 0 ? rows : std::min(rows, first + count);
  std::vector<int> cols = columns;
  if (cols.empty()) {
    for (int c = 0; c < static_cast<int>(error_mm.cols()); ++c) cols.push_back(c);
  }
  for (int c : cols) {
    if (c < 0 || c >= error_mm.cols()) {
      throw InvalidInput("error summary: column " + std::to_string(c) + " outside 0.." +
                         std::to_string(error_mm.cols() - 1));
    }
  }
  // Welford: one pass, stable.
  ErrorStats s;
  double m2 = 0;
  for (int64_t r = first; r < last; ++r) {
    for (int c : cols) {
      const double e = error_mm(r, c);
      if (!std::isfinite(e)) continue;
      ++s.count;
      const double d = e - s.mean;
      s.mean += d / static_cast<double>(s.count);
      m2 += d * (e - s.mean);
      s.max = std::max(s.max, e);
    }
  }
  s.sd = s.count > 1 ? std::sqrt(m2 / static_cast<double>(s.count - 1)) : 0.0;
  return s;
}

Eigen::MatrixXd MarkerDistances(const MarkerArray& a, const MarkerArray& b) {
  if (a.frames() != b.frames() || a.markers() != b.markers()) {
    throw InvalidInput("marker distances: arrays differ in shape (" + std::to_string(a.frames()) + "×" +
                       std::to_string(a.markers()) + " vs " + std::to_string(b.frames()) + "×" +
                       std::to_string(b.markers()) + ")");
  }
  Eigen::MatrixXd d(a.frames(), a.markers());
  for (int64_t f = 0; f < a.frames(); ++f) {
    for (int64_t m = 0; m < a.markers(); ++m) {
      const float* p = a.at(f, m);
      const float* q = b.at(f, m);
      if (IsMissing(p[0]) || IsMissing(q[0])) {
        d(f, m) = std::nan("");
        continue;
      }
      const double dx = double(p[0]) - double(q[0]), dy = double(p[1]) - double(q[1]), dz = double(p[2]) - double(q[2]);
      d(f, m) = std::sqrt(dx * dx + dy * dy + dz * dz);
    }
  }
  return d;
}

}  // namespace csw
