#include "lf3pm/planner/hybrid_search.hpp"

#include <algorithm>
#include <cmath>
#include <functional>
#include <limits>
#include <queue>
#include <stdexcept>
#include <unordered_map>
#include <utility>

namespace lf3pm {

namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();

struct Node {
  Pose2 pose;
  double g = 0.0;
  std::int32_t parent = -1;
  PathSegment move;  // the primitive that led here
  bool closed = false;
};

class Search {
 public:
  Search(const GridField& esdf, const GridField* cells, const GridField* cost, const Pose2& goal, const HybridParams& p)
      : esdf_(esdf), cells_(cells ? *cells : esdf), cost_(cost && !cost->empty() ? cost : nullptr), goal_(goal), p_(p) {
    if (esdf.empty() || esdf.layers() != 1) throw std::invalid_argument("hybrid search: the ESDF needs one layer");
    if (cells_.empty() || cells_.layers() != 1)
      throw std::invalid_argument("hybrid search: the search's cells need one layer");
    if (!(p.radius > 0.0) || !std::isfinite(p.radius))
      throw std::invalid_argument("hybrid search: the turning radius must be positive and finite");
    if (p.yaw_bins < 4) throw std::invalid_argument("hybrid search: yaw_bins must be >= 4");
    if (!(p.weight >= 0.0) || !std::isfinite(p.weight)) throw std::invalid_argument("hybrid search: bad weight");
    if (!std::isfinite(p.clearance)) throw std::invalid_argument("hybrid search: clearance must be finite");
    if (!(p.heuristic_weight >= 1.0) || !std::isfinite(p.heuristic_weight))
      throw std::invalid_argument("hybrid search: heuristic_weight must be >= 1");
    if (!(p.step >= 0.0) || !(p.sample_step >= 0.0) || p.analytic_every < 1)
      throw std::invalid_argument("hybrid search: step and sample_step must be >= 0, analytic_every >= 1");
    nx_ = cells_.nx(), ny_ = cells_.ny(), x0_ = cells_.x0(), y0_ = cells_.y0(), res_ = cells_.res();
    if (cost_ &&
        (cost_->nx() != nx_ || cost_->ny() != ny_ || cost_->x0() != x0_ || cost_->y0() != y0_ || cost_->res() != res_))
      throw std::invalid_argument("hybrid search: the cost and the search's grids differ");
    step_ = p.step > 0.0 ? p.step : std::sqrt(2.0) * res_;
    ds_ = p.sample_step > 0.0 ? p.sample_step : 0.25 * res_;
    double cmin = 0.0;
    if (cost_) {
      cmin = kInf;
      for (int k = 0; k < cost_->layers(); ++k)
        for (int j = 0; j < ny_; ++j)
          for (int i = 0; i < nx_; ++i) cmin = std::min(cmin, cost_->at(k, j, i));
      if (!(cmin >= 0.0)) throw std::invalid_argument("hybrid search: costs must be >= 0");
    }
    unit_ = 1.0 + p.weight * cmin;
    if (!free(goal)) throw std::invalid_argument("hybrid search: the goal is off the grid or too close to an obstacle");
    relax();
  }

  double heuristic(const Pose2& q) const {
    const double d = relaxed_[cell(q)];
    if (!std::isfinite(d)) return kInf;
    if (!p_.heuristic) return 0.0;
    constexpr double kappa = 1.0823922002923940;  // sqrt(4 - 2 sqrt 2)
    return std::max(unit_ * dubins_shortest(q, goal_, p_.radius).length, d / kappa - slack_);
  }

