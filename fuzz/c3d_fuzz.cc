// libFuzzer target for the C3D reader: any input must give a take or a ParseError.
#include <unistd.h>

#include <cstdint>
#include <cstdio>
#include <string>

#include "io/c3d/c3d.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  // C3dReader reads from a path: write the input to a per-process scratch file.
  static const std::string path = "/tmp/csw_c3d_fuzz_" + std::to_string(::getpid()) + ".c3d";
  std::FILE* f = std::fopen(path.c_str(), "wb");
  if (!f) return 0;
  if (size > 0) std::fwrite(data, 1, size, f);
  std::fclose(f);
  try {
    csw::Take take = csw::ReadC3d(path);
    csw::C3dReader reader(path);
    int64_t valid = 0;
    double sum = 0;
    reader.ValidPointStats(&valid, &sum);
    if (reader.info().frames > 0) {
      std::vector<float> p(static_cast<size_t>(reader.info().points * 3));
      std::vector<float> r(static_cast<size_t>(reader.info().points));
      std::vector<float> a(
          static_cast<size_t>(reader.info().analog_channels * reader.info().analog_subframes_per_frame));
      reader.ReadFrames(reader.info().frames - 1, 1, p.data(), r.data(), a.data());
    }
  } catch (const csw::ParseError&) {
  }
  return 0;
}
