#include "core/take.h"

#include <algorithm>
#include <cctype>

namespace csw {

int64_t MarkerArray::CountVisible() const {
  int64_t n = 0;
  for (size_t i = 0; i < data_.size(); i += 3) n += IsMissing(data_[i]) ? 0 : 1;
  return n;
}

int64_t Take::MarkerIndex(const std::string& name) const {
  auto it = std::find(marker_names.begin(), marker_names.end(), name);
  return it == marker_names.end() ? -1 : static_cast<int64_t>(it - marker_names.begin());
}

int64_t CountGaps(const MarkerArray& markers, int64_t marker) {
  int64_t gaps = 0;
  bool in_gap = false;
  for (int64_t f = 0; f < markers.frames(); ++f) {
    bool missing = !markers.Visible(f, marker);
    if (missing && !in_gap) ++gaps;
    in_gap = missing;
  }
  return gaps;
}

double MillimetresPerUnit(const std::string& units) {
  std::string u;
  for (char c : units) {
    if (!std::isspace(static_cast<unsigned char>(c)))
      u += static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  }
  if (u == "mm" || u.empty()) return 1.0;
  if (u == "m") return 1000.0;
  if (u == "cm") return 10.0;
  if (u == "dm") return 100.0;
  if (u == "in" || u == "inch" || u == "inches") return 25.4;
  if (u == "ft") return 304.8;
  return 0.0;
}

}  // namespace csw