  HybridResult run(const Pose2& start) {
    HybridResult out;
    if (!free(start))
      throw std::invalid_argument("hybrid search: the start is off the grid or too close to an obstacle");
    out.relaxed_cells = relaxed_cells_;
    if (!std::isfinite(relaxed_[cell(start)])) {
      out.reason = "no chain of cells clear of obstacles joins start and goal";
      return out;
    }
    using Entry = std::pair<double, std::int32_t>;
    std::priority_queue<Entry, std::vector<Entry>, std::greater<Entry>> open;
    std::unordered_map<std::uint64_t, std::int32_t> best;
    nodes_.push_back(Node{start, 0.0, -1, {}, false});
    best[key(start)] = 0;
    open.push({p_.heuristic_weight * heuristic(start), 0});
    double best_cost = kInf;
    std::int32_t best_node = -1;
    DubinsPath best_tail;
    const double near = 4.0 * p_.radius + step_;
    const double arc = std::min(step_, 0.5 * M_PI * p_.radius);
    const PathSegment moves[3] = {{1.0 / p_.radius, arc}, {0.0, step_}, {-1.0 / p_.radius, arc}};
    bool limited = false;
    while (!open.empty()) {
      const auto [f, n] = open.top();
      open.pop();
      if (f >= best_cost) break;
      Node& node = nodes_[n];
      if (node.closed) continue;
      const std::uint64_t k = key(node.pose);
      if (best[k] != n) continue;  // superseded by a cheaper arrival
      if (out.expanded >= p_.max_expansions) {
        limited = true;
        break;
      }
      node.closed = true;
      ++out.expanded;
      const Pose2 pose = node.pose;
      const double g = node.g;
      const double dist = std::hypot(goal_.x - pose.x, goal_.y - pose.y);
      if (out.expanded % p_.analytic_every == 1 || p_.analytic_every == 1 || dist <= near) {
        ++out.analytic_tries;
        const DubinsPath d = dubins_shortest(pose, goal_, p_.radius);
        if (unit_ * d.length + g < best_cost) {
          double c = 0.0;
          if (trace_all(pose, d.segments.data(), 3, c) && g + c < best_cost) {
            best_cost = g + c;
            best_node = n;
            best_tail = d;
          }
        }
      }
      for (const PathSegment& m : moves) {
        Pose2 end;
        double c;
        if (!trace(pose, m, end, c)) continue;
        const std::uint64_t k2 = key(end);
        if (k2 == k) continue;
        const double g2 = g + c;
        const auto it = best.find(k2);
        if (it != best.end() && (nodes_[it->second].closed || nodes_[it->second].g <= g2)) continue;
        const double h = heuristic(end);
        if (!std::isfinite(h)) continue;
        const auto id = static_cast<std::int32_t>(nodes_.size());
        nodes_.push_back(Node{end, g2, n, m, false});
        best[k2] = id;
        open.push({g2 + p_.heuristic_weight * h, id});
      }
    }
    if (best_node < 0) {
      out.reason = limited ? "gave up after " + std::to_string(out.expanded) + " expansions"
                           : "every forward path of turning radius >= R runs into an obstacle (" +
                                 std::to_string(out.expanded) + " states expanded)";
      return out;
    }
    std::vector<PathSegment> moves_back;
    for (std::int32_t i = best_node; nodes_[i].parent >= 0; i = nodes_[i].parent) moves_back.push_back(nodes_[i].move);
    std::vector<PathSegment> all(moves_back.rbegin(), moves_back.rend());
    all.insert(all.end(), best_tail.segments.begin(), best_tail.segments.end());
    for (const PathSegment& s : all) {
      if (s.length <= 0.0) continue;
      if (!out.segments.empty() && out.segments.back().curvature == s.curvature)
        out.segments.back().length += s.length;
      else
        out.segments.push_back(s);
      out.length += s.length;
    }
    out.found = true;
    out.cost = best_cost;
    return out;
  }

 private:
  bool inside(double x, double y) const { return x >= x0_ && y >= y0_ && x < x0_ + nx_ * res_ && y < y0_ + ny_ * res_; }
  std::size_t cell(const Pose2& q) const {
    const int i = std::clamp(static_cast<int>(std::floor((q.x - x0_) / res_)), 0, nx_ - 1);
    const int j = std::clamp(static_cast<int>(std::floor((q.y - y0_) / res_)), 0, ny_ - 1);
    return std::size_t(j) * nx_ + i;
  }
  std::uint64_t key(const Pose2& q) const {
    const double bin = 2.0 * M_PI / p_.yaw_bins;
    long k = std::lround(q.yaw / bin) % p_.yaw_bins;
    if (k < 0) k += p_.yaw_bins;
    return std::uint64_t(cell(q)) * p_.yaw_bins + std::uint64_t(k);
  }
  bool free(const Pose2& q) const {
    Eigen::Vector3d grad;
    return inside(q.x, q.y) && esdf_.sample(q.x, q.y, 0.0, grad) >= p_.clearance;
  }
  double cost_at(const Pose2& q) const {
    if (!cost_) return 0.0;
    Eigen::Vector3d grad;
    return cost_->sample(q.x, q.y, q.yaw, grad);
  }

  // Samples along one move from `from`: false on a collision; else its end pose and cost (trapezoid rule).
  bool trace(const Pose2& from, const PathSegment& m, Pose2& end, double& cost) const {
    const int n = std::max(1, static_cast<int>(std::ceil(m.length / ds_)));
    const double h = m.length / n;
    double prev = cost_at(from);
    cost = 0.0;
    for (int i = 1; i <= n; ++i) {
      end = advance(from, m.curvature, i * h);
      if (!free(end)) return false;
      const double c = cost_at(end);
      cost += h * (1.0 + p_.weight * 0.5 * (prev + c));
      prev = c;
    }
    return true;
  }
  bool trace_all(Pose2 pose, const PathSegment* segments, int count, double& cost) const {
    cost = 0.0;
    for (int s = 0; s < count; ++s) {
      if (segments[s].length <= 0.0) continue;
      double c;
      Pose2 end;
      if (!trace(pose, segments[s], end, c)) return false;
      pose = end;
      cost += c;
    }
    return true;
  }

