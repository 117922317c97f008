// libFuzzer target for ReadTrc: any input must either parse or throw
// csw::Error (never crash, hang or allocate without bound). A file that parses
// must survive WriteTrc -> ReadTrc with the same shape, rate and samples.
#include <unistd.h>

#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <string>

#include "core/error.h"
#include "io/formats/trc.h"

namespace {

std::string TempPath(const char* suffix) { return "/tmp/csw_fuzz_trc_" + std::to_string(getpid()) + suffix; }

void WriteAll(const std::string& path, const uint8_t* data, size_t size) {
  FILE* f = std::fopen(path.c_str(), "wb");
  if (!f) std::abort();
  if (size > 0 && std::fwrite(data, 1, size, f) != size) std::abort();
  std::fclose(f);
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  static const std::string in = TempPath(".in.trc");
  static const std::string out = TempPath(".out.trc");
  WriteAll(in, data, size);
  csw::Take take;
  try {
    take = csw::ReadTrc(in);
  } catch (const csw::Error&) {
    return 0;
  }
  csw::WriteTrc(out, take);
  csw::Take back = csw::ReadTrc(out);
  if (back.rate_hz != take.rate_hz || back.first_frame != take.first_frame ||
      back.markers.frames() != take.markers.frames() || back.markers.markers() != take.markers.markers()) {
    std::abort();
  }
  const auto& a = take.markers.data();
  const auto& b = back.markers.data();
  for (size_t i = 0; i < a.size(); ++i) {
    if (std::isnan(a[i]) != std::isnan(b[i]) || (!std::isnan(a[i]) && a[i] != b[i])) std::abort();
  }
  return 0;
}
