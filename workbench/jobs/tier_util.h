#pragma once
// Looking up a take's label tiers by name, for the jobs.
#include <string>
#include <vector>

#include "core/take.h"

namespace csw::jobs {

// The tier of that name among a take's tiers, or nullptr.
const LabelTier* FindTier(const std::vector<LabelTier>& tiers, const std::string& name);
LabelTier* FindTier(std::vector<LabelTier>& tiers, const std::string& name);
// The tiers' names for messages: "'words', 'phones'", or "none".
std::string TierNames(const std::vector<LabelTier>& tiers);

}  // namespace csw::jobs
