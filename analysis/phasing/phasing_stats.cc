#include "analysis/phasing/phasing_stats.h"

#include <cmath>
#include <cstdio>
#include <limits>
#include <nlohmann/json.hpp>

#include "core/error.h"

namespace csw::phasing {

namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

// P(|T| < t) for integer degrees of freedom (A&S 26.7.3 odd, 26.7.4 even).
double TwoSidedCdf(double t, int dof) {
  const double theta = std::atan(t / std::sqrt(static_cast<double>(dof)));
  const double c2 = std::cos(theta) * std::cos(theta), s = std::sin(theta);
  if (dof % 2 == 1) {
    if (dof == 1) return 2.0 * theta / M_PI;
    double term = std::cos(theta), sum = term;  // cos θ (1 + 2/3 cos² θ + 2·4/(3·5) cos⁴ θ ...)
    for (int k = 1; 2 * k + 1 <= dof - 2; ++k) {
      term *= c2 * (2.0 * k) / (2.0 * k + 1.0);
      sum += term;
    }
    return 2.0 / M_PI * (theta + s * sum);
  }
  double term = 1.0, sum = 1.0;  // 1 + 1/2 cos² θ + 1·3/(2·4) cos⁴ θ ...
  for (int k = 1; 2 * k <= dof - 2; ++k) {
    term *= c2 * (2.0 * k - 1.0) / (2.0 * k);
    sum += term;
  }
  return s * sum;
}

double Pick(const KeyTiming& t, Component c, Landmark l) {
  if (c == Component::kPlacement) return l == Landmark::kOnset ? t.placement_start_s : t.placement_target_s;
  return l == Landmark::kOnset ? t.shape_start_s : t.shape_target_s;
}

const KeyTiming& Timing(const PhasingKeyRow& r, PhasingMethod m) {
  switch (m) {
    case PhasingMethod::kKinematic:
      return r.kinematic;
    case PhasingMethod::kPosterior:
      return r.posterior;
    case PhasingMethod::kTruth:
      break;
  }
  return r.truth;
}

nlohmann::json ToJson(const TimeSummary& s) {
  return {{"mean_ms", s.mean_ms}, {"sd_ms", s.sd_ms}, {"ci95_ms", s.ci95_ms}, {"count", s.count}};
}

std::string Num(double v, const char* format) {
  if (!std::isfinite(v)) return "";
  char buf[64];
  std::snprintf(buf, sizeof buf, format, v);
  return buf;
}

std::string CsvText(const std::string& s) {
  if (s.find_first_of(",\"\n") == std::string::npos) return s;
  std::string out = "\"";
  for (char c : s) {
    if (c == '"') out += '"';
    out += c;
  }
  return out + "\"";
}

}  // namespace

double StudentTTwoSided(double coverage, int dof) {
  if (dof < 1) throw InvalidInput("Student t: degrees of freedom must be >= 1");
  if (!(coverage > 0.0 && coverage < 1.0)) throw InvalidInput("Student t: coverage must be in (0, 1)");
  double lo = 0.0, hi = 1.0;
  while (TwoSidedCdf(hi, dof) < coverage) hi *= 2.0;
  for (int i = 0; i < 200 && hi - lo > 1e-12 * hi; ++i) {
    const double mid = 0.5 * (lo + hi);
    (TwoSidedCdf(mid, dof) < coverage ? lo : hi) = mid;
  }
  return 0.5 * (lo + hi);
}

TimeSummary SummariseTimes(const std::vector<double>& values) {
  TimeSummary s;
  double sum = 0.0;
  for (double v : values)
    if (std::isfinite(v)) {
      sum += v;
      ++s.count;
    }
  if (s.count == 0) return s;
  s.mean_ms = sum / s.count;
  if (s.count < 2) return s;
  double ss = 0.0;
  for (double v : values)
    if (std::isfinite(v)) ss += (v - s.mean_ms) * (v - s.mean_ms);
  s.sd_ms = std::sqrt(ss / (s.count - 1));
  s.ci95_ms = StudentTTwoSided(0.95, s.count - 1) * s.sd_ms / std::sqrt(static_cast<double>(s.count));
  return s;
}

