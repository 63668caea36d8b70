// bench_peak: one core's ceilings, the other half of the roofline (bench/scripts/roofline.py).
//
//  BM_MulAdd/<isa>   : a = a * m + c on 12 independent accumulators, mul and add as separate
//                      instructions (no contraction: this file is compiled with -ffp-contract=off,
//                      as the DEM is), 2 flops an element; isa = scalar, sse2 (2 lanes, the
//                      portable x86-64 build of fv, coupling and hypre), avx2 (4), avx512 (8; the
//                      DEM is compiled with -march=native). Counter flops: flop/s of one core.
//  BM_Fma/<isa>      : the same with fused multiply-adds (scalar, avx2, avx512): 2 flops an FMA.
//  BM_ReadSum/<MiB>  : sum of an array of MiB (8 accumulators of 2 lanes): read-only bandwidth
//                      of one core (counter bytes: bytes/s), the gathers' side of memory.
//  BM_Triad/<MiB>    : a[i] = b[i] + s c[i], 24 B an element (STREAM's count), one core.
//  BM_Chase/<MiB>    : a dependent walk through a random cyclic permutation of MiB (one 64-byte
//                      line a step): ns a step = the latency of a miss at that size (counter
//                      seconds_per_load), the bound of a gather whose addresses are not known
//                      ahead.
// An ISA this CPU lacks is skipped (SkipWithError). One thread; run it on an idle core:
//   build/bench/bench_peak --benchmark_out=peak.json --benchmark_out_format=json
#include <benchmark/benchmark.h>
#include <immintrin.h>

#include <cstdint>
#include <numeric>
#include <vector>

