#pragma once
// The test corpus of the key and phasing job tests: virtual-cuer sentences
// s0, s1, ... (the shipped sentences in order; no occlusions, audio off) in a
// corpus that remembers the marker set, and each sentence's truth file
// <truth>/<take>.truth.json. Paths: <dir>/c.h5, <dir>/keys.h5 (for a key
// model), <dir>/truth.
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include "core/markerset.h"
#include "datasets/virtual_cuer.h"
#include "io/corpus/corpus.h"
#include "tests/testing/testing.h"

namespace csw::testing {

struct CuerCorpus {
  TempDir dir;
  std::string corpus, keys, truth;
  std::vector<SimulationResult> sims;
  explicit CuerCorpus(int sentences) {
    corpus = (dir / "c.h5").string();
    keys = (dir / "keys.h5").string();
    truth = (dir / "truth").string();
    std::filesystem::create_directories(truth);
    SimulateOptions o;
    o.audio = false;
    o.occlusions = false;
    const VirtualCuer cuer(o);
    const std::string set = MarkerSetToJson(cuer.MakeMarkerSet());
    const auto texts = ShippedSentences();
    CorpusTransaction tx(corpus);
    for (int i = 0; i < sentences; ++i) {
      const std::string name = "s" + std::to_string(i);
      sims.push_back(cuer.SimulateSentence(name, texts[static_cast<size_t>(i)]));
      Take t = sims.back().take;
      t.markerset_json = set;
      tx.WriteTake(t);
      std::ofstream(std::filesystem::path(truth) / (name + ".truth.json")) << TruthToJson(sims.back());
    }
    tx.Commit();
  }
};

}  // namespace csw::testing
