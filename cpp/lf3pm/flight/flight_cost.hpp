// The sampled terms of a quadrotor's trajectory objective (the flight back end): at K + 1
// samples per piece of a quintic MINCO in (x, y, z, yaw), trapezoid-weighted in time,
//   w_q * q(x, y, z, yaw)                        guidance: the r3yaw SOLM's cost (level)
//   W * P(|v|^2 / vmax^2 - 1)                    speed
//   W * P(|omega|^2 / omega_max^2 - 1)           body rate (flatness map)
//   W * P((cos tilt_max - cos tilt) / (1 - cos tilt_max))   tilt (flatness map)
//   W * P(((f - f_mid) / f_half)^2 - 1)          thrust within [thrust_min, thrust_max]
//   W * P((r_safe + margin - esdf(p)) / 0.1 m)   clearance from the map's points
//   w_heading * (vx sin(yaw) - vy cos(yaw))^2      yaw along the velocity (the baseline
//                                                  planners'; the lateral speed in the
//                                                  heading's frame, zero at hover)
// with the cubic penalty P(z) = max(z, 0)^3 (C^2). The attitude, body rates and thrust come
// from the flatness map (flatness.hpp) and its gradients from its backward pass. The
// guidance is read at level attitude: docs/flight.md measures what the tilt changes.
#pragma once

#include <Eigen/Core>

#include "lf3pm/flight/flatness.hpp"
#include "lf3pm/flight/volume_field.hpp"
#include "lf3pm/trajectory/minco_s3.hpp"

namespace lf3pm {

struct FlightWeights {
  double w_q = 1.0;          ///< weight of the guidance cost's integral over time
  double penalty = 1e4;      ///< W: weight of the cubic feasibility penalties
  double r_safe = 0.4;       ///< clearance kept from the map's points, m
  double esdf_margin = 0.1;  ///< the clearance penalty starts at r_safe + margin
  int samples = 16;          ///< K: samples per piece (K + 1 with both ends)
  double w_heading = 0.0;    ///< weight of the yaw-along-velocity term (0: off)
};

/// Each sampled term's integral over time (before its weight), for reports.
struct FlightTerms {
  double guidance = 0, speed = 0, omega = 0, tilt = 0, thrust = 0, clearance = 0, heading = 0;
};

class FlightCost {
 public:
  /// `guidance` and `esdf` may be empty (no such term).
  FlightCost(const QuadrotorParams& params, const QuadrotorLimits& limits, const FlightWeights& weights,
             VolumeField guidance, VolumeField esdf);

  const QuadrotorLimits& limits() const { return limits_; }
  const FlightWeights& weights() const { return weights_; }

  /// The sampled terms of the trajectory with coefficients c (6N x 4) and durations T;
  /// their partial gradients are added to grad_c and grad_t; the terms into `terms`.
  double evaluate(const MincoS3::Coefficients& c, const Eigen::VectorXd& T, MincoS3::Coefficients& grad_c,
                  Eigen::VectorXd& grad_t, FlightTerms* terms = nullptr) const;

 private:
  FlatnessMap flatness_;
  QuadrotorLimits limits_;
  FlightWeights weights_;
  VolumeField guidance_, esdf_;
};

}  // namespace lf3pm
