// dem/src/forces_avx512.cpp — the force pass (force_pass.hpp) with pass 1 on AVX-512 (F, VL):
// a row's entries eight at a time. Compiled with -mavx512f -mavx512vl (dem/CMakeLists.txt);
// ContactForces (forces.cpp) calls it on CPUs that have them.
//
// For eight entries of a row (those of the inner list while it is valid): the partners' x and r
// gathered from their packed lines, the distance test in exact double arithmetic without FMA (the
// operations of ForcePass::gatherPair in its order: the same bits), the touching pair entries
// compressed into a register and stored at the chunk's end in list order, their count added;
// the rare entries where a contact starts or ends (touching without a history slot, or the
// reverse) fixed in entry order by the scalar code, and the wall entries (a row's last) appended
// by it after the row's pairs, so the chunk is the scalar pass's entry for entry.
#include <immintrin.h>

#include "force_pass.hpp"

namespace coloc::dem::detail {

namespace {  // NOLINT(google-build-namespaces,cert-dcl59-cpp)

struct Avx512Rows {
  // the partners' lines of the row this far ahead are prefetched (ForcePass::prefetchRow)
  static constexpr std::size_t kRowsAhead = 6;
  // the holder's r, m, v, omega stored beside its pairs (PairChunk::hold), not gathered in pass 2
  static constexpr bool kHolderInChunk = true;
  template <class FP>
  static unsigned row(FP& f, const Row& r) {
    PairChunk& ch = f.ch_;
    const __m512d xi0 = _mm512_set1_pd(r.xi[0]), xi1 = _mm512_set1_pd(r.xi[1]),
                  xi2 = _mm512_set1_pd(r.xi[2]), ri = _mm512_set1_pd(r.ri),
                  margin = _mm512_set1_pd(f.margin_), zero = _mm512_setzero_pd();
    const __m256i izero = _mm256_setzero_si256();
    const __m256i holder = _mm256_set1_epi32(static_cast<int>(r.i));
    const __m256i noWall = _mm256_set1_epi32(-1);
    const __m256i coefRow = _mm256_set1_epi32(r.coefRow);
    // line u at base + 8 u: x, y, z, r, v, m (pairs.hpp: Body)
    const auto* const base = reinterpret_cast<const double*>(f.B_);
    unsigned kept = 0;
    const Body& bi = f.B_[r.i];
    const double hv[8] = {
        bi.r, bi.m, bi.v[0], bi.v[1], bi.v[2], f.in_.w[0][r.i], f.in_.w[1][r.i], f.in_.w[2][r.i]};
    for (int w = r.e0; w < r.e1; w += 8) {
      const int k0 = w - r.e0;
      auto live = static_cast<__mmask8>(r.e1 - w >= 8 ? 0xff : (1u << (r.e1 - w)) - 1);
      if (f.inner_ && k0 < kKeepBits) live &= static_cast<__mmask8>(r.keep >> k0);
      if (live == 0) continue;
      if (ch.m > kChunk - 8) f.flush();  // room for eight
      const __m256i j = _mm256_maskz_loadu_epi32(live, f.nbrs_ + w);
      const __mmask8 pair = _mm256_mask_cmpge_epi32_mask(live, j, izero);
      const __mmask8 walls = live & static_cast<__mmask8>(~pair);
      const __m256i line = _mm256_slli_epi32(j, 3);
      const __m512d X = _mm512_mask_i32gather_pd(zero, pair, line, base + 0, 8);
      const __m512d Y = _mm512_mask_i32gather_pd(zero, pair, line, base + 1, 8);
      const __m512d Z = _mm512_mask_i32gather_pd(zero, pair, line, base + 2, 8);
      const __m512d R = _mm512_mask_i32gather_pd(zero, pair, line, base + 3, 8);
      const __m512d dx = _mm512_sub_pd(xi0, X), dy = _mm512_sub_pd(xi1, Y),
                    dz = _mm512_sub_pd(xi2, Z);
      const __m512d r2 = _mm512_add_pd(_mm512_add_pd(_mm512_mul_pd(dx, dx), _mm512_mul_pd(dy, dy)),
                                       _mm512_mul_pd(dz, dz));
      const __m512d rs = _mm512_add_pd(ri, R);
      const __mmask8 touch = _mm512_mask_cmp_pd_mask(pair, r2, _mm512_mul_pd(rs, rs), _CMP_NGE_UQ);
      if (f.prune_ && k0 < kKeepBits) {
        const __m512d rm = _mm512_add_pd(rs, margin);
        kept |= static_cast<unsigned>(
                    _mm512_mask_cmp_pd_mask(pair, r2, _mm512_mul_pd(rm, rm), _CMP_NGE_UQ))
                << k0;
      }
      __m256i s = _mm256_maskz_loadu_epi32(live, f.sl_ + w);
      const __mmask8 has = _mm256_mask_cmpge_epi32_mask(pair, s, izero);
      if (const unsigned change = static_cast<unsigned>(touch ^ has); change != 0) {
        for (unsigned b = change; b != 0; b &= b - 1) {
          const int l = std::countr_zero(b);
          f.fixSlot(w + l, (touch >> l) & 1);
        }
        s = _mm256_maskz_loadu_epi32(live, f.sl_ + w);
      }
      const int m = ch.m;
      _mm512_storeu_pd(ch.dx[0] + m, _mm512_maskz_compress_pd(touch, dx));
      _mm512_storeu_pd(ch.dx[1] + m, _mm512_maskz_compress_pd(touch, dy));
      _mm512_storeu_pd(ch.dx[2] + m, _mm512_maskz_compress_pd(touch, dz));
      _mm512_storeu_pd(ch.r2 + m, _mm512_maskz_compress_pd(touch, r2));
      _mm256_storeu_si256(reinterpret_cast<__m256i*>(ch.u + m),
                          _mm256_maskz_compress_epi32(touch, j));
      _mm256_storeu_si256(reinterpret_cast<__m256i*>(ch.slot + m),
                          _mm256_maskz_compress_epi32(touch, s));
      _mm256_storeu_si256(reinterpret_cast<__m256i*>(ch.i + m), holder);
      _mm256_storeu_si256(reinterpret_cast<__m256i*>(ch.wall + m), noWall);
      for (int c = 0; c < 8; ++c) _mm512_storeu_pd(ch.hold[c] + m, _mm512_set1_pd(hv[c]));
      if (!f.single_) {
        const __m256i mu = _mm256_mmask_i32gather_epi32(izero, pair, j, f.mat_, 4);
        _mm256_storeu_si256(reinterpret_cast<__m256i*>(ch.coef + m),
                            _mm256_maskz_compress_epi32(touch, _mm256_add_epi32(coefRow, mu)));
      }
      const int mEnd = m + std::popcount(static_cast<unsigned>(touch));
      // (no prefetch of the touching partners' spin, force and torque lines nor of the
      // histories: passes 2 and 3 find them in cache, and the prefetches cost 5-10 % of the
      // step, measured)
      ch.m = mEnd;
      // the row's walls, after its pairs, entry by entry
      for (unsigned b = walls; b != 0; b &= b - 1) {
        const int l = std::countr_zero(b), e = w + l, k = ch.m;
        bool kb = false;
        const bool t = f.prune_ ? f.template gatherWall<true>(k, r, f.nbrs_[e], kb)
                                : f.template gatherWall<false>(k, r, f.nbrs_[e], kb);
        if (t != (f.sl_[e] >= 0)) f.fixSlot(e, t);
        ch.i[k] = static_cast<int>(r.i);
        ch.slot[k] = f.sl_[e];
        ch.m = k + (t ? 1 : 0);
        if (f.prune_ && k0 < kKeepBits) kept |= static_cast<unsigned>(kb) << (k0 + l);
      }
    }
    return kept;
  }
};

}  // namespace

ContactTally forcePassAvx512(const ForcePassArgs& a) {
  return forcePass<Avx512Rows>(a);
}

}  // namespace coloc::dem::detail
