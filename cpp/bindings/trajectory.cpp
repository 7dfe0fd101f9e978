// nanobind bindings of the trajectory back end: grid fields, MINCO, L-BFGS and
// the trajectory optimiser (logic lives in cpp/lf3pm/).
#include <nanobind/eigen/dense.h>
#include <nanobind/nanobind.h>
#include <nanobind/ndarray.h>
#include <nanobind/stl/function.h>
#include <nanobind/stl/optional.h>
#include <nanobind/stl/string.h>

#include <stdexcept>
#include <vector>

#include "bindings/numpy.hpp"
#include "lf3pm/planner/grid_field.hpp"
#include "lf3pm/trajectory/lbfgs.hpp"
#include "lf3pm/trajectory/minco.hpp"
#include "lf3pm/trajectory/minco_s3.hpp"
#include "lf3pm/trajectory/trajectory_cost.hpp"
#include "lf3pm/trajectory/trajectory_optimizer.hpp"
#include "lf3pm/trajectory/travel_heading.hpp"

namespace nb = nanobind;
using namespace nb::literals;
using namespace lf3pm;

namespace {

using Vec = nb::ndarray<const double, nb::ndim<1>, nb::c_contig, nb::device::cpu>;
using Mat3 = nb::ndarray<const double, nb::shape<-1, 3>, nb::c_contig, nb::device::cpu>;
using Mat32 = nb::ndarray<const double, nb::shape<3, 2>, nb::c_contig, nb::device::cpu>;

Eigen::VectorXd to_vector(Vec v) { return Eigen::Map<const Eigen::VectorXd>(v.data(), v.shape(0)); }

Eigen::Matrix<double, 3, 2> to_state(Mat32 m) {
  Eigen::Matrix<double, 3, 2> s;
  for (int r = 0; r < 3; ++r)
    for (int c = 0; c < 2; ++c) s(r, c) = m(r, c);
  return s;
}

// (K, 3) row-major waypoints -> 3 x K.
Eigen::Matrix3Xd to_points(Mat3 m) {
  return Eigen::Map<const Eigen::Matrix3Xd>(m.data(), 3, static_cast<Eigen::Index>(m.shape(0)));
}

// 4N x 3 coefficients -> (N, 4, 3) numpy array.
nb::ndarray<nb::numpy, double> coefficients_array(const Eigen::MatrixX3d& c) {
  const std::size_t n = static_cast<std::size_t>(c.rows() / 4);
  std::vector<double> flat(c.rows() * 3);
  for (Eigen::Index r = 0; r < c.rows(); ++r)
    for (int d = 0; d < 3; ++d) flat[3 * r + d] = c(r, d);
  return lf3pm::bindings::to_numpy(std::move(flat), {n, 4, 3});
}

nb::dict terms_dict(const CostTerms& t) {
  nb::dict d;
  d["q"] = t.q;
  d["velocity"] = t.velocity;
  d["omega"] = t.omega;
  d["acceleration"] = t.acceleration;
  d["turn"] = t.turn;
  d["esdf"] = t.esdf;
  d["time"] = t.time;
  d["energy"] = t.energy;
  d["total"] = t.total();
  return d;
}

}  // namespace

