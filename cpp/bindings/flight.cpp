// nanobind bindings of the flight stage (cpp/lf3pm/flight/): a quadrotor's parameters and
// limits, and its flatness map over arrays of samples (logic lives in cpp/lf3pm/).
#include <nanobind/eigen/dense.h>
#include <nanobind/nanobind.h>
#include <nanobind/ndarray.h>
#include <nanobind/stl/string.h>

#include <stdexcept>
#include <string>
#include <vector>

#include "bindings/numpy.hpp"
#include "lf3pm/flight/flatness.hpp"
#include "lf3pm/flight/flight_optimizer.hpp"
#include "lf3pm/flight/volume_field.hpp"

namespace nb = nanobind;
using namespace nb::literals;
using namespace lf3pm;
using lf3pm::bindings::to_numpy;

namespace {

using Rows3 = nb::ndarray<const double, nb::shape<-1, 3>, nb::c_contig, nb::device::cpu>;
using Rows33 = nb::ndarray<const double, nb::shape<-1, 3, 3>, nb::c_contig, nb::device::cpu>;
using Vec = nb::ndarray<const double, nb::ndim<1>, nb::c_contig, nb::device::cpu>;

// The samples' flat states; every array must hold n rows.
std::vector<FlatState> flat_states(Rows3 v, Rows3 a, Rows3 j, Vec yaw, Vec yaw_rate) {
  const std::size_t n = v.shape(0);
  if (a.shape(0) != n || j.shape(0) != n || yaw.shape(0) != n || yaw_rate.shape(0) != n)
    throw std::invalid_argument("velocity, acceleration, jerk, yaw and yaw_rate must hold one row per sample");
  std::vector<FlatState> out(n);
  for (std::size_t i = 0; i < n; ++i) {
    for (int d = 0; d < 3; ++d) {
      out[i].velocity[d] = v(i, d);
      out[i].acceleration[d] = a(i, d);
      out[i].jerk[d] = j(i, d);
    }
    out[i].yaw = yaw(i);
    out[i].yaw_rate = yaw_rate(i);
  }
  return out;
}

nb::dict terms_dict(const FlightTerms& t) {
  nb::dict d;
  d["guidance"] = t.guidance;
  d["speed"] = t.speed;
  d["omega"] = t.omega;
  d["tilt"] = t.tilt;
  d["thrust"] = t.thrust;
  d["clearance"] = t.clearance;
  d["heading"] = t.heading;
  return d;
}

std::string singular(std::size_t i) {
  return "sample " + std::to_string(i) + ": no thrust direction there (free fall or upside down)";
}

}  // namespace

