// Conversions the binding files share: C++ containers into numpy arrays that own them,
// row-major pose matrices into Pose.
#pragma once

#include <nanobind/nanobind.h>
#include <nanobind/ndarray.h>

#include <Eigen/Core>
#include <cstring>
#include <initializer_list>
#include <vector>

#include "lf3pm/common/pose.hpp"

namespace lf3pm::bindings {

namespace nb = nanobind;

/// A new numpy array that takes `values` over (no copy of the data), with `shape`.
template <typename T>
nb::ndarray<nb::numpy, T> to_numpy(std::vector<T>&& values, std::initializer_list<std::size_t> shape) {
  auto* owned = new std::vector<T>(std::move(values));
  nb::capsule free_when_done(owned, [](void* p) noexcept { delete static_cast<std::vector<T>*>(p); });
  return nb::ndarray<nb::numpy, T>(owned->data(), shape.size(), shape.begin(), free_when_done);
}

/// A one-dimensional numpy array of `values`.
template <typename T>
nb::ndarray<nb::numpy, T> to_numpy(std::vector<T>&& values) {
  const std::size_t n = values.size();
  return to_numpy(std::move(values), {n});
}

/// Points as an (N, 3) float64 array.
inline nb::ndarray<nb::numpy, double> points_to_numpy(const std::vector<Eigen::Vector3d>& pts) {
  std::vector<double> flat(pts.size() * 3);
  for (std::size_t i = 0; i < pts.size(); ++i) std::memcpy(&flat[3 * i], pts[i].data(), 3 * sizeof(double));
  return to_numpy(std::move(flat), {pts.size(), 3});
}

/// A Pose from a row-major 4 x 4 sensor-to-world matrix.
inline Pose pose_from_matrix(const double* m) {
  Pose p;
  for (int r = 0; r < 3; ++r) {
    for (int c = 0; c < 3; ++c) p.rotation(r, c) = m[4 * r + c];
    p.position[r] = m[4 * r + 3];
  }
  return p;
}

}  // namespace lf3pm::bindings
