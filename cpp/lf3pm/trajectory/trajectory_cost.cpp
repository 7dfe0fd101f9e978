#include "lf3pm/trajectory/trajectory_cost.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include "lf3pm/trajectory/travel_heading.hpp"

namespace lf3pm {

namespace {

// An intrusion of this many metres into the clearance counts as a relative excess of 1
// (as a speed at twice its limit's square): the clearance penalty's scale.
constexpr double kClearanceScale = 0.1;

// |omega| smoothed as sqrt(omega^2 + eps^2) - eps (rad/s): differentiable through zero.
constexpr double kTurnEps = 1e-2;

// Each sample's penalties weigh its share of the time plus this (s): at least one
// 100 Hz control period, however short its piece.
constexpr double kSampleFloor = 0.01;

// W * max(z, 0)^3 into `sum`; returns its derivative by z.
inline double cubic_penalty(double z, double weight, double& sum) {
  if (z <= 0.0) return 0.0;
  sum += weight * z * z * z;
  return 3.0 * weight * z * z;
}

}  // namespace

TrajectoryCost::TrajectoryCost(GridField cost, GridField esdf, const RobotLimits& robot, const CostWeights& weights)
    : cost_(std::move(cost)),
      esdf_(std::move(esdf)),
      robot_(robot),
      weights_(weights),
      head_clearance_(robot.r_safe + weights.esdf_margin),
      tail_clearance_(head_clearance_) {
  if (weights_.samples < 1) throw std::invalid_argument("samples per piece must be >= 1");
}

void TrajectoryCost::keep_ends(double head_x, double head_y, double tail_x, double tail_y) {
  const double clearance = robot_.r_safe + weights_.esdf_margin;
  head_clearance_ = tail_clearance_ = clearance;
  if (esdf_.empty()) return;
  Eigen::Vector3d unused;
  head_clearance_ = std::min(clearance, esdf_.sample(head_x, head_y, 0.0, unused));
  tail_clearance_ = std::min(clearance, esdf_.sample(tail_x, tail_y, 0.0, unused));
}

void TrajectoryCost::add(const Eigen::MatrixX3d& coef, const Eigen::VectorXd& durations, Eigen::MatrixX3d& grad_c,
                         Eigen::VectorXd& grad_t, CostTerms& terms) const {
  const int n = static_cast<int>(durations.size()), k_max = weights_.samples;
  const double w = weights_.penalty;
  // Speed limits are penalised relative to the limit (z = v^2 / vmax^2 - 1), so that
  // the same weight allows the same relative excess on every limit.
  const double ilon2 = 1.0 / (robot_.vmax_lon * robot_.vmax_lon), ilat2 = 1.0 / (robot_.vmax_lat * robot_.vmax_lat);
  const double inorm2 = robot_.vmax_norm > 0.0 ? 1.0 / (robot_.vmax_norm * robot_.vmax_norm) : 0.0;
  const double iw2 = 1.0 / (robot_.wmax * robot_.wmax), r2 = robot_.min_turn_radius * robot_.min_turn_radius;
  const double ialon2 = 1.0 / (robot_.amax_lon * robot_.amax_lon), ialat2 = 1.0 / (robot_.amax_lat * robot_.amax_lat);
  const double ialpha2 = 1.0 / (robot_.alpha_max * robot_.alpha_max);
  const double clearance = robot_.r_safe + weights_.esdf_margin;
  const bool car = robot_.kind == RobotKind::Car && robot_.min_turn_radius > 0.0;  // a turning radius
  const bool straight = robot_.straight_ends();
  const bool flat = robot_.nonholonomic();
  // A robot keeps moving between its straight ends (pieces 0 and n - 1): at least
  // v_min = 0.1 vmax_lon. Slower, it could reverse through a cusp, its heading flipping
  // between two samples.
  const double ivmin2 = 1.0 / (1e-2 * robot_.vmax_lon * robot_.vmax_lon);
  // The rational limits' regulariser eps = (0.01 vmax_lon)^2 keeps them finite at rest (the
  // straight ends, where they are exactly zero) yet within 2 % of the true ratios at v_min.
  const double eps = 1e-4 * robot_.vmax_lon * robot_.vmax_lon;
  Eigen::Vector3d field_grad;

  for (int i = 0; i < n; ++i) {
    const Eigen::Matrix<double, 4, 3> c = coef.middleRows<4>(4 * i);
    const double dur = durations(i), dt = dur / k_max;
    // The fixed ends' pieces keep at most the clearance the ends have (keep_ends).
    double kept = clearance;
    if (i == 0) kept = std::min(kept, head_clearance_);
    if (i == n - 1) kept = std::min(kept, tail_clearance_);
    Eigen::Matrix<double, 4, 3> gc = Eigen::Matrix<double, 4, 3>::Zero();
    double gt = 0.0;
    const Eigen::Vector3d jerk = 6.0 * c.row(3).transpose();
    const double scale = velocity_scale(c.row(1).head<2>(), c.row(2).head<2>(), c.row(3).head<2>(), dur);
    for (int j = 0; j <= k_max; ++j) {
      const double alpha = double(j) / k_max, t = alpha * dur;
      const Eigen::Vector4d b0(1.0, t, t * t, t * t * t), b1(0.0, 1.0, 2.0 * t, 3.0 * t * t),
          b2(0.0, 0.0, 2.0, 6.0 * t);
      const Eigen::Vector3d p = c.transpose() * b0, v = c.transpose() * b1, a = c.transpose() * b2;
      // Partial gradients by position, velocity, acceleration and jerk: of the penalties,
      // and (q*) of the cost field's term, which is weighted differently (below).
      Eigen::Vector3d gp = Eigen::Vector3d::Zero(), gv = Eigen::Vector3d::Zero(), ga = Eigen::Vector3d::Zero(),
                      gj = Eigen::Vector3d::Zero();
      Eigen::Vector3d qp = Eigen::Vector3d::Zero(), qv = Eigen::Vector3d::Zero(), qa = Eigen::Vector3d::Zero();
      CostTerms f;
      if (flat) {
        // Flat output: yaw = atan2(ydot, xdot); s = |v|^2, cr = v x a (omega = cr / s).
        const double s2 = v(0) * v(0) + v(1) * v(1), cr = v(0) * a(1) - v(1) * a(0);
        if (!cost_.empty() && weights_.w_q != 0.0) {
          const TravelHeading h = travel_heading(v.head<2>(), a.head<2>(), jerk.head<2>(), alpha > 0.5, scale);
          const double u2 = h.u.squaredNorm();
          f.q = weights_.w_q * cost_.sample(p(0), p(1), h.yaw, field_grad);
          qp(0) += weights_.w_q * field_grad(0), qp(1) += weights_.w_q * field_grad(1);
          if (u2 > 1e-18) {  // d yaw / d u = (-u_y, u_x) / |u|^2, whatever the sign (none from a u ~ 0)
            const double dy = weights_.w_q * field_grad(2) / u2;
            Eigen::Vector3d& gu = h.rest ? qa : qv;
            gu(0) -= dy * h.u(1), gu(1) += dy * h.u(0);
          }
        }
        double d = ilon2 * cubic_penalty(s2 * ilon2 - 1.0, w, f.velocity);
        if (straight && i > 0 && i < n - 1) d -= ivmin2 * cubic_penalty(1.0 - s2 * ivmin2, w, f.velocity);
        gv(0) += 2.0 * d * v(0), gv(1) += 2.0 * d * v(1);
        // Relative excesses, regularised at rest by eps (omega and curvature are
        // undefined there): z = (cr^2 - wmax^2 s^2) / (wmax^2 (s + eps)^2) ~ omega^2 / wmax^2 - 1
        // and z = (R^2 cr^2 - s^3) / (s + eps)^3 ~ R^2 curvature^2 - 1 when moving.
        // dcr/dv = (ay, -ax), dcr/da = (-vy, vx), ds/dv = 2 v.
        const Eigen::Vector2d dcr_dv(a(1), -a(0)), dcr_da(-v(1), v(0)), ds_dv(2.0 * v(0), 2.0 * v(1));
        const double w2 = robot_.wmax * robot_.wmax, se = s2 + eps, se2 = se * se;
        {
          const double num = cr * cr - w2 * s2 * s2, den = w2 * se2;
          const double dz = cubic_penalty(num / den, w, f.omega);
          const Eigen::Vector2d gzv =
              (2.0 * cr * dcr_dv - 2.0 * w2 * s2 * ds_dv) / den - (num / den) * (2.0 / se) * ds_dv;
          gv.head<2>() += dz * gzv, ga.head<2>() += dz * (2.0 * cr / den) * dcr_da;
        }
        if (car) {
          const double num = r2 * cr * cr - s2 * s2 * s2, den = se2 * se;
          const double dz = cubic_penalty(num / den, w, f.turn);
          const Eigen::Vector2d gzv =
              (2.0 * r2 * cr * dcr_dv - 3.0 * s2 * s2 * ds_dv) / den - (num / den) * (3.0 / se) * ds_dv;
          gv.head<2>() += dz * gzv, ga.head<2>() += dz * (2.0 * r2 * cr / den) * dcr_da;
        }
        {
          // Centripetal a_lat^2 = cr^2 / s and tangential a_lon^2 = |a|^2 - cr^2 / s, both with
          // s regularised to s + eps; d(cr^2 / se)/dv = (2 cr dcr_dv se - cr^2 ds_dv) / se^2.
          const double lat2 = cr * cr / se;
          const Eigen::Vector2d dlat2_dv = (2.0 * cr * dcr_dv - lat2 * ds_dv) / se;
          const Eigen::Vector2d dlat2_da = (2.0 * cr / se) * dcr_da;
          double dz = ialat2 * cubic_penalty(lat2 * ialat2 - 1.0, w, f.acceleration);
          gv.head<2>() += dz * dlat2_dv, ga.head<2>() += dz * dlat2_da;
          const double a2 = a(0) * a(0) + a(1) * a(1);
          dz = ialon2 * cubic_penalty((a2 - lat2) * ialon2 - 1.0, w, f.acceleration);
          gv.head<2>() -= dz * dlat2_dv, ga.head<2>() += dz * (2.0 * a.head<2>() - dlat2_da);
          // Yaw acceleration alpha = d(cr / s)/dt = N / s^2, N = (v x j) s - 2 cr (v . a), regularised
          // as N / (s + eps)^2.
          const double cj = v(0) * jerk(1) - v(1) * jerk(0), dot = v(0) * a(0) + v(1) * a(1);
          const double num = cj * s2 - 2.0 * cr * dot, se4 = se2 * se2;
          const Eigen::Vector2d dcj_dv(jerk(1), -jerk(0)), dcj_dj(-v(1), v(0));
          const Eigen::Vector2d dnum_dv = dcj_dv * s2 + cj * ds_dv - 2.0 * dot * dcr_dv - 2.0 * cr * a.head<2>();
          const Eigen::Vector2d dnum_da = -2.0 * dot * dcr_da - 2.0 * cr * v.head<2>();
          const double z = num * num / se4 * ialpha2;
          dz = cubic_penalty(z - 1.0, w, f.acceleration);
          gv.head<2>() += dz * (2.0 * num / se4 * ialpha2 * dnum_dv - (4.0 * z / se) * ds_dv);
          ga.head<2>() += dz * (2.0 * num / se4 * ialpha2) * dnum_da;
          gj.head<2>() += dz * (2.0 * num / se4 * ialpha2 * s2) * dcj_dj;
        }
      } else {
        const double cy = std::cos(p(2)), sy = std::sin(p(2));
        const double v_lon = v(0) * cy + v(1) * sy, v_lat = -v(0) * sy + v(1) * cy;
        if (!cost_.empty() && weights_.w_q != 0.0) {
          f.q = weights_.w_q * cost_.sample(p(0), p(1), p(2), field_grad);
          qp += weights_.w_q * field_grad;
        }
        if (weights_.turn > 0.0) {
          // The turn's price: turn (w_time + w_q c) |omega|, with qp so far w_q grad c.
          const double root = std::sqrt(v(2) * v(2) + kTurnEps * kTurnEps), rate = root - kTurnEps;
          const double price = weights_.turn * (weights_.w_time + f.q);
          qv(2) += price * v(2) / root;
          qp *= 1.0 + weights_.turn * rate;
          f.q += price * rate;
        }
        // d v_lon / d(xdot, ydot, yaw) = (cos, sin | v_lat); d v_lat = (-sin, cos | -v_lon).
        double d = 2.0 * v_lon * ilon2 * cubic_penalty(v_lon * v_lon * ilon2 - 1.0, w, f.velocity);
        gv(0) += d * cy, gv(1) += d * sy, gp(2) += d * v_lat;
        d = 2.0 * v_lat * ilat2 * cubic_penalty(v_lat * v_lat * ilat2 - 1.0, w, f.velocity);
        gv(0) -= d * sy, gv(1) += d * cy, gp(2) -= d * v_lon;
        if (inorm2 > 0.0) {
          d = 2.0 * inorm2 * cubic_penalty((v(0) * v(0) + v(1) * v(1)) * inorm2 - 1.0, w, f.velocity);
          gv(0) += d * v(0), gv(1) += d * v(1);
        }
        gv(2) += 2.0 * v(2) * iw2 * cubic_penalty(v(2) * v(2) * iw2 - 1.0, w, f.omega);
        // Body-frame acceleration: d a_lon / d(a, yaw) = (cos, sin | a_lat), d a_lat = (-sin, cos | -a_lon).
        const double a_lon = a(0) * cy + a(1) * sy, a_lat = -a(0) * sy + a(1) * cy;
        d = 2.0 * a_lon * ialon2 * cubic_penalty(a_lon * a_lon * ialon2 - 1.0, w, f.acceleration);
        ga(0) += d * cy, ga(1) += d * sy, gp(2) += d * a_lat;
        d = 2.0 * a_lat * ialat2 * cubic_penalty(a_lat * a_lat * ialat2 - 1.0, w, f.acceleration);
        ga(0) -= d * sy, ga(1) += d * cy, gp(2) -= d * a_lon;
        ga(2) += 2.0 * a(2) * ialpha2 * cubic_penalty(a(2) * a(2) * ialpha2 - 1.0, w, f.acceleration);
      }
      if (!esdf_.empty()) {
        const double dist = esdf_.sample(p(0), p(1), 0.0, field_grad);
        // In units of kClearanceScale, so that an intrusion weighs like the relative excesses above.
        const double dc = cubic_penalty((kept - dist) / kClearanceScale, w, f.esdf) / kClearanceScale;
        gp(0) -= dc * field_grad(0), gp(1) -= dc * field_grad(1);
      }

      // Trapezoid weight wt = dt (dt / 2 at the ends); t = alpha T moves with T. The
      // penalties weigh wt + kSampleFloor: a short piece (a straight end can shrink to a
      // few hundredths of a second) must not hide its violations.
      const double wt = (j == 0 || j == k_max) ? 0.5 * dt : dt, wp = wt + kSampleFloor;
      const double penalties = f.velocity + f.omega + f.acceleration + f.turn + f.esdf;
      terms.q += wt * f.q, terms.velocity += wp * f.velocity, terms.omega += wp * f.omega;
      terms.acceleration += wp * f.acceleration, terms.turn += wp * f.turn, terms.esdf += wp * f.esdf;
      // The jerk 6 c3 is constant on a piece: its time derivative adds nothing to gt.
      gc.noalias() += wt * (b0 * qp.transpose() + b1 * qv.transpose() + b2 * qa.transpose()) +
                      wp * (b0 * gp.transpose() + b1 * gv.transpose() + b2 * ga.transpose());
      gc.row(3) += wp * 6.0 * gj.transpose();
      gt += (f.q + penalties) * wt / dur +
            alpha * (wt * (qp.dot(v) + qv.dot(a) + qa.dot(jerk)) + wp * (gp.dot(v) + gv.dot(a) + ga.dot(jerk)));
    }
    grad_c.middleRows<4>(4 * i) += gc;
    grad_t(i) += gt;
  }
}

}  // namespace lf3pm
