#include "core/progress.h"

#include "core/error.h"

namespace csw {

void Progress::Update(const std::string& stage, double fraction) {
  CheckCancel();
  if (sink_) sink_(stage, fraction);
}

void Progress::CheckCancel() const {
  if (cancelled_.load()) throw Cancelled();
}

}  // namespace csw
