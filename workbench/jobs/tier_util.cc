#include "workbench/jobs/tier_util.h"

namespace csw::jobs {

const LabelTier* FindTier(const std::vector<LabelTier>& tiers, const std::string& name) {
  for (const LabelTier& t : tiers)
    if (t.name == name) return &t;
  return nullptr;
}

LabelTier* FindTier(std::vector<LabelTier>& tiers, const std::string& name) {
  for (LabelTier& t : tiers)
    if (t.name == name) return &t;
  return nullptr;
}

std::string TierNames(const std::vector<LabelTier>& tiers) {
  std::string s;
  for (const LabelTier& t : tiers) s += (s.empty() ? "'" : ", '") + t.name + "'";
  return s.empty() ? "none" : s;
}

}  // namespace csw::jobs
