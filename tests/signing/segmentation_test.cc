#include "analysis/signing/segmentation.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>

#include "datasets/virtual_signer.h"
#include "tests/testing/testing.h"

namespace csw::signing {
namespace {

struct Score {
  int total = 0, within = 0;
  double worst_s = 0.0;
  void Add(double error_s, double frame_s) {
    ++total;
    if (std::abs(error_s) <= 2 * frame_s + 1e-9) ++within;
    worst_s = std::max(worst_s, std::abs(error_s));
  }
  double Fraction() const { return total ? static_cast<double>(within) / total : 0.0; }
};

TEST(Segmentation, DebugSweep) {
  for (double cutoff : {4.0, 6.0, 8.0, 10.0, 0.0}) {
    SignerOptions o;
    VirtualSigner signer(o);
    Score moving, at_rest, rest_edges, manual_before;
    for (int i = 0; i < 40; ++i) {
      SignerTake t = signer.SimulateTake(i);
      const LabelTier manual = JitterBoundaries(t.take.tiers[0], "manual", 0.1, o.rate_hz, 1000 + i);
      SegmentationOptions so;
      so.speed.cutoff_hz = cutoff;
      auto hands = RefineSegmentation(t.take, manual, so);
      ASSERT_EQ(hands[0].boundaries.size(), t.boundaries.size());
      for (size_t b = 0; b < t.boundaries.size(); ++b) {
        const BoundaryTruth& bt = t.boundaries[b];
        for (int h = 0; h < 2; ++h) {
          const double truth = h == 0 ? bt.right_s : bt.left_s;
          if (!std::isfinite(truth)) continue;
          const bool rest = h == 0 ? bt.right_at_rest : bt.left_at_rest;
          const double err = hands[static_cast<size_t>(h)].boundaries[b].refined_s - truth;
          if (cutoff == 6.0 && bt.stroke && !rest && std::abs(err) > 0.0201) {
            // which sign
            std::string g;
            for (const auto& l : t.take.tiers[0].labels)
              if (std::abs(l.start_s - bt.nominal_s) < 1e-6 || std::abs(l.end_s - bt.nominal_s) < 1e-6)
                g += l.text + "|";
            std::printf("  take %d %c %s truth %.2f manual %.3f refined %.2f err %+.2f minima:", i, h ? 'L' : 'R',
                        g.c_str(), truth, hands[h].boundaries[b].manual_s, hands[h].boundaries[b].refined_s, err);
            for (auto m : hands[h].minima)
              if (std::abs(m / 100.0 - truth) < 0.3) std::printf(" %.2f(%.0f)", m / 100.0, hands[h].speed[m]);
            std::printf("\n");
          }
          manual_before.Add(hands[static_cast<size_t>(h)].boundaries[b].manual_s - truth, 1 / o.rate_hz);
          if (!bt.stroke)
            rest_edges.Add(err, 1 / o.rate_hz);
          else if (rest)
            at_rest.Add(err, 1 / o.rate_hz);
          else
            moving.Add(err, 1 / o.rate_hz);
        }
      }
    }
    std::printf(
        "cutoff %4.1f: moving %d/%d %.3f worst %.3f; stroke at rest %d/%d %.3f; rest edges %d/%d %.3f; manual %.3f\n",
        cutoff, moving.within, moving.total, moving.Fraction(), moving.worst_s, at_rest.within, at_rest.total,
        at_rest.Fraction(), rest_edges.within, rest_edges.total, rest_edges.Fraction(), manual_before.Fraction());
  }
}

}  // namespace
}  // namespace csw::signing