void bind_flight(nb::module_& m) {
  nb::class_<QuadrotorParams>(m, "QuadrotorParams", "A quadrotor's mass, gravity and linear drag (the defaults).")
      .def(nb::init<>())
      .def_rw("mass", &QuadrotorParams::mass, "kg")
      .def_rw("gravity", &QuadrotorParams::gravity, "m/s^2")
      .def_rw("drag_h", &QuadrotorParams::drag_h, "Horizontal linear drag, N per m/s.")
      .def_rw("drag_v", &QuadrotorParams::drag_v, "Vertical linear drag, N per m/s.");
  nb::class_<QuadrotorLimits>(m, "QuadrotorLimits", "Flight limits (the defaults).")
      .def(nb::init<>())
      .def_rw("vmax", &QuadrotorLimits::vmax, "Speed, m/s.")
      .def_rw("omega_max", &QuadrotorLimits::omega_max, "Body rate, rad/s.")
      .def_rw("tilt_max", &QuadrotorLimits::tilt_max, "Tilt from the vertical, rad.")
      .def_rw("thrust_min", &QuadrotorLimits::thrust_min, "N")
      .def_rw("thrust_max", &QuadrotorLimits::thrust_max, "N");

  m.def(
      "flat_attitudes",
      [](const QuadrotorParams& params, Rows3 v, Rows3 a, Rows3 j, Vec yaw, Vec yaw_rate) {
        const std::vector<FlatState> states = flat_states(v, a, j, yaw, yaw_rate);
        const FlatnessMap map(params);
        const std::size_t n = states.size();
        std::vector<double> thrust(n), rotation(9 * n), omega(3 * n), cos_tilt(n);
        for (std::size_t i = 0; i < n; ++i) {
          FlatAttitude at;
          if (!map.forward(states[i], &at)) throw std::invalid_argument(singular(i));
          thrust[i] = at.thrust;
          cos_tilt[i] = at.cos_tilt;
          for (int r = 0; r < 3; ++r) {
            omega[3 * i + r] = at.omega[r];
            for (int c = 0; c < 3; ++c) rotation[9 * i + 3 * r + c] = at.rotation(r, c);
          }
        }
        nb::dict out;
        out["thrust"] = to_numpy(std::move(thrust));
        out["rotation"] = to_numpy(std::move(rotation), {n, 3, 3});
        out["omega"] = to_numpy(std::move(omega), {n, 3});
        out["cos_tilt"] = to_numpy(std::move(cos_tilt));
        return out;
      },
      "params"_a, "velocity"_a, "acceleration"_a, "jerk"_a, "yaw"_a, "yaw_rate"_a,
      "The flatness map at n samples: dict of thrust (n), rotation (n, 3, 3) body to world, omega (n, 3) body "
      "rates, cos_tilt (n).");

  m.def(
      "flat_gradients",
      [](const QuadrotorParams& params, Rows3 v, Rows3 a, Rows3 j, Vec yaw, Vec yaw_rate, Vec g_thrust,
         Rows33 g_rotation, Rows3 g_omega, Vec g_cos_tilt) {
        const std::vector<FlatState> states = flat_states(v, a, j, yaw, yaw_rate);
        const std::size_t n = states.size();
        if (g_thrust.shape(0) != n || g_rotation.shape(0) != n || g_omega.shape(0) != n || g_cos_tilt.shape(0) != n)
          throw std::invalid_argument("one gradient row per sample");
        const FlatnessMap map(params);
        std::vector<double> gv(3 * n), ga(3 * n), gj(3 * n), gyaw(n), grate(n);
        for (std::size_t i = 0; i < n; ++i) {
          FlatAttitude at;
          if (!map.forward(states[i], &at)) throw std::invalid_argument(singular(i));
          AttitudeGradient g;
          g.thrust = g_thrust(i);
          g.cos_tilt = g_cos_tilt(i);
          for (int r = 0; r < 3; ++r) {
            g.omega[r] = g_omega(i, r);
            for (int c = 0; c < 3; ++c) g.rotation(r, c) = g_rotation(i, r, c);
          }
          const FlatGradient d = map.backward(states[i], g);
          for (int r = 0; r < 3; ++r) {
            gv[3 * i + r] = d.velocity[r];
            ga[3 * i + r] = d.acceleration[r];
            gj[3 * i + r] = d.jerk[r];
          }
          gyaw[i] = d.yaw;
          grate[i] = d.yaw_rate;
        }
        nb::dict out;
        out["velocity"] = to_numpy(std::move(gv), {n, 3});
        out["acceleration"] = to_numpy(std::move(ga), {n, 3});
        out["jerk"] = to_numpy(std::move(gj), {n, 3});
        out["yaw"] = to_numpy(std::move(gyaw));
        out["yaw_rate"] = to_numpy(std::move(grate));
        return out;
      },
      "params"_a, "velocity"_a, "acceleration"_a, "jerk"_a, "yaw"_a, "yaw_rate"_a, "g_thrust"_a, "g_rotation"_a,
      "g_omega"_a, "g_cos_tilt"_a,
      "Gradients of a cost at n samples with respect to velocity, acceleration, jerk (n, 3), yaw and yaw_rate (n), "
      "from its gradients with respect to thrust, rotation, omega and cos_tilt.");

  nb::class_<VolumeField>(m, "VolumeField",
                          "Values over (x, y, z[, yaw bins]) interpolated linearly (volume_field.hpp).")
      .def(nb::init<>())
      .def(
          "__init__",
          [](VolumeField* self, Vec values, int nx, int ny, int nz, int bins, double x0, double y0, double z0,
             double res, double dz) {
            new (self) VolumeField(std::vector<double>(values.data(), values.data() + values.shape(0)), nx, ny, nz,
                                   bins, x0, y0, z0, res, dz);
          },
          "values"_a, "nx"_a, "ny"_a, "nz"_a, "bins"_a, "x0"_a, "y0"_a, "z0"_a, "res"_a, "dz"_a,
          "values[((iz * bins + ib) * ny + iy) * nx + ix]; cells centred at x0 + (ix + 0.5) res, y0 + (iy + 0.5) "
          "res, levels at z0 + iz dz, bins at ib 2 pi / bins.")
      .def(
          "sample",
          [](const VolumeField& f, Rows3 p, Vec yaw) {
            const std::size_t n = p.shape(0);
            if (yaw.shape(0) != n) throw std::invalid_argument("one yaw per point");
            std::vector<double> value(n), grad(4 * n);
            for (std::size_t i = 0; i < n; ++i) {
              Eigen::Vector4d g;
              value[i] = f.sample(Eigen::Vector3d(p(i, 0), p(i, 1), p(i, 2)), yaw(i), g);
              for (int k = 0; k < 4; ++k) grad[4 * i + k] = g(k);
            }
            return nb::make_tuple(to_numpy(std::move(value)), to_numpy(std::move(grad), {n, 4}));
          },
          "points"_a, "yaw"_a, "Values (n) and gradients (n, 4: d/dx, d/dy, d/dz, d/dyaw).");

  nb::class_<FlightWeights>(m, "FlightWeights", "Weights of the flight objective's sampled terms (the defaults).")
      .def(nb::init<>())
      .def_rw("w_q", &FlightWeights::w_q)
      .def_rw("penalty", &FlightWeights::penalty)
      .def_rw("r_safe", &FlightWeights::r_safe)
      .def_rw("esdf_margin", &FlightWeights::esdf_margin)
      .def_rw("samples", &FlightWeights::samples)
      .def_rw("w_heading", &FlightWeights::w_heading);

  nb::class_<FlightProblem>(m, "FlightProblem", "The flight back end's objective over a quintic MINCO.")
      .def(
          "__init__",
          [](FlightProblem* self, const QuadrotorParams& params, const QuadrotorLimits& limits,
             const FlightWeights& weights, const VolumeField& guidance, const VolumeField& esdf, double rho_t,
             double w_energy, double yaw_energy, const MincoS3::State& head, const MincoS3::State& tail,
             const MincoS3::Points& waypoints, const Eigen::VectorXd& durations) {
            new (self) FlightProblem(FlightCost(params, limits, weights, guidance, esdf), rho_t, w_energy, yaw_energy,
                                     head, tail, waypoints, durations);
          },
          "params"_a, "limits"_a, "weights"_a, "guidance"_a, "esdf"_a, "rho_t"_a, "w_energy"_a, "yaw_energy"_a,
          "head"_a, "tail"_a, "waypoints"_a, "durations"_a)
      .def_prop_ro("dimension", &FlightProblem::dimension)
      .def_prop_ro("initial", &FlightProblem::initial)
      .def(
          "evaluate",
          [](FlightProblem& p, const Eigen::VectorXd& x) {
            Eigen::VectorXd g;
            FlightTerms t;
            const double f = p.evaluate(x, g, &t);
            return nb::make_tuple(f, g, terms_dict(t));
          },
          "x"_a, "(objective, gradient, terms) at x.")
      .def(
          "trajectory",
          [](FlightProblem& p, const Eigen::VectorXd& x) {
            MincoS3::Coefficients c;
            Eigen::VectorXd t;
            p.trajectory(x, c, t);
            return nb::make_tuple(c, t);
          },
          "x"_a, "(coefficients 6N x 4, durations N) at x.")
      .def(
          "optimize",
          [](FlightProblem& p, const LbfgsParams& lbfgs) {
            FlightOutcome o;
            {
              nb::gil_scoped_release release;
              o = optimize_flight(p, lbfgs);
            }
            nb::dict d;
            d["x"] = o.x;
            d["iterations"] = o.iterations;
            d["evaluations"] = o.evaluations;
            d["f"] = o.f;
            d["status"] = o.status;
            d["reason"] = o.reason;
            d["terms"] = terms_dict(o.terms);
            return d;
          },
          "lbfgs"_a,
          "Minimise with L-BFGS from the initial point: dict of x, iterations, evaluations, status, reason, "
          "terms.");
}
