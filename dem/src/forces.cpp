// dem/src/forces.cpp — contact and wall forces over the half list (the same terms in the same order
// at any rank count), and the elastic contact energy. The part (ContactForces) is declared in
// contact_forces.hpp, the pass itself in force_pass.hpp (compiled here for the build's target,
// and in forces_avx512.cpp with AVX-512).
#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>
#include <span>
#include <string>

#include "contact_forces.hpp"
#include "force_pass.hpp"
#include "impl.hpp"
#include "pairs.hpp"

namespace coloc::dem {

using namespace detail;

// ---------------------------------------------------------------------------------------------
// ContactForces

ContactTally detail::forcePassBuild(const ForcePassArgs& a) {
  return forcePass<ScalarRows>(a);
}

bool ContactForces::selectIsa(ForceIsa want) {
  const bool avx512 = __builtin_cpu_supports("avx512f") && __builtin_cpu_supports("avx512vl");
  if (want == ForceIsa::Widest) want = avx512 ? ForceIsa::Avx512 : ForceIsa::Scalar;
  if (want == ForceIsa::Avx512 && !avx512) return false;
  isa_ = want;
  return true;
}

void ContactForces::compute(const ForceInputs& in, bool update, bool stepped, HeatPass* heat) {
  // inside a step without a rebuild, the integration has reset the sums and packed the owned
  // bodies; else both here. The ghosts' bodies are packed here.
  const bool ownedCurrent = stepped && packed_;
  if (!ownedCurrent) resetSums(in);
  packBodies(in.p, ownedCurrent ? in.p.nOwned : 0);
  packed_ = true;
  const ForcePassArgs a{in, law, body_.data(), chunk_, update, heat};
  tally_ = isa_ == ForceIsa::Avx512 ? forcePassAvx512(a) : forcePassBuild(a);
}

void ContactForces::resetSums(const ForceInputs& in) {
  ParticleStore& p = in.p;
  const std::size_t n = p.nOwned;
  for (int k = 0; k < 3; ++k) {
    const double* fe = p.fExt[k].data();
    const double* ms = p.mass.data();
    double* fk = p.f[k].data();
    double* tk = p.torque[k].data();
    const double gk = in.g[k];
#pragma omp simd
    for (std::size_t i = 0; i < n; ++i) {
      fk[i] = ms[i] * gk + fe[i];
      tk[i] = 0;
    }
  }
  ensure(body_, p.size());
  body_.resize(p.size());
}

unsigned char* ContactForces::lend(std::size_t bytes) {
  ensure(body_, (bytes + sizeof(Body) - 1) / sizeof(Body));
  return reinterpret_cast<unsigned char*>(body_.data());
}

void ContactForces::packBodies(const ParticleStore& p, std::size_t from) {
  const double *X0 = p.x[0].data(), *X1 = p.x[1].data(), *X2 = p.x[2].data();
  const double *V0 = p.v[0].data(), *V1 = p.v[1].data(), *V2 = p.v[2].data();
  const double *R = p.radius.data(), *Ms = p.mass.data();
  Body* Bw = body_.data();
  for (std::size_t i = from; i < p.size(); ++i)
    Bw[i] = Body{{X0[i], X1[i], X2[i]}, R[i], {V0[i], V1[i], V2[i]}, Ms[i]};
}

void DemSolver::Impl::computeForces(bool update, bool stepped) {
  // conduction rides the force pass (force_pass.hpp) when it has contacts to conduct through
  if (heat.on && heat.conduction) {
    HeatPass h = heat.forcePass(p);
    forces.compute({p, search, integrator.dt, integrator.g}, update, stepped, &h);
    heat.setWallRate(h.wallRate);
    return;
  }
  forces.compute({p, search, integrator.dt, integrator.g}, update, stepped, nullptr);
  if (heat.on) heat.conduct(p, search);  // no conduction: the heat rates are zeroed
}

// ---------------------------------------------------------------------------------------------
// energy
double DemSolver::contactEnergy() const {
  const auto& m = *impl_;
  const auto& p = m.p;
  const std::size_t n = p.nOwned;
  const detail::Bins& bins = m.search.bins();
  const detail::NeighbourList& list = m.search.list();
  double e = 0;
  for (std::size_t q = 0; q < p.size(); ++q) {
    const auto i = static_cast<std::size_t>(bins.binItems[q]);
    for (int k = list.rowStart[q]; k < list.rowStart[q + 1]; ++k) {
      const int j = list.nbr[static_cast<std::size_t>(k)];
      if (j >= 0) {
        const auto u = static_cast<std::size_t>(j);
        double r2 = 0;
        for (int d = 0; d < 3; ++d) r2 += (p.x[d][i] - p.x[d][u]) * (p.x[d][i] - p.x[d][u]);
        const double rs = p.radius[i] + p.radius[u];
        if (r2 >= rs * rs) continue;
        // half of the pair's energy to each owned particle of the pair
        const double share = 0.5 * ((i < n ? 1 : 0) + (u < n ? 1 : 0));
        const auto& c =
            m.forces.law
                .pair[static_cast<std::size_t>(p.material[i] * m.forces.law.nMat + p.material[u])];
        e += share * detail::normalEnergy(m.forces.law.model, c, rs - std::sqrt(r2),
                                          p.radius[i] * p.radius[u] / rs);
      } else {
        const int w = -1 - j, d = w / 2, s = w % 2;
        const double dist =
            s == 0 ? p.x[d][i] - bins.origin[d] : bins.origin[d] + bins.L[d] - p.x[d][i];
        const double delta = p.radius[i] - dist;
        if (delta > 0)
          e += detail::normalEnergy(m.forces.law.model,
                                    m.forces.law.wall[static_cast<std::size_t>(p.material[i])],
                                    delta, p.radius[i]);
      }
    }
  }
  return m.comm.sum(e);
}

}  // namespace coloc::dem
