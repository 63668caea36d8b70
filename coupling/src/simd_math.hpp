// coupling/src/simd_math.hpp — a few vectorised elementary functions for the batched drag laws
// (drag.cpp): SLEEF's (libsleef, 1-ulp "u10" variants) on packs of doubles, the pack as wide as
// the instruction set the build targets.
//
//   AVX-512F  (drag_avx512.cpp)  8 lanes, SLEEF's run-time dispatcher among its AVX-512 variants;
//   AVX2      (drag_avx2.cpp)    4 lanes, SLEEF's AVX2 variant;
//   otherwise (drag.cpp in the portable x86-64 build: SSE2 only)  2 lanes, SLEEF's run-time
//             dispatcher (its SSE2, SSE4.1 or 128-bit AVX2+FMA variant for the CPU).
//
// Every lane goes through the same code: a particle's value depends on its own inputs only, never
// on the lane or the pack it falls in (the caller pads a partial pack). The choice of variant is
// made once per process, the same on every rank of a run on one kind of CPU; a build for another
// instruction set (or, for the portable build, a CPU of another generation) may differ in the
// last bits. This is the one place that knows the instruction set (no #if in the kernels).
#pragma once

#include <immintrin.h>
#include <sleef.h>

#include <cstddef>
#include <cstring>

// Internal linkage: each translation unit (one per instruction set, drag_packs.hpp) its own copy.
namespace coloc::coupling::simd {
namespace {  // NOLINT(google-build-namespaces,cert-dcl59-cpp)

#if defined(__AVX512F__)
using Pack = __m512d;
inline constexpr std::size_t kLanes = 8;
inline Pack log(Pack x) {
  return Sleef_logd8_u10(x);
}
inline Pack exp(Pack x) {
  return Sleef_expd8_u10(x);
}
// (the masked form: GCC 12 warns of the unmasked one's undefined pass-through operand)
inline Pack sqrt(Pack x) {
  return _mm512_mask_sqrt_pd(x, 0xff, x);
}
#elif defined(__AVX2__)
using Pack = __m256d;
inline constexpr std::size_t kLanes = 4;
inline Pack log(Pack x) {
  return Sleef_logd4_u10avx2(x);
}
inline Pack exp(Pack x) {
  return Sleef_expd4_u10avx2(x);
}
inline Pack sqrt(Pack x) {
  return _mm256_sqrt_pd(x);
}
#else
using Pack = __m128d;
inline constexpr std::size_t kLanes = 2;
inline Pack log(Pack x) {
  return Sleef_logd2_u10(x);
}
inline Pack exp(Pack x) {
  return Sleef_expd2_u10(x);
}
inline Pack sqrt(Pack x) {
  return _mm_sqrt_pd(x);
}
#endif

// Arithmetic, comparisons and selection are GCC/Clang vector-extension operators on Pack
// (a * b, a * 2.0, a < b ? x : y), lane by lane.
inline Pack splat(double v) {
  Pack p;
  for (std::size_t l = 0; l < kLanes; ++l) p[l] = v;
  return p;
}
inline Pack load(const double* a) {
  Pack p;
  std::memcpy(&p, a, sizeof p);
  return p;
}
inline void store(double* a, Pack p) {
  std::memcpy(a, &p, sizeof p);
}
/// std::max(a, b) lane by lane (the same operand on ties).
inline Pack max(Pack a, Pack b) {
  return a < b ? b : a;
}
/// a^b = exp(b log a), a > 0.
inline Pack pow(Pack a, Pack b) {
  return exp(b * log(a));
}

}  // namespace
}  // namespace coloc::coupling::simd
