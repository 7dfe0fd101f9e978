// Conversions the binding files share: C++ containers into numpy arrays that own them.
#pragma once

#include <nanobind/nanobind.h>
#include <nanobind/ndarray.h>

#include <Eigen/Core>
#include <cstring>
#include <initializer_list>
#include <vector>

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

}  // namespace lf3pm::bindings
