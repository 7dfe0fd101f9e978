// SE(2) SOLM cells by sector Grams: one scan per yaw *sector*, reused by every
// yaw bin whose field of view covers it.
//
// The Grams of disjoint ray sets add (docs/design.md). A limited field-of-view
// sensor at yaw bin k sees the azimuth sectors k - F .. k + F (F = half the
// field of view in bins); casting each sector once and summing makes a cell
// cost K sectors instead of K whole scans, F x 2 + 1 times fewer rays. The
// approximation: every sector is scanned with one representative ray set (the
// sensor's pattern folded into one sector, so its elevation distribution is
// kept but its azimuthal density variations are averaged). Its error against
// exact per-yaw evaluation is measured, not assumed (tests, README).
#pragma once

#include <cstdint>
#include <vector>

#include "lf3pm/metric/evaluator.hpp"

namespace lf3pm {

/// For each position (x, y, z), the metric at yaw bins k = 0..bins-1 (yaw
/// k * 2 pi / bins) from sector Grams. `sector_rays` are unit directions in
/// the sensor frame within one sector centred on azimuth 0; `half_width`
/// sectors on each side of a bin's own are summed. Cell noise stream for
/// sector j of position i: streams[i] * bins + j. Output index i * bins + k.
std::vector<Metric> evaluate_yaw_sectors(const MapIndex& map, const std::vector<Eigen::Vector3d>& positions,
                                         const std::vector<std::uint64_t>& streams, const double* sector_rays,
                                         std::size_t count, int bins, int half_width, const EvalParams& params);

}  // namespace lf3pm
