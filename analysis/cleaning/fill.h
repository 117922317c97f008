#pragma once
// TEMPORARY copy (clean-structfill): the real fill.h is written by another helper;
// the lead drops this file on merge.
#include <cstdint>
#include <string>

#include "analysis/cleaning/gaps.h"
#include "core/take.h"

namespace csw::cleaning {

struct FillRecord {
  int marker;
  int64_t start;
  int64_t length;
  std::string method;
  std::string parameters;
};

struct GapFiller {
  virtual ~GapFiller() = default;
  virtual std::string name() const = 0;
  virtual bool CanFill(const MarkerArray& in, const Gap& gap, std::string* why_not) const = 0;
  virtual bool Fill(const MarkerArray& in, const Gap& gap, MarkerArray* out, FillRecord* record) const = 0;
};

}  // namespace csw::cleaning
