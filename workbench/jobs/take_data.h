#pragma once
// Corpus side of the model jobs: the selected takes of a corpus and their
// markers in a model's order.
#include <string>
#include <vector>

#include "core/markerset.h"
#include "core/take.h"
#include "io/corpus/corpus.h"
#include "workbench/jobs/take_selection.h"

namespace csw::jobs {

// The corpus's takes (names and frame counts) for SelectTakes.
std::vector<TakeInfo> CorpusTakeInfos(const Corpus& corpus);

// SelectTakes on the corpus's takes, errors prefixed with the corpus path.
std::vector<TakeRange> SelectCorpusTakes(const Corpus& corpus, const std::vector<std::string>& arguments);

// Columns of `names` in a take with these labels, through the marker set
// (aliases, case, prefixes). InvalidInput listing every missing marker, prefixed by `where`.
std::vector<int> BindNames(const MarkerSet& set, const std::vector<std::string>& labels,
                           const std::vector<std::string>& names, const std::string& where);

// Frames [first, first + count) of the columns `cols` of `all`.
MarkerArray Extract(const MarkerArray& all, const std::vector<int>& cols, int64_t first, int64_t count);

// The range's frames of a corpus take, columns = `names` (model order).
MarkerArray LoadRange(const Corpus& corpus, const TakeRange& range, const MarkerSet& set,
                      const std::vector<std::string>& names);

}  // namespace csw::jobs
