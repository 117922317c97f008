#include "analysis/cleaning/fill.h"

#include <algorithm>
#include <cmath>

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

FillReport FillGaps(const MarkerArray& in, const std::vector<const GapFiller*>& methods, int64_t max_gap_frames,
                    MarkerArray* out, Progress* progress) {
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
        if (m->Fill(in, gap, out, &rec) && GapWritten(*out, gap)) {
          rec.marker = gap.marker;
          rec.start = gap.start;
          rec.length = gap.length;
          if (rec.method.empty()) rec.method = name;
          report.filled.push_back(std::move(rec));
          done = true;
          break;
        }
        RestoreGap(in, gap, out);
        why = "the fill failed";
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
