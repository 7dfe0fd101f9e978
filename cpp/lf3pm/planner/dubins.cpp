#include "lf3pm/planner/dubins.hpp"

#include <cmath>
#include <limits>

namespace lf3pm {

namespace {

constexpr double kTwoPi = 2.0 * M_PI;
constexpr double kInf = std::numeric_limits<double>::infinity();

// Angle in [0, 2 pi); a turn within 1e-10 rad of a full one is none (round-off).
double mod2pi(double a) {
  double r = std::fmod(a, kTwoPi);
  if (r < 0.0) r += kTwoPi;
  return (r > kTwoPi - 1e-10) ? 0.0 : r;
}

struct Point {
  double x, y;
};

Point centre(const Pose2& p, double side, double radius) {
  return {p.x - side * radius * std::sin(p.yaw), p.y + side * radius * std::cos(p.yaw)};
}

// Heading of a car at point q on the circle of `side` centred at c.
double heading_on(const Point& c, const Point& q, double side) {
  // c = q + side R (-sin h, cos h)  =>  (c - q) side = R (-sin h, cos h).
  return std::atan2(-(c.x - q.x) * side, (c.y - q.y) * side);
}

DubinsPath make(int word, double k1, double a1, double k2, double l2, double k3, double a3, double radius) {
  DubinsPath p;
  p.word = word;
  // Arcs are given as turn angles (k != 0), the straight as a length.
  p.segments = {PathSegment{k1, a1 * radius}, PathSegment{k2, k2 == 0.0 ? l2 : l2 * radius},
                PathSegment{k3, a3 * radius}};
  p.length = p.segments[0].length + p.segments[1].length + p.segments[2].length;
  return p;
}

DubinsPath none(int word) {
  DubinsPath p;
  p.word = word;
  p.length = kInf;
  return p;
}

// s1, s3: sides of the first and last arc (+1 left, -1 right).
DubinsPath csc(int word, const Pose2& a, const Pose2& b, double s1, double s3, double radius) {
  const Point c1 = centre(a, s1, radius), c3 = centre(b, s3, radius);
  const double vx = c3.x - c1.x, vy = c3.y - c1.y, d = std::hypot(vx, vy);
  double phi, straight;
  if (s1 == s3) {
    // Coinciding circles: any tangent works; leave along the start heading.
    phi = d < 1e-12 * radius ? a.yaw : std::atan2(vy, vx);
    straight = d;
  } else {
    if (d < 2.0 * radius) return none(word);
    straight = std::sqrt(std::max(d * d - 4.0 * radius * radius, 0.0));
    phi = std::atan2(vy, vx) + s1 * std::atan2(2.0 * radius, straight);
  }
  return make(word, s1 / radius, mod2pi(s1 * (phi - a.yaw)), 0.0, straight, s3 / radius, mod2pi(s3 * (b.yaw - phi)),
              radius);
}

// CCC with sides s, -s, s: the better of the two middle circles.
DubinsPath ccc(int word, const Pose2& a, const Pose2& b, double s, double radius) {
  const Point c1 = centre(a, s, radius), c3 = centre(b, s, radius);
  const double vx = c3.x - c1.x, vy = c3.y - c1.y, d = std::hypot(vx, vy);
  if (d > 4.0 * radius || d < 1e-12 * radius) return none(word);
  const double h = std::sqrt(std::max(4.0 * radius * radius - 0.25 * d * d, 0.0));
  DubinsPath best = none(word);
  for (const double side : {1.0, -1.0}) {
    const Point c2{0.5 * (c1.x + c3.x) - side * h * vy / d, 0.5 * (c1.y + c3.y) + side * h * vx / d};
    const Point q1{0.5 * (c1.x + c2.x), 0.5 * (c1.y + c2.y)}, q2{0.5 * (c2.x + c3.x), 0.5 * (c2.y + c3.y)};
    const double h1 = heading_on(c1, q1, s), h2 = heading_on(c3, q2, s);
    const DubinsPath p = make(word, s / radius, mod2pi(s * (h1 - a.yaw)), -s / radius, mod2pi(-s * (h2 - h1)),
                              s / radius, mod2pi(s * (b.yaw - h2)), radius);
    if (p.length < best.length) best = p;
  }
  return best;
}

}  // namespace

const std::array<const char*, 6>& dubins_word_names() {
  static const std::array<const char*, 6> names{"LSL", "RSR", "LSR", "RSL", "RLR", "LRL"};
  return names;
}

std::array<DubinsPath, 6> dubins_words(const Pose2& from, const Pose2& to, double radius) {
  return {csc(0, from, to, 1, 1, radius),  csc(1, from, to, -1, -1, radius), csc(2, from, to, 1, -1, radius),
          csc(3, from, to, -1, 1, radius), ccc(4, from, to, -1, radius),     ccc(5, from, to, 1, radius)};
}

DubinsPath dubins_shortest(const Pose2& from, const Pose2& to, double radius) {
  DubinsPath best = none(-1);
  for (const DubinsPath& p : dubins_words(from, to, radius))
    if (p.length < best.length) best = p;
  return best;
}

Pose2 advance(const Pose2& p, double curvature, double length) {
  if (curvature == 0.0) return {p.x + length * std::cos(p.yaw), p.y + length * std::sin(p.yaw), p.yaw};
  const double yaw = p.yaw + curvature * length;
  return {p.x + (std::sin(yaw) - std::sin(p.yaw)) / curvature, p.y + (std::cos(p.yaw) - std::cos(yaw)) / curvature,
          yaw};
}

}  // namespace lf3pm
