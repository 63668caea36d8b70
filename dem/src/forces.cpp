// dem/src/forces.cpp — contact and wall forces over the half list (the same terms in the same order
// at any rank count), and the elastic contact energy.
#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>
#include <span>
#include <string>

#include "impl.hpp"

namespace coloc::dem {

using namespace detail;

// ---------------------------------------------------------------------------------------------
// forces

void DemSolver::Impl::computeForces(bool update) {
  if (model == Model::HertzMindlin)
    rolling ? forces<Model::HertzMindlin, true>(update)
            : forces<Model::HertzMindlin, false>(update);
  else
    rolling ? forces<Model::Linear, true>(update) : forces<Model::Linear, false>(update);
}

// Each pair is computed once (Newton's third law inside the rank; an owned-ghost pair is
// computed by each rank for its own particle, "newton off" across ranks, so nothing goes back to
// a ghost's owner). Holders are visited in K order (see buildLists), so a particle receives the
// terms of its lower-K partners (pushed by their rows, in increasing K), then those of its own
// row (increasing K), then its walls: the same sum in the same order at any rank count, and the
// pair term itself is computed from the same operands (lower K first) everywhere.
template <Model M, bool Rolling>
void DemSolver::Impl::forces(bool update) {
  const std::size_t n = p.nOwned, nAll = p.size();
  double* FX[3] = {p.f[0].data(), p.f[1].data(), p.f[2].data()};
  double* TX[3] = {p.torque[0].data(), p.torque[1].data(), p.torque[2].data()};
  for (int k = 0; k < 3; ++k) {
    const double* fe = p.fExt[k].data();
    const double* ms = p.mass.data();
    for (std::size_t i = 0; i < n; ++i) {
      FX[k][i] = ms[i] * g[k] + fe[i];
      TX[k][i] = 0;
    }
  }
  const double* X[3] = {p.x[0].data(), p.x[1].data(), p.x[2].data()};
  const double* V[3] = {p.v[0].data(), p.v[1].data(), p.v[2].data()};
  const double* W[3] = {p.omega[0].data(), p.omega[1].data(), p.omega[2].data()};
  const double* R = p.radius.data();
  const double* Ms = p.mass.data();
  const int* mat = p.material.data();
  const int* nbrs = list.nbr.data();
  int* sl = list.slot.data();
  long long nc = 0, nw = 0;
  double worst = 0;
  std::int64_t worstId = -1, worstPartner = 0;
  for (std::size_t q = 0; q < nAll; ++q) {
    const int e0 = list.rowStart[q], e1 = list.rowStart[q + 1];
    if (e0 == e1) continue;
    const auto i = static_cast<std::size_t>(bins.binItems[q]);
    const bool ownI = i < n;
    const double ri = R[i], mi = Ms[i];
    double F[3] = {0, 0, 0}, T[3] = {0, 0, 0};
    if (ownI)
      for (int k = 0; k < 3; ++k) {
        F[k] = FX[k][i];
        T[k] = TX[k][i];
      }
    const double xi[3] = {X[0][i], X[1][i], X[2][i]};
    const double vi[3] = {V[0][i], V[1][i], V[2][i]};
    const double wi[3] = {W[0][i], W[1][i], W[2][i]};
    const PairCoeff* rowC = &pairC[static_cast<std::size_t>(mat[i] * nMat)];
    for (int e = e0; e < e1; ++e) {
      const int j = nbrs[e];
      if (j >= 0) {
        const auto u = static_cast<std::size_t>(j);
        const double dx[3] = {xi[0] - X[0][u], xi[1] - X[1][u], xi[2] - X[2][u]};
        const double r2 = dx[0] * dx[0] + dx[1] * dx[1] + dx[2] * dx[2];
        const double rj = R[u], rs = ri + rj;
        if (r2 >= rs * rs) {
          if (sl[e] >= 0) hist.freeSlot(sl[e]), sl[e] = -1;
          continue;
        }
        if (sl[e] < 0) sl[e] = hist.newSlot();
        double* sh = &hist.hS[3 * static_cast<std::size_t>(sl[e])];
        // R* and m* with one division, independent of the distance (in parallel with the
        // square root and 1/r on the critical path)
        const double mj = Ms[u], msum = mi + mj;
        const double q0 = 1.0 / (rs * msum);
        const double Reff = ri * rj * (msum * q0);
        const double meff = mi * mj * (rs * q0);
        const double r = std::sqrt(r2);
        const double inv = 1.0 / r;
        const double nrm[3] = {dx[0] * inv, dx[1] * inv, dx[2] * inv};
        const double delta = rs - r;
        const double vr[3] = {vi[0] - V[0][u], vi[1] - V[1][u], vi[2] - V[2][u]};
        const double ws[3] = {ri * wi[0] + rj * W[0][u], ri * wi[1] + rj * W[1][u],
                              ri * wi[2] + rj * W[2][u]};
        const double wr[3] = {wi[0] - W[0][u], wi[1] - W[1][u], wi[2] - W[2][u]};
        double Fp[3], c[3], rl[3];
        detail::pairForce<M, Rolling>(rowC[mat[u]], dt, update, nrm, delta, Reff, meff, vr, ws, wr,
                                      sh, Fp, c, rl);
        if (ownI) {
          for (int k = 0; k < 3; ++k) {
            F[k] += Fp[k];
            T[k] -= ri * c[k];
            if constexpr (Rolling) T[k] -= rl[k];
          }
          ++nc;
        }
        if (u < n) {
          for (int k = 0; k < 3; ++k) {
            FX[k][u] -= Fp[k];
            TX[k][u] -= rj * c[k];
            if constexpr (Rolling) TX[k][u] += rl[k];
          }
          ++nc;
        }
        const double rmin = std::min(ri, rj);
        if (delta > worst * rmin) {  // largest overlap / smaller radius, divided only when larger
          worst = delta / rmin;
          worstId = p.id[ownI ? i : u];
          worstPartner = p.id[ownI ? u : i];
        }
      } else {
        const int w = -1 - j, d = w / 2, s = w % 2;
        const double dist = s == 0 ? xi[d] - bins.origin[d] : bins.origin[d] + bins.L[d] - xi[d];
        const double delta = ri - dist;
        if (delta <= 0) {
          if (sl[e] >= 0) hist.freeSlot(sl[e]), sl[e] = -1;
          continue;
        }
        if (sl[e] < 0) sl[e] = hist.newSlot();
        double* sh = &hist.hS[3 * static_cast<std::size_t>(sl[e])];
        double nrm[3] = {0, 0, 0};
        nrm[d] = s == 0 ? 1.0 : -1.0;
        const double ws[3] = {ri * wi[0], ri * wi[1], ri * wi[2]};
        detail::contactForce<M>(wallC[static_cast<std::size_t>(mat[i])], dt, update, nrm, delta, ri,
                                mi, ri, vi, ws, wi, sh, F, T);
        ++nw;
        const double ov = delta / ri;
        if (ov > worst) worst = ov, worstId = p.id[i], worstPartner = -1;
      }
    }
    if (ownI)
      for (int k = 0; k < 3; ++k) {
        FX[k][i] = F[k];
        TX[k][i] = T[k];
      }
  }
  tally = {nc, nw, worst, worstId, worstPartner};
}

double DemSolver::contactEnergy() const {
  const auto& m = *impl_;
  const auto& p = m.p;
  const std::size_t n = p.nOwned;
  double e = 0;
  for (std::size_t q = 0; q < p.size(); ++q) {
    const auto i = static_cast<std::size_t>(m.bins.binItems[q]);
    for (int k = m.list.rowStart[q]; k < m.list.rowStart[q + 1]; ++k) {
      const int j = m.list.nbr[static_cast<std::size_t>(k)];
      if (j >= 0) {
        const auto u = static_cast<std::size_t>(j);
        double r2 = 0;
        for (int d = 0; d < 3; ++d) r2 += (p.x[d][i] - p.x[d][u]) * (p.x[d][i] - p.x[d][u]);
        const double rs = p.radius[i] + p.radius[u];
        if (r2 >= rs * rs) continue;
        // half of the pair's energy to each owned particle of the pair
        const double share = 0.5 * ((i < n ? 1 : 0) + (u < n ? 1 : 0));
        const auto& c = m.pairC[static_cast<std::size_t>(p.material[i] * m.nMat + p.material[u])];
        e += share *
             detail::normalEnergy(m.model, c, rs - std::sqrt(r2), p.radius[i] * p.radius[u] / rs);
      } else {
        const int w = -1 - j, d = w / 2, s = w % 2;
        const double dist =
            s == 0 ? p.x[d][i] - m.bins.origin[d] : m.bins.origin[d] + m.bins.L[d] - p.x[d][i];
        const double delta = p.radius[i] - dist;
        if (delta > 0)
          e += detail::normalEnergy(m.model, m.wallC[static_cast<std::size_t>(p.material[i])],
                                    delta, p.radius[i]);
      }
    }
  }
  return m.comm.sum(e);
}

}  // namespace coloc::dem