Histogram MakeHistogram(const std::vector<double>& values, double first_ms, double bin_ms, int bins) {
  if (!(bin_ms > 0.0) || bins < 1) throw InvalidInput("histogram: need bin_ms > 0 and bins >= 1");
  Histogram h;
  h.first_ms = first_ms;
  h.bin_ms = bin_ms;
  h.counts.assign(static_cast<size_t>(bins), 0);
  for (double v : values) {
    if (!std::isfinite(v)) continue;
    const double i = std::floor((v - first_ms) / bin_ms);
    if (i < 0)
      ++h.below;
    else if (i >= bins)
      ++h.above;
    else
      ++h.counts[static_cast<size_t>(i)];
  }
  return h;
}

KeyTiming UnmeasuredTiming() { return {kNaN, kNaN, kNaN, kNaN}; }

double VowelOnset(const Key& key, const std::vector<Phone>& phones) {
  if (key.type != KeyType::kCV && key.type != KeyType::kVowelAlone) return kNaN;
  if (key.vowel_phone < 0 || key.vowel_phone >= static_cast<int>(phones.size()))
    return key.type == KeyType::kVowelAlone ? key.a1_s : kNaN;
  return phones[static_cast<size_t>(key.vowel_phone)].start_s;
}

const char* KeyTypeLabel(KeyType type) { return KeyTypeText(type); }

std::vector<double> RelativeTimesMs(const std::vector<PhasingKeyRow>& rows, PhasingMethod method,
                                    PhasingReference reference, KeyType type, Component component, Landmark landmark) {
  std::vector<double> out;
  for (const PhasingKeyRow& r : rows) {
    if (r.type != type) continue;
    const double ref = reference == PhasingReference::kA1 ? r.a1_s : r.vowel_onset_s;
    const double v = 1000.0 * (Pick(Timing(r, method), component, landmark) - ref);
    if (std::isfinite(v)) out.push_back(v);
  }
  return out;
}

PhasingSummary SummarisePhasing(const std::vector<PhasingKeyRow>& rows, PhasingMethod method,
                                PhasingReference reference) {
  const auto one = [&](KeyType type) {
    KeyTypeSummary s;
    const auto get = [&](Component c, Landmark l) {
      return SummariseTimes(RelativeTimesMs(rows, method, reference, type, c, l));
    };
    s.placement_onset = get(Component::kPlacement, Landmark::kOnset);
    s.placement_target = get(Component::kPlacement, Landmark::kTarget);
    s.shape_onset = get(Component::kShape, Landmark::kOnset);
    s.shape_target = get(Component::kShape, Landmark::kTarget);
    return s;
  };
  return {one(KeyType::kCV), one(KeyType::kVowelAlone), one(KeyType::kConsonantAlone)};
}

nlohmann::json PhasingSummaryToJson(const PhasingSummary& summary) {
  const auto one = [](const KeyTypeSummary& s) {
    return nlohmann::json{{"placement", {{"onset", ToJson(s.placement_onset)}, {"target", ToJson(s.placement_target)}}},
                          {"shape", {{"onset", ToJson(s.shape_onset)}, {"target", ToJson(s.shape_target)}}}};
  };
  return {{"CV", one(summary.cv)}, {"V", one(summary.v)}, {"C", one(summary.c)}};
}

std::string PhasingCsvHeader() {
  std::string h = "take,key,code,type,a1_s,vowel_onset_s";
  for (const char* m : {"kinematic", "posterior", "truth"})
    for (const char* c : {"placement_onset_s", "placement_target_s", "shape_onset_s", "shape_target_s"})
      h += std::string(",") + m + "_" + c;
  for (const char* m : {"kinematic", "posterior"})
    for (const char* c : {"placement_onset", "placement_target", "shape_onset", "shape_target"})
      h += std::string(",") + m + "_" + c + "_rel_a1_ms";
  return h;
}

std::string PhasingCsvRow(const PhasingKeyRow& r) {
  std::string s = CsvText(r.take) + "," + std::to_string(r.key_index) + "," + CsvText(r.code) + "," +
                  KeyTypeLabel(r.type) + "," + Num(r.a1_s, "%.4f") + "," + Num(r.vowel_onset_s, "%.4f");
  for (const KeyTiming* t : {&r.kinematic, &r.posterior, &r.truth})
    for (double v : {t->placement_start_s, t->placement_target_s, t->shape_start_s, t->shape_target_s})
      s += "," + Num(v, "%.4f");
  for (const KeyTiming* t : {&r.kinematic, &r.posterior})
    for (double v : {t->placement_start_s, t->placement_target_s, t->shape_start_s, t->shape_target_s})
      s += "," + Num(1000.0 * (v - r.a1_s), "%.1f");
  return s;
}

}  // namespace csw::phasing