  // The heuristic's backward pass: octile distances to the goal's cell over the cells a
  // collision-free sample could lie in.
  void relax() {
    // A sample in the quadrant (si, sj) of cell (i, j) interpolates the centres of the cell,
    // its neighbours a (along x) and b (along y) and d (diagonal), with the cell's weight
    // at least 1/4: bilinear, so its largest value is at one of the quadrant's corners.
    std::vector<std::uint8_t> open(std::size_t(nx_) * ny_, 0);
    auto v = [&](int i, int j) { return cells_.at(0, std::clamp(j, 0, ny_ - 1), std::clamp(i, 0, nx_ - 1)); };
    for (int j = 0; j < ny_; ++j)
      for (int i = 0; i < nx_; ++i)
        for (const int si : {-1, 1})
          for (const int sj : {-1, 1}) {
            const double c = v(i, j), a = v(i + si, j), b = v(i, j + sj), d = v(i + si, j + sj);
            const double top = std::max({c, 0.5 * (c + a), 0.5 * (c + b), 0.25 * (c + a + b + d)});
            if (top >= p_.clearance) open[std::size_t(j) * nx_ + i] = 1;
          }
    // The least cost a sample in each cell can read: interpolation mixes the centres of
    // the 3 x 3 cells around it (any yaw layer).
    std::vector<double> least(open.size(), 0.0);
    double most = 0.0;
    if (cost_) {
      std::vector<double> below(open.size(), kInf);
      for (int k = 0; k < cost_->layers(); ++k)
        for (int j = 0; j < ny_; ++j)
          for (int i = 0; i < nx_; ++i) {
            double& b = below[std::size_t(j) * nx_ + i];
            b = std::min(b, cost_->at(k, j, i));
          }
      for (int j = 0; j < ny_; ++j)
        for (int i = 0; i < nx_; ++i) {
          double m = kInf;
          for (int dj = -1; dj <= 1; ++dj)
            for (int di = -1; di <= 1; ++di)
              m = std::min(m,
                           below[std::size_t(std::clamp(j + dj, 0, ny_ - 1)) * nx_ + std::clamp(i + di, 0, nx_ - 1)]);
          least[std::size_t(j) * nx_ + i] = m;
          if (open[std::size_t(j) * nx_ + i]) most = std::max(most, m);
        }
    }
    slack_ = std::sqrt(2.0) * res_ * (1.0 + p_.weight * most);
    relaxed_.assign(open.size(), kInf);
    using Entry = std::pair<double, std::size_t>;
    std::priority_queue<Entry, std::vector<Entry>, std::greater<Entry>> heap;
    const std::size_t g = cell(goal_);
    relaxed_[g] = 0.0;
    heap.push({0.0, g});
    const double diag = std::sqrt(2.0) * res_;
    while (!heap.empty()) {
      const auto [d, c] = heap.top();
      heap.pop();
      if (d > relaxed_[c]) continue;
      ++relaxed_cells_;
      const int i = static_cast<int>(c % nx_), j = static_cast<int>(c / nx_);
      for (int dj = -1; dj <= 1; ++dj)
        for (int di = -1; di <= 1; ++di) {
          const int a = i + di, b = j + dj;
          if ((di == 0 && dj == 0) || a < 0 || b < 0 || a >= nx_ || b >= ny_) continue;
          const std::size_t c2 = std::size_t(b) * nx_ + a;
          const double d2 = d + (di != 0 && dj != 0 ? diag : res_) * (1.0 + p_.weight * std::min(least[c], least[c2]));
          if (open[c2] && d2 < relaxed_[c2]) {
            relaxed_[c2] = d2;
            heap.push({d2, c2});
          }
        }
    }
  }

  const GridField& esdf_;
  const GridField& cells_;
  const GridField* cost_;
  Pose2 goal_;
  HybridParams p_;
  int nx_ = 0, ny_ = 0;
  double x0_ = 0.0, y0_ = 0.0, res_ = 1.0, step_ = 1.0, ds_ = 0.25, unit_ = 1.0, slack_ = 0.0;
  std::vector<double> relaxed_;
  std::uint64_t relaxed_cells_ = 0;
  std::vector<Node> nodes_;
};

}  // namespace

HybridResult hybrid_search(const GridField& esdf, const GridField* cells, const GridField* cost, const Pose2& start,
                           const Pose2& goal, const HybridParams& params) {
  Search search(esdf, cells, cost, goal, params);
  return search.run(start);
}

std::vector<double> hybrid_heuristic(const GridField& esdf, const GridField* cells, const GridField* cost,
                                     const std::vector<Pose2>& poses, const Pose2& goal, const HybridParams& params) {
  const Search search(esdf, cells, cost, goal, params);
  std::vector<double> h(poses.size());
  for (std::size_t i = 0; i < poses.size(); ++i) h[i] = search.heuristic(poses[i]);
  return h;
}

std::vector<Pose2> sample_segments(const Pose2& start, const std::vector<PathSegment>& segments, double spacing) {
  if (!(spacing > 0.0)) throw std::invalid_argument("sample spacing must be positive");
  std::vector<Pose2> out{start};
  Pose2 pose = start;
  for (const PathSegment& s : segments) {
    const int n = std::max(1, static_cast<int>(std::ceil(s.length / spacing)));
    for (int i = 1; i <= n; ++i) out.push_back(advance(pose, s.curvature, s.length * i / n));
    pose = out.back();
  }
  return out;
}

}  // namespace lf3pm
