#include "workbench/gui/demo_take.h"

#include <vector>

#include "core/error.h"

namespace csw::gui {

namespace {

SimulateOptions CuerOptions(const DemoTakeOptions& o) {
  SimulateOptions s;
  s.seed = o.seed;
  s.rate_hz = o.rate_hz;
  s.audio = o.audio;
  s.write_truth = false;
  return s;
}

// Speech time of a sentence at the virtual cuer's default rate, estimated from
// its length (espeak-ng at 80 words per minute: about 65 ms per character);
// only used to decide how many sentences to join.
double EstimatedSeconds(const std::string& text) { return 0.065 * static_cast<double>(text.size()); }

}  // namespace

std::string DemoText(const DemoTakeOptions& o) {
  const std::vector<std::string> sentences = ShippedSentences();
  if (sentences.empty()) throw Error("demo take: the shipped sentence list is empty");
  std::string text = sentences[0];
  double estimate = EstimatedSeconds(text);
  for (size_t i = 1; estimate < o.seconds; ++i) {  // the list again from the top when it runs out
    const std::string& next = sentences[i % sentences.size()];
    text += " " + next;
    estimate += EstimatedSeconds(next);
  }
  return text;
}

SimulationResult SimulateDemoTake(const DemoTakeOptions& o) {
  const SimulateOptions s = CuerOptions(o);
  if (const std::string why = s.Check(); !why.empty()) throw InvalidInput("demo take: " + why);
  VirtualCuer cuer(s);
  return cuer.SimulateSentence(o.name, DemoText(o));
}

Take MakeDemoTake(const DemoTakeOptions& o) { return SimulateDemoTake(o).take; }

MarkerSet DemoMarkerSet() { return VirtualCuer(SimulateOptions{}).MakeMarkerSet(); }

}  // namespace csw::gui
