// Discs stored as structure of arrays, and the nearest ray-disc intersection
// over a contiguous range of them.
//
// A cell's discs are tested together: with AVX2 eight at a time (one masked load
// per field, no branch per disc), which is what makes a cell of twenty discs
// cost about as much as one step of the voxel walk. The scalar fallback computes
// the same float expressions in the same order (the products that the compiler
// contracts to fused multiply-adds included), so both paths return the same
// hits to the last bit.
#pragma once

#include <cmath>
#include <cstdint>
#include <vector>

#if defined(__AVX2__) && defined(__FMA__)
#include <immintrin.h>
#define LF3PM_DISC_AVX2 1
#endif

namespace lf3pm {

/// Discs with centres c, unit normals n and squared radii r2; id is the caller's
/// index of each disc (map point).
struct DiscSet {
  std::vector<float> cx, cy, cz, nx, ny, nz, r2;
  std::vector<std::uint32_t> id;

  std::size_t size() const { return id.size(); }
  void resize(std::size_t n) {
    for (auto* v : {&cx, &cy, &cz, &nx, &ny, &nz, &r2}) v->resize(n);
    id.resize(n);
  }
  std::size_t memory_bytes() const { return size() * (7 * sizeof(float) + sizeof(std::uint32_t)); }

  /// Lowers `best` to the nearest intersection parameter t in (t_min, best) of
  /// the ray o + t d with discs [begin, end), and sets `best_id` to that disc's
  /// id; among equal t the first disc wins. Rays in a disc's plane
  /// (|n.d| < 1e-7) miss it.
  void nearest_hit(const float* o, const float* d, float t_min, std::uint32_t begin, std::uint32_t end,
                   float& best, std::uint32_t& best_id) const {
#ifdef LF3PM_DISC_AVX2
    const __m256 ox = _mm256_set1_ps(o[0]), oy = _mm256_set1_ps(o[1]), oz = _mm256_set1_ps(o[2]);
    const __m256 dx = _mm256_set1_ps(d[0]), dy = _mm256_set1_ps(d[1]), dz = _mm256_set1_ps(d[2]);
    const __m256 abs_mask = _mm256_castsi256_ps(_mm256_set1_epi32(0x7fffffff));
    const __m256 eps = _mm256_set1_ps(1e-7f), tmin = _mm256_set1_ps(t_min);
    const __m256i lane = _mm256_setr_epi32(0, 1, 2, 3, 4, 5, 6, 7);
    for (std::uint32_t k = begin; k < end; k += 8) {
      // Masked loads never touch memory past the range, so no padding is needed.
      const __m256i live = _mm256_cmpgt_epi32(_mm256_set1_epi32(static_cast<int>(end - k)), lane);
      const __m256 n0 = _mm256_maskload_ps(&nx[k], live), n1 = _mm256_maskload_ps(&ny[k], live),
                   n2 = _mm256_maskload_ps(&nz[k], live);
      const __m256 c0 = _mm256_maskload_ps(&cx[k], live), c1 = _mm256_maskload_ps(&cy[k], live),
                   c2 = _mm256_maskload_ps(&cz[k], live);
      const __m256 denom = _mm256_fmadd_ps(n2, dz, _mm256_fmadd_ps(n0, dx, _mm256_mul_ps(n1, dy)));
      const __m256 num =
          _mm256_fmadd_ps(n2, _mm256_sub_ps(c2, oz),
                          _mm256_fmadd_ps(n0, _mm256_sub_ps(c0, ox), _mm256_mul_ps(n1, _mm256_sub_ps(c1, oy))));
      const __m256 t = _mm256_div_ps(num, denom);
      const __m256 qx = _mm256_sub_ps(_mm256_fmadd_ps(dx, t, ox), c0);
      const __m256 qy = _mm256_sub_ps(_mm256_fmadd_ps(dy, t, oy), c1);
      const __m256 qz = _mm256_sub_ps(_mm256_fmadd_ps(dz, t, oz), c2);
      const __m256 q2 = _mm256_fmadd_ps(qz, qz, _mm256_fmadd_ps(qx, qx, _mm256_mul_ps(qy, qy)));
      __m256 ok = _mm256_and_ps(_mm256_castsi256_ps(live),
                                _mm256_cmp_ps(_mm256_and_ps(denom, abs_mask), eps, _CMP_GE_OQ));
      ok = _mm256_and_ps(ok, _mm256_cmp_ps(t, tmin, _CMP_GT_OQ));
      ok = _mm256_and_ps(ok, _mm256_cmp_ps(t, _mm256_set1_ps(best), _CMP_LT_OQ));
      ok = _mm256_and_ps(ok, _mm256_cmp_ps(q2, _mm256_maskload_ps(&r2[k], live), _CMP_LE_OQ));
      unsigned hits = static_cast<unsigned>(_mm256_movemask_ps(ok));
      if (hits == 0) continue;
      alignas(32) float ts[8];
      _mm256_store_ps(ts, t);
      for (; hits; hits &= hits - 1) {
        const int j = __builtin_ctz(hits);
        if (ts[j] < best) {
          best = ts[j];
          best_id = id[k + j];
        }
      }
    }
#else
    for (std::uint32_t k = begin; k < end; ++k) {
      const float denom = ny[k] * d[1] + nx[k] * d[0] + nz[k] * d[2];
      if (std::abs(denom) < 1e-7f) continue;
      const float num = ny[k] * (cy[k] - o[1]) + nx[k] * (cx[k] - o[0]) + nz[k] * (cz[k] - o[2]);
      const float t = num / denom;
      if (!(t > t_min) || t >= best) continue;
      const float qx = d[0] * t + o[0] - cx[k], qy = d[1] * t + o[1] - cy[k], qz = d[2] * t + o[2] - cz[k];
      if (qy * qy + qx * qx + qz * qz <= r2[k]) {
        best = t;
        best_id = id[k];
      }
    }
#endif
  }
};

}  // namespace lf3pm
