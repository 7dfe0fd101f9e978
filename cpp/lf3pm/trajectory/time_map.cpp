#include "lf3pm/trajectory/time_map.hpp"

#include <cmath>

namespace lf3pm {

double duration_from_tau(double tau) {
  return tau > 0.0 ? (0.5 * tau + 1.0) * tau + 1.0 : 1.0 / ((0.5 * tau - 1.0) * tau + 1.0);
}

double tau_from_duration(double duration) {
  return duration > 1.0 ? std::sqrt(2.0 * duration - 1.0) - 1.0 : 1.0 - std::sqrt(2.0 / duration - 1.0);
}

double duration_derivative(double tau) {
  if (tau > 0.0) return tau + 1.0;
  const double den = (0.5 * tau - 1.0) * tau + 1.0;
  return (1.0 - tau) / (den * den);
}

}  // namespace lf3pm
