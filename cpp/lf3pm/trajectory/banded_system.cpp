#include "lf3pm/trajectory/banded_system.hpp"

namespace lf3pm {

void BandedSystem::reset(int n, int lower, int upper) {
  n_ = n;
  lower_ = lower;
  upper_ = upper;
  band_.assign(std::size_t(lower + upper + 1) * n, 0.0);
}

void BandedSystem::factorize() {
  for (int k = 0; k < n_; ++k) {
    const int last_row = std::min(k + lower_, n_ - 1), last_col = std::min(k + upper_, n_ - 1);
    const double pivot = (*this)(k, k);
    for (int i = k + 1; i <= last_row; ++i) {
      double& l = (*this)(i, k);
      if (l == 0.0) continue;
      l /= pivot;
      for (int j = k + 1; j <= last_col; ++j) (*this)(i, j) -= l * (*this)(k, j);
    }
  }
}

}  // namespace lf3pm
