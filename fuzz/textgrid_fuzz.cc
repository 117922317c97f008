// libFuzzer target for ReadTextGrid: any input must either parse or throw
// csw::Error. A file that parses must read back identically after
// WriteTextGrid in both the long and the short format.
#include <unistd.h>

#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <string>
#include <vector>

#include "core/error.h"
#include "io/formats/textgrid.h"

namespace {

std::string TempPath(const char* suffix) { return "/tmp/csw_fuzz_textgrid_" + std::to_string(getpid()) + suffix; }

void WriteAll(const std::string& path, const uint8_t* data, size_t size) {
  FILE* f = std::fopen(path.c_str(), "wb");
  if (!f) std::abort();
  if (size > 0 && std::fwrite(data, 1, size, f) != size) std::abort();
  std::fclose(f);
}

bool SameLabels(const std::vector<csw::LabelTier>& a, const std::vector<csw::LabelTier>& b) {
  if (a.size() != b.size()) return false;
  for (size_t t = 0; t < a.size(); ++t) {
    if (a[t].name != b[t].name || a[t].kind != b[t].kind || a[t].labels.size() != b[t].labels.size()) {
      return false;
    }
    // A 0..0 domain holding labels is written with the grid's domain.
    const bool unset = a[t].start_s == 0 && a[t].end_s == 0 && !a[t].labels.empty();
    if (!unset && (a[t].start_s != b[t].start_s || a[t].end_s != b[t].end_s)) return false;
    for (size_t i = 0; i < a[t].labels.size(); ++i) {
      const csw::Label& x = a[t].labels[i];
      const csw::Label& y = b[t].labels[i];
      if (x.start_s != y.start_s || x.end_s != y.end_s || x.text != y.text) return false;
    }
  }
  return true;
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  static const std::string in = TempPath(".in.TextGrid");
  static const std::string out = TempPath(".out.TextGrid");
  WriteAll(in, data, size);
  std::vector<csw::LabelTier> tiers;
  double xmin = 0, xmax = 0;
  try {
    tiers = csw::ReadTextGrid(in, &xmin, &xmax);
  } catch (const csw::Error&) {
    return 0;
  }
  for (bool short_format : {false, true}) {
    csw::WriteTextGrid(out, tiers, xmin, xmax, short_format);
    double xmin2 = 0, xmax2 = 0;
    std::vector<csw::LabelTier> back = csw::ReadTextGrid(out, &xmin2, &xmax2);
    if (xmin2 != xmin || xmax2 != xmax || !SameLabels(tiers, back)) std::abort();
  }
  return 0;
}
