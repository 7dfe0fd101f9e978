// Which rays a real LiDAR returns: the probability that a ray hitting a surface gives a
// return, tabulated over the hit's range and the cosine of its incidence. Real sensors
// lose returns on dark, far and grazing surfaces (the hall run's OS1 returned about 60 %
// of the rays a simulation returns; docs/real.md); a table fitted from a run (`lf3pm
// sensors fit`) makes simulated scans lose as many, where they do.
#pragma once

#include <cstdint>
#include <vector>

namespace lf3pm {

struct ReturnModel {
  std::vector<double> range_edges;  // m, ascending; a range outside them takes the nearest bin
  std::vector<double> cos_edges;    // |cos incidence| in [0, 1], ascending
  // (range bins) x (cos bins), row-major, each in [0, 1]; empty model: every hit returns.
  std::vector<double> probability;

  bool empty() const { return probability.empty(); }
  /// Throws std::invalid_argument unless the table is empty or well formed.
  void check() const;
  /// The probability of a return from a hit at `range` with incidence cosine `cos`.
  double at(double range, double cos) const;
};

/// Whether ray `index` of stream `stream` under `seed` returns, given its probability:
/// a counter-based draw (thread-count and order independent), not the range noise's.
bool ray_returns(double probability, std::uint64_t seed, std::uint64_t stream, std::uint64_t index);

}  // namespace lf3pm
