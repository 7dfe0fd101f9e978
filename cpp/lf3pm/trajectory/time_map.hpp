// The time map: GCOPTER's C^2 diffeomorphism from the real line to durations T > 0,
// so that the optimiser moves unconstrained variables tau and every piece keeps T > 0:
//   T = tau^2 / 2 + tau + 1 for tau > 0,   T = 1 / (tau^2 / 2 - tau + 1) otherwise.
#pragma once

namespace lf3pm {

/// T(tau).
double duration_from_tau(double tau);
/// Its inverse.
double tau_from_duration(double duration);
/// dT / dtau.
double duration_derivative(double tau);

}  // namespace lf3pm
