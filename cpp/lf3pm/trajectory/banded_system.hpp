// A square banded matrix with an in-place LU factorisation without pivoting: the linear
// system of every MINCO (minco.hpp, minco_s3.hpp), whose row order keeps each pivot
// non-zero (tested against dense solves).
#pragma once

#include <Eigen/Core>
#include <algorithm>
#include <vector>

namespace lf3pm {

class BandedSystem {
 public:
  /// n x n, `lower` sub-diagonals and `upper` super-diagonals, all zero.
  void reset(int n, int lower, int upper);
  double& operator()(int i, int j) { return band_[index(i, j)]; }
  double operator()(int i, int j) const { return band_[index(i, j)]; }
  /// LU-factorise in place (Doolittle, unit lower triangle).
  void factorize();
  /// Solve A X = B in place (after factorize); B has any number of columns.
  template <typename Matrix>
  void solve(Matrix& b) const {
    for (int j = 0; j < n_; ++j)  // L y = b (unit diagonal)
      for (int i = j + 1; i <= std::min(j + lower_, n_ - 1); ++i)
        if ((*this)(i, j) != 0.0) b.row(i) -= (*this)(i, j) * b.row(j);
    for (int j = n_ - 1; j >= 0; --j) {  // U x = y
      b.row(j) /= (*this)(j, j);
      for (int i = std::max(0, j - upper_); i < j; ++i)
        if ((*this)(i, j) != 0.0) b.row(i) -= (*this)(i, j) * b.row(j);
    }
  }
  /// Solve A^T X = B in place (after factorize).
  template <typename Matrix>
  void solve_transposed(Matrix& b) const {
    for (int j = 0; j < n_; ++j) {  // U^T y = b
      b.row(j) /= (*this)(j, j);
      for (int i = j + 1; i <= std::min(j + upper_, n_ - 1); ++i)
        if ((*this)(j, i) != 0.0) b.row(i) -= (*this)(j, i) * b.row(j);
    }
    for (int j = n_ - 1; j >= 0; --j)  // L^T x = y
      for (int i = std::max(0, j - lower_); i < j; ++i)
        if ((*this)(j, i) != 0.0) b.row(i) -= (*this)(j, i) * b.row(j);
  }

 private:
  std::size_t index(int i, int j) const { return std::size_t(i - j + upper_) * n_ + j; }
  int n_ = 0, lower_ = 0, upper_ = 0;
  std::vector<double> band_;
};

}  // namespace lf3pm
