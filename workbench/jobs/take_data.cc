#include "workbench/jobs/take_data.h"

#include <algorithm>

#include "core/error.h"

namespace csw::jobs {

std::vector<TakeInfo> CorpusTakeInfos(const Corpus& corpus) {
  std::vector<TakeInfo> out;
  for (const TakeSummary& s : corpus.Takes()) out.push_back({s.name, s.frames});
  return out;
}

std::vector<TakeRange> SelectCorpusTakes(const Corpus& corpus, const std::vector<std::string>& arguments) {
  return SelectTakes(CorpusTakeInfos(corpus), arguments, corpus.path());
}

std::vector<int> BindNames(const MarkerSet& set, const std::vector<std::string>& labels,
                           const std::vector<std::string>& names, const std::string& where) {
  const MarkerBinding b = BindMarkerSet(set, labels, false, where);
  std::vector<int> cols;
  std::vector<std::string> missing;
  for (const auto& n : names) {
    auto it = b.index.find(n);
    if (it == b.index.end()) {
      missing.push_back(n);
      continue;
    }
    cols.push_back(it->second);
  }
  if (!missing.empty()) {
    std::string list;
    for (const auto& m : missing) list += (list.empty() ? "" : ", ") + m;
    throw InvalidInput(where + ": the take has no marker " + list + " (marker set \"" + set.name + "\")");
  }
  return cols;
}

MarkerArray Extract(const MarkerArray& all, const std::vector<int>& cols, int64_t first, int64_t count) {
  MarkerArray out(count, static_cast<int64_t>(cols.size()));
  for (int64_t f = 0; f < count; ++f) {
    for (size_t c = 0; c < cols.size(); ++c) {
      const float* p = all.at(first + f, cols[c]);
      std::copy(p, p + 3, out.at(f, static_cast<int64_t>(c)));
    }
  }
  return out;
}

MarkerArray LoadRange(const Corpus& corpus, const TakeRange& range, const MarkerSet& set,
                      const std::vector<std::string>& names) {
  const Take take = corpus.LoadTake(range.take);
  const std::vector<int> cols = BindNames(set, take.marker_names, names, corpus.path() + ": take '" + range.take + "'");
  return Extract(take.markers, cols, range.first, range.count);
}

}  // namespace csw::jobs
