// tridex — the vector lanes of the milling kernel: kLanes doubles as one value (DoubleN) and the
// few operations on them that mill.hpp's loops need (load, store, min, max, square root, masks).
//
// Why: the ball end's, flat end's, bull nose's and profiles' swept surfaces are evaluated kLanes
// grid points (or tiles) at a time (cutter_lanes.hpp), with the GCC/Clang vector extension so
// that one source serves AVX-512, AVX and SSE2; the width follows the compiler's target.
#pragma once

#include <algorithm>
#include <cstdint>
#include <limits>

#if defined(__SSE2__) || defined(__AVX__) || defined(__AVX512F__)
#include <immintrin.h>
#endif

namespace tridex::detail {

constexpr double kInf = std::numeric_limits<double>::infinity();

// Doubles processed as one value (GCC/Clang vector extension): eight with AVX-512, four with
// AVX, two with the SSE2 of every x86-64, two in plain scalar code elsewhere; the compiler's
// target decides (the project's build picks the building machine's, see TRIDEX_SIMD in
// CMakeLists.txt). Comparisons give a MaskN of all-ones/all-zeros lanes.
#if defined(__AVX512F__)
using DoubleN = double __attribute__((vector_size(64)));
using MaskN = long long __attribute__((vector_size(64)));
using FloatN = float __attribute__((vector_size(32)));
#elif defined(__AVX__)
using DoubleN = double __attribute__((vector_size(32)));
using MaskN = long long __attribute__((vector_size(32)));
using FloatN = float __attribute__((vector_size(16)));
#else
using DoubleN = double __attribute__((vector_size(16)));
using MaskN = long long __attribute__((vector_size(16)));
using FloatN = float __attribute__((vector_size(8)));
#endif
constexpr int kLanes = static_cast<int>(sizeof(DoubleN) / sizeof(double));
inline DoubleN splat(double v) { return DoubleN{} + v; }
inline DoubleN load_n(const double* p) {
  DoubleN v;
  __builtin_memcpy(&v, p, sizeof v);
  return v;
}
inline void store_n(double* p, DoubleN v) { __builtin_memcpy(p, &v, sizeof v); }
inline DoubleN min_n(DoubleN a, DoubleN b) { return a < b ? a : b; }
inline DoubleN max_n(DoubleN a, DoubleN b) { return a > b ? a : b; }
inline DoubleN abs_n(DoubleN a) { return a < 0 ? -a : a; }
inline DoubleN sqrt_n(DoubleN a) {
#if defined(__AVX512F__)
  // The masked form: GCC 12 warns of an uninitialised operand in _mm512_sqrt_pd.
  const __m512d v = reinterpret_cast<__m512d>(a);
  return reinterpret_cast<DoubleN>(_mm512_mask_sqrt_pd(v, static_cast<__mmask8>(0xff), v));
#elif defined(__AVX__)
  return reinterpret_cast<DoubleN>(_mm256_sqrt_pd(reinterpret_cast<__m256d>(a)));
#elif defined(__SSE2__)
  return reinterpret_cast<DoubleN>(_mm_sqrt_pd(reinterpret_cast<__m128d>(a)));
#else
  return DoubleN{std::sqrt(a[0]), std::sqrt(a[1])};
#endif
}
inline bool any_n(MaskN m) {
#if defined(__AVX512F__)
  return _mm512_test_epi64_mask(reinterpret_cast<__m512i>(m), reinterpret_cast<__m512i>(m)) != 0;
#elif defined(__AVX__)
  return _mm256_movemask_pd(reinterpret_cast<__m256d>(m)) != 0;
#elif defined(__SSE2__)
  return _mm_movemask_pd(reinterpret_cast<__m128d>(m)) != 0;
#else
  return (m[0] | m[1]) != 0;
#endif
}
inline bool all_n(MaskN m) {
#if defined(__AVX512F__)
  return _mm512_test_epi64_mask(reinterpret_cast<__m512i>(m), reinterpret_cast<__m512i>(m)) == 0xff;
#elif defined(__AVX__)
  return _mm256_movemask_pd(reinterpret_cast<__m256d>(m)) == (1 << kLanes) - 1;
#elif defined(__SSE2__)
  return _mm_movemask_pd(reinterpret_cast<__m128d>(m)) == (1 << kLanes) - 1;
#else
  return (m[0] & m[1]) != 0;
#endif
}
// Bit l set where lane l of m is set.
inline std::uint32_t lane_bits(MaskN m) {
#if defined(__AVX512F__)
  return _mm512_test_epi64_mask(reinterpret_cast<__m512i>(m), reinterpret_cast<__m512i>(m));
#elif defined(__AVX__)
  return static_cast<std::uint32_t>(_mm256_movemask_pd(reinterpret_cast<__m256d>(m)));
#elif defined(__SSE2__)
  return static_cast<std::uint32_t>(_mm_movemask_pd(reinterpret_cast<__m128d>(m)));
#else
  return (m[0] != 0 ? 1u : 0u) | (m[1] != 0 ? 2u : 0u);
#endif
}
// The mask with lane l set where bit l is (lane_bits' inverse).
inline MaskN bits_mask(std::uint32_t bits) {
  MaskN bit{};
  for (int l = 0; l < kLanes; ++l) bit[l] = 1ll << l;
  return ((MaskN{} + static_cast<long long>(bits)) & bit) != 0;
}
inline double max_lane(DoubleN a) {
  double m = a[0];
  for (int l = 1; l < kLanes; ++l) m = std::max(m, a[l]);
  return m;
}
inline DoubleN lane_index() {
  DoubleN lane{};
  for (int l = 0; l < kLanes; ++l) lane[l] = l;
  return lane;
}

// The squared distance from points at offsets (ux, uy) from a move's start to its path (v, and
// 1/|v|² > 0).
inline DoubleN path_distance2(DoubleN ux, DoubleN uy, double vx, double vy, double inv_vv) {
  const DoubleN along = min_n(max_n((ux * vx + uy * vy) * inv_vv, splat(0)), splat(1));
  const DoubleN dx = ux - along * vx, dy = uy - along * vy;
  return dx * dx + dy * dy;
}

}  // namespace tridex::detail