void bind_trajectory(nb::module_& m) {
  nb::class_<GridField>(m, "GridField",
                        "Regular (x, y[, periodic yaw]) grid with bilinear/trilinear interpolation and gradient.")
      .def(
          "__init__",
          [](GridField* self, nb::ndarray<const double, nb::c_contig, nb::device::cpu> values, double x0, double y0,
             double res) {
            if (values.ndim() != 2 && values.ndim() != 3)
              throw std::invalid_argument("grid values must be (ny, nx) or (yaw_bins, ny, nx)");
            const bool three = values.ndim() == 3;
            const int layers = three ? int(values.shape(0)) : 1;
            const int ny = int(values.shape(three ? 1 : 0)), nx = int(values.shape(three ? 2 : 1));
            std::vector<double> v(values.data(), values.data() + values.size());
            new (self) GridField(std::move(v), nx, ny, layers, x0, y0, res);
          },
          "values"_a, "x0"_a, "y0"_a, "res"_a)
      .def_prop_ro("layers", &GridField::layers)
      .def(
          "sample",
          [](const GridField& f, Vec x, Vec y, Vec yaw) {
            const std::size_t n = x.shape(0);
            if (y.shape(0) != n || yaw.shape(0) != n) throw std::invalid_argument("x, y, yaw lengths differ");
            Eigen::VectorXd value(n);
            Eigen::Matrix<double, -1, 3, Eigen::RowMajor> grad(n, 3);
            Eigen::Vector3d gr;
            for (std::size_t i = 0; i < n; ++i) {
              value(i) = f.sample(x(i), y(i), yaw(i), gr);
              grad.row(i) = gr.transpose();
            }
            return nb::make_tuple(value, grad);
          },
          "x"_a, "y"_a, "yaw"_a, "Values (n,) and gradients (n, 3: d/dx, d/dy, d/dyaw) at the points.");

  m.def(
      "minco_s2",
      [](nb::ndarray<const double, nb::shape<3, -1>, nb::c_contig, nb::device::cpu> head,
         nb::ndarray<const double, nb::shape<3, -1>, nb::c_contig, nb::device::cpu> tail, Mat3 waypoints,
         Vec durations) {
        // (3, 2): position and velocity; (3, 3): and the acceleration.
        auto state = [](const auto& m) {
          if (m.shape(1) != 2 && m.shape(1) != 3) throw std::invalid_argument("an end state is (3, 2) or (3, 3)");
          MincoS2::State s = MincoS2::State::Zero();
          for (int r = 0; r < 3; ++r)
            for (std::size_t c = 0; c < m.shape(1); ++c) s(r, c) = m(r, c);
          return s;
        };
        MincoS2 minco;
        minco.set_conditions(state(head), state(tail), int(durations.shape(0)), head.shape(1) == 3, tail.shape(1) == 3);
        minco.set_parameters(to_points(waypoints), to_vector(durations));
        return nb::make_tuple(coefficients_array(minco.coefficients()), minco.energy());
      },
      "head"_a, "tail"_a, "waypoints"_a, "durations"_a,
      "Cubic MINCO: (coefficients (N, 4, 3), acceleration energy) from head/tail (3 x 2: position, velocity; "
      "3 x 3: and acceleration, which frees the neighbouring junction's waypoint), the free intermediate "
      "waypoints (K, 3) and durations (N,).");

  m.def(
      "minco_s3",
      [](const MincoS3::State& head, const MincoS3::State& tail, const MincoS3::Points& waypoints, Vec durations,
         const Eigen::Vector4d& weights, std::optional<MincoS3::Coefficients> grad_c,
         std::optional<Eigen::VectorXd> grad_t) {
        MincoS3 minco;
        minco.set_conditions(head, tail, int(durations.shape(0)));
        minco.set_parameters(waypoints, to_vector(durations));
        nb::dict out;
        out["coefficients"] = minco.coefficients();
        out["jerk_energy"] = minco.jerk_energy(weights);
        MincoS3::Coefficients ec = MincoS3::Coefficients::Zero(minco.coefficients().rows(), MincoS3::kDims);
        Eigen::VectorXd et = Eigen::VectorXd::Zero(minco.pieces());
        minco.add_jerk_energy_gradient(weights, ec, et);
        out["energy_grad_c"] = ec;
        out["energy_grad_t"] = et;
        if (grad_c) {
          if (grad_c->rows() != minco.coefficients().rows() || !grad_t || grad_t->size() != minco.pieces())
            throw std::invalid_argument("grad_c must be 6N x 4 and grad_t N");
          MincoS3::Points gq;
          Eigen::VectorXd gT;
          minco.propagate_gradient(*grad_c, *grad_t, gq, gT);
          out["grad_q"] = gq;
          out["grad_T"] = gT;
        }
        return out;
      },
      "head"_a, "tail"_a, "waypoints"_a, "durations"_a, "weights"_a, "grad_c"_a = nb::none(), "grad_t"_a = nb::none(),
      "Quintic MINCO in (x, y, z, yaw) (minco_s3.hpp): from head/tail (4 x 3: position, velocity, acceleration), "
      "waypoints (4 x (N - 1)) and durations (N), a dict of coefficients (6N x 4), jerk_energy with per-dimension "
      "weights (4) and its partial gradients (energy_grad_c, energy_grad_t); given partial gradients of a cost by c "
      "and T, also its total gradients grad_q (4 x (N - 1)) and grad_T (N).");

  m.def(
      "travel_heading",
      [](nb::ndarray<const double, nb::shape<-1, 4, 3>, nb::c_contig, nb::device::cpu> c, Vec tau, Vec durations) {
        const std::size_t n = c.shape(0);
        if (tau.shape(0) != n || durations.shape(0) != n)
          throw std::invalid_argument("travel_heading: c, tau and durations must have one row per sample");
        std::vector<double> yaw(n), omega(n);
        for (std::size_t i = 0; i < n; ++i) {
          const double t = tau(i), d = durations(i);
          Eigen::Vector2d c1, c2, c3, v, a, j;
          for (int k = 0; k < 2; ++k) {
            c1(k) = c(i, 1, k), c2(k) = c(i, 2, k), c3(k) = c(i, 3, k);
            v(k) = c1(k) + t * (2.0 * c2(k) + t * (3.0 * c3(k)));  // Horner, as Trajectory's positions
            a(k) = 2.0 * c2(k) + t * (6.0 * c3(k));
            j(k) = 6.0 * c3(k);
          }
          const TravelHeading h = travel_heading(v, a, j, t > 0.5 * d, velocity_scale(c1, c2, c3, d));
          yaw[i] = h.yaw, omega[i] = h.omega;
        }
        return nb::make_tuple(lf3pm::bindings::to_numpy(std::move(yaw)), lf3pm::bindings::to_numpy(std::move(omega)));
      },
      "c"_a, "tau"_a, "durations"_a,
      "The flat map of a nonholonomic robot (travel_heading.hpp): yaw = atan2(ydot, xdot) and its rate on "
      "cubic pieces c (n, 4, 3) at local times tau (n,) of pieces of the given durations (n,), with the "
      "limits at rest. Returns (yaw, omega), each (n,).");

  nb::class_<LbfgsParams>(m, "LbfgsParams", "L-BFGS parameters (the defaults; see lbfgs.hpp).")
      .def(nb::init<>())
      .def_rw("memory", &LbfgsParams::memory, "Stored correction pairs.")
      .def_rw("g_epsilon", &LbfgsParams::g_epsilon, "Stop when |g| <= g_epsilon max(1, |x|).")
      .def_rw("past", &LbfgsParams::past, "Stop when f fell by less than delta max(1, |f|) over `past` iterations.")
      .def_rw("delta", &LbfgsParams::delta)
      .def_rw("max_iterations", &LbfgsParams::max_iterations, "0: no limit.")
      .def_rw("max_linesearch", &LbfgsParams::max_linesearch);
  m.def("trajectory_lbfgs", &trajectory_lbfgs, "The L-BFGS parameters the trajectory optimiser uses by default.");

  m.def(
      "lbfgs_minimize",
      [](const std::function<nb::tuple(const Eigen::VectorXd&)>& fun, Vec x0, const LbfgsParams& params) {
        Eigen::VectorXd x = to_vector(x0);
        const Objective f = [&fun](const Eigen::VectorXd& xv, Eigen::VectorXd& g) {
          const nb::tuple r = fun(xv);
          g = nb::cast<Eigen::VectorXd>(r[1]);
          if (g.size() != xv.size()) throw std::invalid_argument("gradient has the wrong size");
          return nb::cast<double>(r[0]);
        };
        const LbfgsResult r = lbfgs_minimize(f, x, params);
        nb::dict out;
        out["x"] = x;
        out["f"] = r.f;
        out["iterations"] = r.iterations;
        out["evaluations"] = r.evaluations;
        out["gradient_norm"] = r.gradient_norm;
        out["status"] = std::string(to_string(r.status));
        out["reason"] = r.reason;
        return out;
      },
      "fun"_a, "x0"_a, "params"_a = LbfgsParams(),
      "Minimise fun(x) -> (f, gradient) with our L-BFGS (weak Wolfe line search).");

  nb::enum_<RobotKind>(m, "RobotKind")
      .value("omni", RobotKind::Omni)
      .value("diff", RobotKind::Diff)
      .value("car", RobotKind::Car);

  nb::class_<RobotLimits>(m, "RobotLimits", "A ground robot's kind and kinematic limits (SI units; the defaults).")
      .def(nb::init<>())
      .def_rw("kind", &RobotLimits::kind)
      .def_rw("vmax_lon", &RobotLimits::vmax_lon)
      .def_rw("vmax_lat", &RobotLimits::vmax_lat)
      .def_rw("wmax", &RobotLimits::wmax)
      .def_rw("amax_lon", &RobotLimits::amax_lon)
      .def_rw("amax_lat", &RobotLimits::amax_lat)
      .def_rw("alpha_max", &RobotLimits::alpha_max)
      .def_rw("min_turn_radius", &RobotLimits::min_turn_radius)
      .def_rw("vmax_norm", &RobotLimits::vmax_norm)
      .def_rw("r_safe", &RobotLimits::r_safe);

  nb::class_<CostWeights>(m, "CostWeights", "Weights of the trajectory objective's sampled terms (the defaults).")
      .def(nb::init<>())
      .def_rw("w_q", &CostWeights::w_q)
      .def_rw("penalty", &CostWeights::penalty)
      .def_rw("esdf_margin", &CostWeights::esdf_margin)
      .def_rw("samples", &CostWeights::samples)
      .def_rw("turn", &CostWeights::turn)
      .def_rw("w_time", &CostWeights::w_time);

  nb::class_<TrajectoryProblem>(m, "TrajectoryProblem",
                                "The LF-3PM trajectory objective over x = [waypoints (3 per), tau (1 per piece), car: "
                                "2 x 3 straight-end parameters].")
      .def(
          "__init__",
          [](TrajectoryProblem* self, const GridField* cost, const GridField* esdf, const RobotLimits& robot,
             const CostWeights& weights, double rho_t, double w_energy, Mat32 head, Mat32 tail, Mat3 waypoints,
             Vec durations) {
            TrajectoryCost tc(cost ? *cost : GridField(), esdf ? *esdf : GridField(), robot, weights);
            new (self) TrajectoryProblem(std::move(tc), rho_t, w_energy, to_state(head), to_state(tail),
                                         to_points(waypoints), to_vector(durations));
          },
          "cost"_a.none(), "esdf"_a.none(), "robot"_a, "weights"_a, "rho_T"_a, "w_energy"_a, "head"_a, "tail"_a,
          "waypoints"_a, "durations"_a)
      .def_prop_ro("dimension", &TrajectoryProblem::dimension)
      .def_prop_ro("pieces", &TrajectoryProblem::pieces, "MINCO pieces N (a car adds its two straight ends).")
      .def_prop_ro("initial", &TrajectoryProblem::initial)
      .def(
          "evaluate",
          [](TrajectoryProblem& p, Vec x) {
            Eigen::VectorXd g;
            const Eigen::VectorXd xv = to_vector(x);
            double f;
            {
              nb::gil_scoped_release release;
              f = p.evaluate(xv, g);
            }
            return nb::make_tuple(f, g);
          },
          "x"_a, "(objective, gradient) at x.")
      .def(
          "details",
          [](TrajectoryProblem& p, Vec x) {
            Eigen::VectorXd g;
            CostTerms t;
            p.evaluate(to_vector(x), g, &t);
            return terms_dict(t);
          },
          "x"_a, "The objective's terms at x.")
      .def(
          "trajectory",
          [](TrajectoryProblem& p, Vec x) {
            Eigen::MatrixX3d c;
            Eigen::VectorXd T;
            p.trajectory(to_vector(x), c, T);
            return nb::make_tuple(coefficients_array(c), T);
          },
          "x"_a, "(coefficients (N, 4, 3), durations (N,)) at x.")
      .def(
          "optimize",
          [](TrajectoryProblem& p, const LbfgsParams& lb) {
            OptimizeOutcome o;
            {
              nb::gil_scoped_release release;
              o = optimize(p, lb);
            }
            nb::dict out;
            out["x"] = o.x;
            out["iterations"] = o.iterations;
            out["evaluations"] = o.evaluations;
            out["status"] = o.status;
            out["reason"] = o.reason;
            out["terms"] = terms_dict(o.terms);
            return out;
          },
          "params"_a = trajectory_lbfgs(),
          "L-BFGS from the initial guess; dict of x, iterations, evaluations, status, reason, terms.");
}
