// Shortest forward paths of bounded curvature (Dubins 1957) between two poses.
//
// A car moving forwards only with turning radius >= R reaches any pose from any
// other; Dubins showed a shortest such path is one of six words of at most three
// segments, each an arc of radius R to the left (L) or right (R) or a straight (S):
// LSL, RSR, LSR, RSL (CSC) and RLR, LRL (CCC). This computes all six geometrically
// (tangent lines between the turning circles, or the middle circle tangent to
// both) and keeps the shortest:
//   - a turning circle of side s (+1 left, -1 right) at pose (p, th) is centred
//     at p + s R (-sin th, cos th); on it the heading fixes the position, so an
//     arc from heading a to heading b turns mod2pi(s (b - a));
//   - CSC: the straight's heading phi follows from the centres' offset v
//     (|v| = D, angle psi): same side, phi = psi and the straight is D long;
//     opposite sides (inner tangent, D >= 2R), the straight is sqrt(D^2 - 4R^2)
//     long and phi = psi + s1 atan2(2R, that length);
//   - CCC (D <= 4R): the middle circle touches both end circles, its centre 2R
//     from each (two candidates); the arcs meet at the midpoints between centres.
#pragma once

#include <array>
#include <vector>

namespace lf3pm {

struct Pose2 {
  double x = 0.0, y = 0.0, yaw = 0.0;
};

/// One segment: signed curvature (+1/R left, -1/R right, 0 straight) and length (m, >= 0).
struct PathSegment {
  double curvature = 0.0;
  double length = 0.0;
};

struct DubinsPath {
  std::array<PathSegment, 3> segments{};
  double length = 0.0;  ///< total length (m)
  int word = -1;        ///< index into dubins_word_names()
};

/// Names of the six words, in the order `DubinsPath::word` indexes them.
const std::array<const char*, 6>& dubins_word_names();

/// The shortest forward path of turning radius `radius` (> 0) from `from` to `to`.
DubinsPath dubins_shortest(const Pose2& from, const Pose2& to, double radius);

/// Every word that exists for the pair (length +inf where it does not), in the order of
/// dubins_word_names(): for tests.
std::array<DubinsPath, 6> dubins_words(const Pose2& from, const Pose2& to, double radius);

/// The pose after moving `length` metres along a segment of signed `curvature` (exact).
Pose2 advance(const Pose2& p, double curvature, double length);

}  // namespace lf3pm
