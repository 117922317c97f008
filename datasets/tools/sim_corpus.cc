// Writes a simulated corpus (the library's SimulateCorpus / GenerateDemoCorpus):
//   csw_sim_corpus OUT_DIR [--kind shapes|visemes|sentences|demo] [--seed N]
//                  [--count N] [--text "sentence"]... [--clean] [--no-truth]
// Exit status: 0 done, 1 usage, 2 error. The same arguments in a fresh process
// give byte-identical files.
#include <cstdio>
#include <cstdlib>
#include <string>

#include "core/error.h"
#include "datasets/virtual_cuer.h"

int main(int argc, char** argv) {
  auto usage = [&]() {
    std::fprintf(stderr,
                 "usage: %s OUT_DIR [--kind shapes|visemes|sentences|demo] [--seed N] [--count N] "
                 "[--text SENTENCE]... [--clean] [--no-truth]\n",
                 argv[0]);
    return 1;
  };
  if (argc < 2) return usage();
  std::string out = argv[1], kind = "sentences";
  csw::SimulateOptions o;
  for (int i = 2; i < argc; ++i) {
    std::string a = argv[i];
    auto value = [&]() -> const char* { return i + 1 < argc ? argv[++i] : nullptr; };
    if (a == "--kind") {
      const char* v = value();
      if (!v) return usage();
      kind = v;
    } else if (a == "--seed") {
      const char* v = value();
      if (!v) return usage();
      o.seed = std::strtoull(v, nullptr, 10);
    } else if (a == "--count") {
      const char* v = value();
      if (!v) return usage();
      o.count = std::atoi(v);
    } else if (a == "--text") {
      const char* v = value();
      if (!v) return usage();
      o.sentences.emplace_back(v);
    } else if (a == "--clean") {
      o.write_clean = true;
    } else if (a == "--no-truth") {
      o.write_truth = false;
    } else {
      return usage();
    }
  }
  csw::Progress progress([](const std::string& stage, double f) {
    std::fprintf(stderr, "\r%s %3.0f%%", stage.c_str(), 100.0 * f);
    if (f >= 1.0) std::fprintf(stderr, "\n");
  });
  try {
    if (kind == "demo") {
      csw::GenerateDemoCorpus(out, o.seed, o.count > 0 ? o.count : 7, progress);
      return 0;
    }
    if (!csw::ParseCorpusKind(kind, &o.kind)) return usage();
    if (std::string why = o.Check(); !why.empty()) {
      std::fprintf(stderr, "error: %s\n", why.c_str());
      return 1;
    }
    csw::SimulateCorpus(o, out, progress);
  } catch (const csw::Error& e) {
    std::fprintf(stderr, "error: %s\n", e.what());
    return 2;
  }
  return 0;
}
