// Discs stored in groups of eight (structure of arrays within a group), and the
// nearest ray-disc intersection over a run of groups.
//
// A cell's discs are tested together: with AVX2 a group at a time (aligned
// loads, no branch per disc), which is what makes a cell of twenty discs cost
// about as much as one step of the voxel walk. A cell's groups are contiguous,
// so its discs arrive in whole cache lines instead of from eight arrays. The
// AVX2 path multiplies and adds in the scalar fallback's order, without fused
// multiply-adds (the core is built with -ffp-contract=off), so both paths return
// the same hits to the last bit and a build for any x86-64 level casts the same scan.
#pragma once

#include <cmath>
#include <cstdint>
#include <vector>

#if defined(__AVX2__)
#include <immintrin.h>
#define LF3PM_DISC_AVX2 1
#endif

namespace lf3pm {

/// Eight discs: centres c, unit normals n, squared radii r2 and the caller's id
/// of each (map point). Unused lanes have n = 0, which no ray hits.
struct alignas(64) DiscGroup {
  static constexpr int kLanes = 8;
  float cx[kLanes], cy[kLanes], cz[kLanes], nx[kLanes], ny[kLanes], nz[kLanes], r2[kLanes];
  std::uint32_t id[kLanes];
};

/// Lowers `best` to the nearest intersection parameter t in (t_min, best) of the
/// ray o + t d with the discs of `groups[0, count)`, and sets `best_id` to that
/// disc's id; among equal t the first disc wins. Rays in a disc's plane
/// (|n.d| < 1e-7) miss it.
inline void nearest_disc_hit(const DiscGroup* groups, std::uint32_t count, const float* o, const float* d, float t_min,
                             float& best, std::uint32_t& best_id) {
#ifdef LF3PM_DISC_AVX2
  const __m256 ox = _mm256_set1_ps(o[0]), oy = _mm256_set1_ps(o[1]), oz = _mm256_set1_ps(o[2]);
  const __m256 dx = _mm256_set1_ps(d[0]), dy = _mm256_set1_ps(d[1]), dz = _mm256_set1_ps(d[2]);
  const __m256 abs_mask = _mm256_castsi256_ps(_mm256_set1_epi32(0x7fffffff));
  const __m256 eps = _mm256_set1_ps(1e-7f), tmin = _mm256_set1_ps(t_min);
  for (std::uint32_t g = 0; g < count; ++g) {
    const DiscGroup& q = groups[g];
    const __m256 n0 = _mm256_load_ps(q.nx), n1 = _mm256_load_ps(q.ny), n2 = _mm256_load_ps(q.nz);
    const __m256 c0 = _mm256_load_ps(q.cx), c1 = _mm256_load_ps(q.cy), c2 = _mm256_load_ps(q.cz);
    const __m256 denom =
        _mm256_add_ps(_mm256_add_ps(_mm256_mul_ps(n0, dx), _mm256_mul_ps(n1, dy)), _mm256_mul_ps(n2, dz));
    const __m256 num =
        _mm256_add_ps(_mm256_add_ps(_mm256_mul_ps(n0, _mm256_sub_ps(c0, ox)), _mm256_mul_ps(n1, _mm256_sub_ps(c1, oy))),
                      _mm256_mul_ps(n2, _mm256_sub_ps(c2, oz)));
    const __m256 t = _mm256_div_ps(num, denom);
    const __m256 qx = _mm256_sub_ps(_mm256_add_ps(ox, _mm256_mul_ps(t, dx)), c0);
    const __m256 qy = _mm256_sub_ps(_mm256_add_ps(oy, _mm256_mul_ps(t, dy)), c1);
    const __m256 qz = _mm256_sub_ps(_mm256_add_ps(oz, _mm256_mul_ps(t, dz)), c2);
    const __m256 q2 = _mm256_add_ps(_mm256_add_ps(_mm256_mul_ps(qx, qx), _mm256_mul_ps(qy, qy)), _mm256_mul_ps(qz, qz));
    __m256 ok = _mm256_cmp_ps(_mm256_and_ps(denom, abs_mask), eps, _CMP_GE_OQ);
    ok = _mm256_and_ps(ok, _mm256_cmp_ps(t, tmin, _CMP_GT_OQ));
    ok = _mm256_and_ps(ok, _mm256_cmp_ps(t, _mm256_set1_ps(best), _CMP_LT_OQ));
    ok = _mm256_and_ps(ok, _mm256_cmp_ps(q2, _mm256_load_ps(q.r2), _CMP_LE_OQ));
    unsigned hits = static_cast<unsigned>(_mm256_movemask_ps(ok));
    if (hits == 0) continue;
    alignas(32) float ts[DiscGroup::kLanes];
    _mm256_store_ps(ts, t);
    for (; hits; hits &= hits - 1) {
      const int j = __builtin_ctz(hits);
      if (ts[j] < best) {
        best = ts[j];
        best_id = q.id[j];
      }
    }
  }
#else
  for (std::uint32_t g = 0; g < count; ++g) {
    const DiscGroup& q = groups[g];
    for (int k = 0; k < DiscGroup::kLanes; ++k) {
      const float denom = q.nx[k] * d[0] + q.ny[k] * d[1] + q.nz[k] * d[2];
      if (std::abs(denom) < 1e-7f) continue;
      const float num = q.nx[k] * (q.cx[k] - o[0]) + q.ny[k] * (q.cy[k] - o[1]) + q.nz[k] * (q.cz[k] - o[2]);
      const float t = num / denom;
      if (!(t > t_min) || t >= best) continue;
      const float qx = o[0] + t * d[0] - q.cx[k], qy = o[1] + t * d[1] - q.cy[k], qz = o[2] + t * d[2] - q.cz[k];
      if (qx * qx + qy * qy + qz * qz <= q.r2[k]) {
        best = t;
        best_id = q.id[k];
      }
    }
  }
#endif
}

}  // namespace lf3pm
