#include "datasets/motion.h"

namespace csw {

double MinimumJerk(double tau) {
  if (!(tau > 0.0)) return 0.0;
  if (tau >= 1.0) return 1.0;
  double t3 = tau * tau * tau;
  return t3 * (10.0 + tau * (-15.0 + 6.0 * tau));
}

double MinimumJerkRate(double tau) {
  if (!(tau > 0.0) || tau >= 1.0) return 0.0;
  double t2 = tau * tau;
  return 30.0 * t2 * (1.0 - 2.0 * tau + t2);
}

Eigen::VectorXd Superpose(const Eigen::VectorXd& initial, const std::vector<Gesture>& gestures, double t) {
  Eigen::VectorXd v = initial;
  for (const Gesture& g : gestures) {
    double span = g.target_s - g.start_s;
    double s = span > 0.0 ? MinimumJerk((t - g.start_s) / span) : (t >= g.target_s ? 1.0 : 0.0);
    if (s != 0.0) v += s * g.delta;
  }
  return v;
}

Eigen::VectorXd SuperposeRate(const std::vector<Gesture>& gestures, Eigen::Index size, double t) {
  Eigen::VectorXd v = Eigen::VectorXd::Zero(size);
  for (const Gesture& g : gestures) {
    double span = g.target_s - g.start_s;
    if (span <= 0.0) continue;
    double r = MinimumJerkRate((t - g.start_s) / span) / span;
    if (r != 0.0) v += r * g.delta;
  }
  return v;
}

}  // namespace csw