namespace {

constexpr int kAcc = 12;     // independent chains: enough to fill 2-4 pipes of 3-5 cycles
constexpr long kInner = 64;  // iterations between two checks of the benchmark loop

using D2 = double __attribute__((vector_size(16)));
using D4 = double __attribute__((vector_size(32)));
using D8 = double __attribute__((vector_size(64)));

/// kInner x kAcc x L elements of a = a * m + c, mul and add separate (V: double, or a vector of
/// L doubles).
template <class V, int L>
__attribute__((always_inline)) inline double mulAddBody(long reps) {
  V acc[kAcc], m, c;
  if constexpr (L == 1) {
    m = 0.999999, c = 1e-3;
    for (int k = 0; k < kAcc; ++k) acc[k] = 1.0 + 0.01 * k;
  } else {
    for (int l = 0; l < L; ++l) m[l] = 0.999999, c[l] = 1e-3;
    for (int k = 0; k < kAcc; ++k)
      for (int l = 0; l < L; ++l) acc[k][l] = 1.0 + 0.01 * k + 0.001 * l;
  }
  for (long r = 0; r < reps; ++r) {
    for (long it = 0; it < kInner; ++it)
#pragma GCC unroll 12
      for (int k = 0; k < kAcc; ++k) acc[k] = acc[k] * m + c;
    benchmark::DoNotOptimize(acc[0]);
  }
  double s = 0;
  for (int k = 0; k < kAcc; ++k) {
    if constexpr (L == 1)
      s += acc[k];
    else
      for (int l = 0; l < L; ++l) s += acc[k][l];
  }
  return s;
}

double mulAddScalar(long reps) {
  return mulAddBody<double, 1>(reps);
}
double mulAddSse2(long reps) {
  return mulAddBody<D2, 2>(reps);
}
__attribute__((target("avx2"))) double mulAddAvx2(long reps) {
  return mulAddBody<D4, 4>(reps);
}
__attribute__((target("avx512f"))) double mulAddAvx512(long reps) {
  return mulAddBody<D8, 8>(reps);
}

__attribute__((target("fma"))) double fmaScalar(long reps) {
  double acc[kAcc];
  for (int k = 0; k < kAcc; ++k) acc[k] = 1.0 + 0.01 * k;
  const __m128d m = _mm_set_sd(0.999999), c = _mm_set_sd(1e-3);
  for (long r = 0; r < reps; ++r) {
    for (long it = 0; it < kInner; ++it)
#pragma GCC unroll 12
      for (int k = 0; k < kAcc; ++k) acc[k] = _mm_cvtsd_f64(_mm_fmadd_sd(_mm_set_sd(acc[k]), m, c));
    benchmark::DoNotOptimize(acc[0]);
  }
  double s = 0;
  for (double a : acc) s += a;
  return s;
}

__attribute__((target("avx2,fma"))) double fmaAvx2(long reps) {
  __m256d acc[kAcc];
  for (int k = 0; k < kAcc; ++k) acc[k] = _mm256_set1_pd(1.0 + 0.01 * k);
  const __m256d m = _mm256_set1_pd(0.999999), c = _mm256_set1_pd(1e-3);
  for (long r = 0; r < reps; ++r) {
    for (long it = 0; it < kInner; ++it)
#pragma GCC unroll 12
      for (int k = 0; k < kAcc; ++k) acc[k] = _mm256_fmadd_pd(acc[k], m, c);
    benchmark::DoNotOptimize(acc[0]);
  }
  double out[4], s = 0;
  for (int k = 0; k < kAcc; ++k) {
    _mm256_storeu_pd(out, acc[k]);
    s += out[0] + out[1] + out[2] + out[3];
  }
  return s;
}

__attribute__((target("avx512f"))) double fmaAvx512(long reps) {
  __m512d acc[kAcc];
  for (int k = 0; k < kAcc; ++k) acc[k] = _mm512_set1_pd(1.0 + 0.01 * k);
  const __m512d m = _mm512_set1_pd(0.999999), c = _mm512_set1_pd(1e-3);
  for (long r = 0; r < reps; ++r) {
    for (long it = 0; it < kInner; ++it)
#pragma GCC unroll 12
      for (int k = 0; k < kAcc; ++k) acc[k] = _mm512_fmadd_pd(acc[k], m, c);
    benchmark::DoNotOptimize(acc[0]);
  }
  double out[8], s = 0;
  for (int k = 0; k < kAcc; ++k) {
    _mm512_storeu_pd(out, acc[k]);
    for (double o : out) s += o;
  }
  return s;
}

struct Kernel {
  const char* isa;
  int lanes;
  double (*fn)(long);
  bool (*supported)();
};

bool always() {
  return true;
}
bool hasAvx2() {
  return __builtin_cpu_supports("avx2");
}
bool hasAvx512() {
  return __builtin_cpu_supports("avx512f");
}
bool hasFma() {
  return __builtin_cpu_supports("fma");
}
bool hasAvx2Fma() {
  return hasAvx2() && hasFma();
}

const Kernel kMulAdd[] = {{"scalar", 1, mulAddScalar, always},
                          {"sse2", 2, mulAddSse2, always},
                          {"avx2", 4, mulAddAvx2, hasAvx2},
                          {"avx512", 8, mulAddAvx512, hasAvx512}};
const Kernel kFma[] = {{"scalar", 1, fmaScalar, hasFma},
                       {"avx2", 4, fmaAvx2, hasAvx2Fma},
                       {"avx512", 8, fmaAvx512, hasAvx512}};

void runFlops(benchmark::State& state, const Kernel& k) {
  if (!k.supported()) {
    state.SkipWithError("this CPU lacks the instruction set");
    return;
  }
  constexpr long kReps = 2000;
  for (auto _ : state) benchmark::DoNotOptimize(k.fn(kReps));
  // 2 flops (a mul and an add, or one FMA) an element
  const double flops = 2.0 * kReps * kInner * kAcc * k.lanes;
  state.counters["flops"] = benchmark::Counter(flops * static_cast<double>(state.iterations()),
                                               benchmark::Counter::kIsRate);
  state.SetLabel(k.isa);
}

void BM_MulAdd(benchmark::State& state) {
  runFlops(state, kMulAdd[state.range(0)]);
}
void BM_Fma(benchmark::State& state) {
  runFlops(state, kFma[state.range(0)]);
}

std::size_t elements(const benchmark::State& state, double bytesEach) {
  return static_cast<std::size_t>(static_cast<double>(state.range(0)) * 1048576.0 / bytesEach);
}

void BM_ReadSum(benchmark::State& state) {
  const std::size_t n = elements(state, 8.0) / 16 * 16;
  std::vector<double> a(n, 1.0);
  for (auto _ : state) {
    D2 acc[8] = {};
    for (std::size_t i = 0; i < n; i += 16)
      for (int k = 0; k < 8; ++k) {
        D2 v;
        __builtin_memcpy(&v, &a[i + 2 * static_cast<std::size_t>(k)], sizeof v);
        acc[k] += v;
      }
    for (int k = 1; k < 8; ++k) acc[0] += acc[k];
    benchmark::DoNotOptimize(acc[0]);
  }
  state.counters["bytes"] =
      benchmark::Counter(8.0 * static_cast<double>(n) * static_cast<double>(state.iterations()),
                         benchmark::Counter::kIsRate);
}

void BM_Triad(benchmark::State& state) {
  const std::size_t n = elements(state, 24.0) / 2 * 2;
  std::vector<double> a(n, 0.0), b(n, 1.0), c(n, 2.0);
  const double s = 1.0000001;
  const D2 s2 = {s, s};
  for (auto _ : state) {
    for (std::size_t i = 0; i + 1 < n; i += 2) {
      D2 vb, vc;
      __builtin_memcpy(&vb, &b[i], sizeof vb);
      __builtin_memcpy(&vc, &c[i], sizeof vc);
      const D2 va = vb + s2 * vc;
      __builtin_memcpy(&a[i], &va, sizeof va);
    }
    benchmark::DoNotOptimize(a.data());
    benchmark::ClobberMemory();
  }
  state.counters["bytes"] =
      benchmark::Counter(24.0 * static_cast<double>(n) * static_cast<double>(state.iterations()),
                         benchmark::Counter::kIsRate);
}

void BM_Chase(benchmark::State& state) {
  // one index a 64-byte line: next[8 * i] holds the line visited after line i
  const std::size_t lines = elements(state, 64.0);
  std::vector<std::uint32_t> order(lines);
  std::iota(order.begin(), order.end(), 0U);
  std::uint64_t x = 0x9E3779B97F4A7C15ULL;  // xorshift: a fixed random cycle
  for (std::size_t i = lines - 1; i > 0; --i) {
    x ^= x << 13, x ^= x >> 7, x ^= x << 17;
    std::swap(order[i], order[x % (i + 1)]);
  }
  std::vector<std::uint32_t> next(16 * lines, 0);
  for (std::size_t i = 0; i < lines; ++i) next[16 * order[i]] = order[(i + 1) % lines];
  const std::size_t steps = std::max<std::size_t>(lines, 1 << 20);
  std::uint32_t p = order[0];
  for (auto _ : state) {
    for (std::size_t s = 0; s < steps; ++s) p = next[16 * static_cast<std::size_t>(p)];
    benchmark::DoNotOptimize(p);
  }
  // steps a iteration (the counter multiplies by the iterations), per second, inverted
  state.counters["seconds_per_load"] =
      benchmark::Counter(static_cast<double>(steps), benchmark::Counter::kIsIterationInvariantRate |
                                                         benchmark::Counter::kInvert);
}

}  // namespace

BENCHMARK(BM_MulAdd)->DenseRange(0, 3)->Unit(benchmark::kMicrosecond);
BENCHMARK(BM_Fma)->DenseRange(0, 2)->Unit(benchmark::kMicrosecond);
BENCHMARK(BM_ReadSum)
    ->Arg(1)
    ->Arg(4)
    ->Arg(16)
    ->Arg(32)
    ->Arg(64)
    ->Arg(256)
    ->Unit(benchmark::kMicrosecond);
BENCHMARK(BM_Triad)->Arg(1)->Arg(4)->Arg(16)->Arg(32)->Arg(64)->Arg(256)->Unit(
    benchmark::kMicrosecond);
BENCHMARK(BM_Chase)->Arg(1)->Arg(16)->Arg(256)->Unit(benchmark::kMillisecond);
