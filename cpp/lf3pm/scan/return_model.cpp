#include "lf3pm/scan/return_model.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

#include "lf3pm/common/random.hpp"

namespace lf3pm {

namespace {

void check_edges(const std::vector<double>& edges, const char* what) {
  if (edges.size() < 2) throw std::invalid_argument(std::string(what) + " need at least 2 edges");
  for (std::size_t i = 0; i < edges.size(); ++i) {
    if (!std::isfinite(edges[i])) throw std::invalid_argument(std::string(what) + " must be finite");
    if (i > 0 && !(edges[i] > edges[i - 1])) throw std::invalid_argument(std::string(what) + " must increase");
  }
}

// The bin of v among edges: [e_i, e_i+1), the first and last bins open outwards.
std::size_t bin(const std::vector<double>& edges, double v) {
  const auto it = std::upper_bound(edges.begin() + 1, edges.end() - 1, v);
  return static_cast<std::size_t>(it - (edges.begin() + 1));
}

// Salt of the return draws: independent of the range noise drawn for the same ray.
constexpr std::uint64_t kReturnSalt = 0x5851F42D4C957F2Dull;

}  // namespace

void ReturnModel::check() const {
  if (empty()) return;
  check_edges(range_edges, "return model range edges");
  check_edges(cos_edges, "return model incidence cosine edges");
  if (cos_edges.front() < 0.0 || cos_edges.back() > 1.0)
    throw std::invalid_argument("return model incidence cosine edges must lie in [0, 1]");
  if (probability.size() != (range_edges.size() - 1) * (cos_edges.size() - 1))
    throw std::invalid_argument("return model table must have (range bins) x (cosine bins) entries");
  for (double p : probability)
    if (!(p >= 0.0 && p <= 1.0)) throw std::invalid_argument("return probabilities must lie in [0, 1]");
}

double ReturnModel::at(double range, double cos) const {
  if (empty()) return 1.0;
  return probability[bin(range_edges, range) * (cos_edges.size() - 1) + bin(cos_edges, cos)];
}

bool ray_returns(double probability, std::uint64_t seed, std::uint64_t stream, std::uint64_t index) {
  if (probability >= 1.0) return true;
  const std::uint64_t key = splitmix64(seed ^ splitmix64(stream ^ splitmix64(index ^ kReturnSalt)));
  return unit_open(splitmix64(key)) < probability;
}

}  // namespace lf3pm
