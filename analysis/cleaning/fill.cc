#include "analysis/cleaning/fill.h"

#include <algorithm>
#include <cmath>
#include <cstdio>

#include "core/error.h"

namespace csw::cleaning {

GapFiller::~GapFiller() = default;

int64_t FillReport::filled_samples() const {
  int64_t n = 0;
  for (const FillRecord& r : filled) n += r.length;
  return n;
}

int64_t FillReport::unfilled_samples() const {
  int64_t n = 0;
  for (const auto& u : unfilled) n += u.first.length;
  return n;
}

int64_t ValidFramesBefore(const MarkerArray& in, const Gap& gap, int64_t limit) {
  int64_t n = 0;
  for (int64_t f = gap.start - 1; f >= 0 && n < limit && !SampleMissing(in, f, gap.marker); --f) ++n;
  return n;
}

int64_t ValidFramesAfter(const MarkerArray& in, const Gap& gap, int64_t limit) {
  int64_t n = 0;
  for (int64_t f = gap.end(); f < in.frames() && n < limit && !SampleMissing(in, f, gap.marker); ++f) ++n;
  return n;
}

std::string CheckSides(const MarkerArray& in, const Gap& gap, int64_t min_frames) {
  if (gap.leading && gap.trailing) return "marker never visible";
  if (gap.leading || gap.start == 0) return "leading gap: no valid frame before it";
  if (gap.trailing || gap.end() >= in.frames()) return "trailing gap: no valid frame after it";
  const int64_t need = std::max<int64_t>(min_frames, 1);
  const int64_t before = ValidFramesBefore(in, gap, need);
  if (before < need)
    return std::to_string(before) + " valid frame" + (before == 1 ? "" : "s") + " before the gap, " +
           std::to_string(need) + " needed";
  const int64_t after = ValidFramesAfter(in, gap, need);
  if (after < need)
    return std::to_string(after) + " valid frame" + (after == 1 ? "" : "s") + " after the gap, " +
           std::to_string(need) + " needed";
  return "";
}

namespace {

void CheckArguments(const MarkerArray& in, const std::vector<const GapFiller*>& methods, int64_t max_gap_frames) {
  for (size_t i = 0; i < methods.size(); ++i)
    if (methods[i] == nullptr) throw InvalidInput("fill gaps: fill method " + std::to_string(i) + " is null");
  if (max_gap_frames < 0)
    throw InvalidInput("fill gaps: maximum gap " + std::to_string(max_gap_frames) + " frames is negative");
  (void)in;
}

std::string TooLong(const Gap& gap, int64_t max_gap_frames) {
  return "gap of " + std::to_string(gap.length) + " frames longer than the maximum gap of " +
         std::to_string(max_gap_frames) + " frames";
}

void RestoreGap(const MarkerArray& in, const Gap& gap, MarkerArray* out) {
  for (int64_t f = gap.start; f < gap.end(); ++f) std::copy_n(in.at(f, gap.marker), 3, out->at(f, gap.marker));
}

bool GapWritten(const MarkerArray& out, const Gap& gap) {
  for (int64_t f = gap.start; f < gap.end(); ++f)
    if (SampleMissing(out, f, gap.marker)) return false;
  return true;
}

}  // namespace

std::string CheckFillSpeed(const MarkerArray& in, const MarkerArray& out, const Gap& gap,
                           const FillGuardOptions& guard) {
  if (!(guard.speed_factor > 0)) return "";
  auto step = [](const float* a, const float* b) {
    return std::sqrt(std::pow(double(a[0]) - b[0], 2) + std::pow(double(a[1]) - b[1], 2) +
                     std::pow(double(a[2]) - b[2], 2));
  };
  const int64_t m = gap.marker;
  // Peak measured speed in the context (consecutive measured frames only).
  double context = 0;
  const int64_t lo = std::max<int64_t>(1, gap.start - guard.context_frames);
  const int64_t hi = std::min<int64_t>(in.frames() - 1, gap.end() + guard.context_frames);
  double box_lo[3] = {INFINITY, INFINITY, INFINITY}, box_hi[3] = {-INFINITY, -INFINITY, -INFINITY};
  for (int64_t f = lo - 1; f <= hi; ++f) {
    if (f >= gap.start && f < gap.end()) continue;
    if (SampleMissing(in, f, m)) continue;
    for (int c = 0; c < 3; ++c) {
      box_lo[c] = std::min(box_lo[c], double(in.at(f, m)[c]));
      box_hi[c] = std::max(box_hi[c], double(in.at(f, m)[c]));
    }
    if (f < lo || f == gap.end() || SampleMissing(in, f - 1, m)) continue;
    context = std::max(context, step(in.at(f, m), in.at(f - 1, m)));
  }
  double needed = 0;
  const bool before = gap.start > 0 && !SampleMissing(in, gap.start - 1, m);
  const bool after = gap.end() < in.frames() && !SampleMissing(in, gap.end(), m);
  if (before && after)
    needed = step(in.at(gap.start - 1, m), in.at(gap.end(), m)) / static_cast<double>(gap.length + 1);
  if (context == 0 && needed == 0) return "";  // nothing measured to compare with
  const double limit = guard.speed_factor * std::max({context, needed, guard.floor_mm_per_frame});
  double peak = 0;
  // Steps from the measured edge sample into the gap, inside it, and out of it.
  const int64_t first_step = before ? gap.start : gap.start + 1;
  for (int64_t f = std::max<int64_t>(1, first_step); f <= gap.end() && f < out.frames(); ++f) {
    if (SampleMissing(out, f, m) || SampleMissing(out, f - 1, m)) continue;
    peak = std::max(peak, step(out.at(f, m), out.at(f - 1, m)));
  }
  char buf[256];
  if (std::isfinite(box_lo[0])) {
    const double diagonal = std::sqrt(std::pow(box_hi[0] - box_lo[0], 2) + std::pow(box_hi[1] - box_lo[1], 2) +
                                      std::pow(box_hi[2] - box_lo[2], 2));
    const double margin = std::max(guard.box_margin * diagonal, guard.box_floor_mm);
    double outside = 0;
    for (int64_t f = gap.start; f < gap.end(); ++f) {
      double d2 = 0;
      for (int c = 0; c < 3; ++c) {
        const double v = out.at(f, m)[c];
        const double d = v < box_lo[c] ? box_lo[c] - v : (v > box_hi[c] ? v - box_hi[c] : 0.0);
        d2 += d * d;
      }
      outside = std::max(outside, std::sqrt(d2));
    }
    if (outside > margin) {
      std::snprintf(buf, sizeof(buf),
                    "fill refused: it leaves the box of the measured samples around the gap by %.1f mm, more "
                    "than %.1f mm",
                    outside, margin);
      return buf;
    }
  }
  if (peak <= limit) return "";
  std::snprintf(buf, sizeof(buf),
                "fill refused: peak speed %.1f mm/frame in the gap, more than %.1f x the largest of the measured "
                "peak around it (%.1f), the speed needed to cross it (%.1f) and %.1f mm/frame",
                peak, guard.speed_factor, context, needed, guard.floor_mm_per_frame);
  return buf;
}

FillReport FillGaps(const MarkerArray& in, const std::vector<const GapFiller*>& methods, int64_t max_gap_frames,
                    MarkerArray* out, Progress* progress, const FillGuardOptions& guard) {
  if (out == nullptr) throw InvalidInput("fill gaps: no output array");
  if (out == &in) throw InvalidInput("fill gaps: the output must not be the input (fills read only the input)");
  CheckArguments(in, methods, max_gap_frames);
  *out = in;
  const std::vector<Gap> gaps = FindAllGaps(in);
  FillReport report;
  const size_t every = std::max<size_t>(1, gaps.size() / 100);
  for (size_t i = 0; i < gaps.size(); ++i) {
    if (progress != nullptr) {
      if (i % every == 0)
        progress->Update("fill gaps", static_cast<double>(i) / static_cast<double>(gaps.size()));
      else
        progress->CheckCancel();
    }
    const Gap& gap = gaps[i];
    if (max_gap_frames > 0 && gap.length > max_gap_frames) {
      report.unfilled.emplace_back(gap, TooLong(gap, max_gap_frames));
      continue;
    }
    std::string reasons;
    bool done = false;
    for (const GapFiller* m : methods) {
      std::string why;
      const std::string name = m->name();
      if (m->CanFill(in, gap, &why)) {
        FillRecord rec;
        rec.marker = gap.marker;
        rec.start = gap.start;
        rec.length = gap.length;
        rec.method = name;
        std::string implausible;
        if (m->Fill(in, gap, out, &rec) && GapWritten(*out, gap) &&
            (implausible = CheckFillSpeed(in, *out, gap, guard)).empty()) {
          rec.marker = gap.marker;
          rec.start = gap.start;
          rec.length = gap.length;
          if (rec.method.empty()) rec.method = name;
          report.filled.push_back(std::move(rec));
          done = true;
          break;
        }
        RestoreGap(in, gap, out);
        why = implausible.empty() ? "the fill failed" : implausible;
      }
      if (why.empty()) why = "cannot fill this gap";
      if (!reasons.empty()) reasons += "; ";
      reasons += name + ": " + why;
    }
    if (!done) report.unfilled.emplace_back(gap, methods.empty() ? std::string("no fill method given") : reasons);
  }
  if (progress != nullptr) progress->Update("fill gaps", 1.0);
  return report;
}

std::vector<GapMethods> AssessGaps(const MarkerArray& in, const std::vector<Gap>& gaps,
                                   const std::vector<const GapFiller*>& methods, int64_t max_gap_frames) {
  CheckArguments(in, methods, max_gap_frames);
  std::vector<GapMethods> result;
  result.reserve(gaps.size());
  for (const Gap& gap : gaps) {
    if (gap.marker < 0 || gap.marker >= in.markers() || gap.start < 0 || gap.length < 1 || gap.end() > in.frames())
      throw InvalidInput("assess gaps: gap of marker " + std::to_string(gap.marker) + " at frame " +
                         std::to_string(gap.start) + " (" + std::to_string(gap.length) +
                         " frames) is outside the take");
    GapMethods gm;
    gm.gap = gap;
    if (max_gap_frames > 0 && gap.length > max_gap_frames) {
      gm.too_long = true;
      for (const GapFiller* m : methods) gm.cannot.emplace_back(m->name(), TooLong(gap, max_gap_frames));
    } else {
      for (const GapFiller* m : methods) {
        std::string why;
        if (m->CanFill(in, gap, &why))
          gm.can_fill.push_back(m->name());
        else
          gm.cannot.emplace_back(m->name(), why.empty() ? std::string("cannot fill this gap") : why);
      }
    }
    result.push_back(std::move(gm));
  }
  return result;
}

}  // namespace csw::cleaning
