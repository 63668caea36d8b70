#include "momentum.hpp"

#include "momentum_kernels.hpp"

namespace coloc::fv {

COLOC_MOMENTUM_DEFINE(explicitTermsBuild, predictFacesBuild)

void massFluxes(const FaceField& u, const CellField& eps, FaceField& M) {
  const double* ec = eps.data().data();
  for (int d = 0; d < 3; ++d) {
    const Field3<double>& U = u[d];
    Field3<double>& m = M[d];
    IndexBox box = U.allocated();
    box.lo[d] += 1;  // face idx needs cells idx - e_d and idx
    box.hi[d] -= 1;
    const std::ptrdiff_t cd = eps.stride(d);
    const double* up = U.data().data();
    double* mp = m.data().data();
    for (int k = box.lo[2]; k < box.hi[2]; ++k)
      for (int j = box.lo[1]; j < box.hi[1]; ++j) {
        const std::ptrdiff_t q0 = U.index(box.lo[0], j, k);
        const std::ptrdiff_t c0 = eps.index(box.lo[0], j, k);
#pragma GCC ivdep
        for (int i = 0; i < box.hi[0] - box.lo[0]; ++i)
          mp[q0 + i] = 0.5 * (ec[c0 + i - cd] + ec[c0 + i]) * up[q0 + i];
      }
  }
}

namespace {

/// The variant to run for `isa`: Widest is the widest the CPU runs (momentum_kernels.hpp; all
/// give the same bits); false where the CPU lacks the instructions.
bool resolve(MomentumIsa& isa) {
  const bool avx512 = __builtin_cpu_supports("avx512f");
  const bool avx2 = __builtin_cpu_supports("avx2");
  if (isa == MomentumIsa::Widest)
    isa = avx512 ? MomentumIsa::Avx512 : avx2 ? MomentumIsa::Avx2 : MomentumIsa::Build;
  return !((isa == MomentumIsa::Avx512 && !avx512) || (isa == MomentumIsa::Avx2 && !avx2));
}

}  // namespace

bool explicitTermsOn(MomentumIsa isa, int d, const FaceField& u, const FaceField& M,
                     const CellField& eps, const MomentumParams& prm, const IndexBox& box,
                     Field3<double>& H) {
  if (!resolve(isa)) return false;
  const ExplicitTermsFn f = isa == MomentumIsa::Avx512 ? explicitTermsAvx512
                            : isa == MomentumIsa::Avx2 ? explicitTermsAvx2
                                                       : explicitTermsBuild;
  f(d, u, M, eps, prm, box, H);
  return true;
}

bool predictFacesOn(MomentumIsa isa, const PredictFaces& p, Field3<double>& U, Field3<double>& P) {
  if (!resolve(isa)) return false;
  const PredictFacesFn f = isa == MomentumIsa::Avx512 ? predictFacesAvx512
                           : isa == MomentumIsa::Avx2 ? predictFacesAvx2
                                                      : predictFacesBuild;
  f(p, U, P);
  return true;
}

void predictFaces(const PredictFaces& p, Field3<double>& U, Field3<double>& P) {
  predictFacesOn(MomentumIsa::Widest, p, U, P);
}

void explicitTerms(int d, const FaceField& u, const FaceField& M, const CellField& eps,
                   const MomentumParams& prm, const IndexBox& box, Field3<double>& H) {
  explicitTermsOn(MomentumIsa::Widest, d, u, M, eps, prm, box, H);
}

}  // namespace coloc::fv
