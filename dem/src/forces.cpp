// dem/src/forces.cpp — contact and wall forces over the half list (the same terms in the same order
// at any rank count), and the elastic contact energy.
#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>
#include <new>
#include <span>
#include <string>

#include "impl.hpp"
#include "pairs.hpp"

namespace coloc::dem {

using namespace detail;

// ---------------------------------------------------------------------------------------------
// forces

void DemSolver::Impl::computeForces(bool update, bool stepped) {
  if (model == Model::HertzMindlin)
    rolling ? forces<Model::HertzMindlin, true>(update, stepped)
            : forces<Model::HertzMindlin, false>(update, stepped);
  else
    rolling ? forces<Model::Linear, true>(update, stepped)
            : forces<Model::Linear, false>(update, stepped);
}

// Each pair is computed once (Newton's third law inside the rank; an owned-ghost pair is
// computed by each rank for its own particle, "newton off" across ranks, so nothing goes back to
// a ghost's owner). Holders are visited in K order (see buildLists), so a particle receives the
// terms of its lower-K partners (pushed by their rows, in increasing K), then those of its own
// row (increasing K), then its walls: the same sum in the same order at any rank count, and the
// pair term itself is computed from the same operands (lower K first) everywhere. The touching
// entries go through a PairChunk (pairs.hpp): gathered in list order, their contact law computed
// on the vector units, the results added in list order (the order above).
template <Model M, bool Rolling>
void DemSolver::Impl::forces(bool update, bool stepped) {
  const std::size_t n = p.nOwned, nAll = p.size();
  double* FX[3] = {p.f[0].data(), p.f[1].data(), p.f[2].data()};
  double* TX[3] = {p.torque[0].data(), p.torque[1].data(), p.torque[2].data()};
  // inside a step without a rebuild, initialIntegrate has reset the sums and packed the owned
  // bodies; else both here. The ghosts' bodies are packed here.
  const bool ownedCurrent = stepped && packed;
  if (!ownedCurrent) {
    for (int k = 0; k < 3; ++k) {
      const double* fe = p.fExt[k].data();
      const double* ms = p.mass.data();
      double* fk = FX[k];
      double* tk = TX[k];
      const double gk = g[k];
#pragma omp simd
      for (std::size_t i = 0; i < n; ++i) {
        fk[i] = ms[i] * gk + fe[i];
        tk[i] = 0;
      }
    }
    ensure(body, nAll);
    body.resize(nAll);
  }
  {
    const double *X0 = p.x[0].data(), *X1 = p.x[1].data(), *X2 = p.x[2].data();
    const double *V0 = p.v[0].data(), *V1 = p.v[1].data(), *V2 = p.v[2].data();
    const double *R = p.radius.data(), *Ms = p.mass.data();
    Body* Bw = body.data();
    for (std::size_t i = ownedCurrent ? n : 0; i < nAll; ++i)
      ::new (static_cast<void*>(Bw + i))
          Body{{X0[i], X1[i], X2[i]}, R[i], {V0[i], V1[i], V2[i]}, Ms[i]};
  }
  packed = true;
  const Body* B = body.data();
  const int* mat = p.material.data();
  const int* nbrs = search.list.nbr.data();
  int* sl = search.list.slot.data();
  const bool single = nMat == 1;
  PairInputs in{B,
                {p.omega[0].data(), p.omega[1].data(), p.omega[2].data()},
                search.hist.hS.data(),
                pairC.data(),
                dt};
  PairChunk& ch = chunk;
  long long nc = 0, nw = 0;
  double worst = 0;
  std::int64_t worstId = -1, worstPartner = 0;
  // passes 2 and 3 over the chunk gathered so far
  const auto flush = [&] {
    if (single)
      pairChunk<M, Rolling, true>(in, update, ch);
    else
      pairChunk<M, Rolling, false>(in, update, ch);
    for (int k = 0; k < ch.m; ++k) {
      const auto i = static_cast<std::size_t>(ch.i[k]);
      const Body& bi = B[i];
      const double ri = bi.r;
      double* sh = &search.hist.hS[3 * static_cast<std::size_t>(ch.slot[k])];
      if (ch.wall[k] >= 0) {
        const int w = ch.wall[k], d = w / 2, s = w % 2;
        const double xi = bi.x[d];
        const double dist =
            s == 0 ? xi - search.bins.origin[d] : search.bins.origin[d] + search.bins.L[d] - xi;
        const double delta = ri - dist;
        double nrm[3] = {0, 0, 0};
        nrm[d] = s == 0 ? 1.0 : -1.0;
        const double wi[3] = {in.w[0][i], in.w[1][i], in.w[2][i]};
        const double ws[3] = {ri * wi[0], ri * wi[1], ri * wi[2]};
        double F[3] = {FX[0][i], FX[1][i], FX[2][i]}, T[3] = {TX[0][i], TX[1][i], TX[2][i]};
        detail::contactForce<M>(wallC[static_cast<std::size_t>(mat[i])], dt, update, nrm, delta, ri,
                                bi.m, ri, bi.v, ws, wi, sh, F, T);
        for (int c = 0; c < 3; ++c) FX[c][i] = F[c], TX[c][i] = T[c];
        ++nw;
        const double ov = delta / ri;
        if (ov > worst) worst = ov, worstId = p.id[i], worstPartner = -1;
        continue;
      }
      const auto u = static_cast<std::size_t>(ch.u[k]);
      const double rj = B[u].r;
      for (int c = 0; c < 3; ++c) sh[c] = ch.shear[c][k];
      if (i < n) {
        for (int c = 0; c < 3; ++c) {
          FX[c][i] += ch.fp[c][k];
          TX[c][i] -= ri * ch.nxft[c][k];
          if constexpr (Rolling) TX[c][i] -= ch.roll[c][k];
        }
        ++nc;
      }
      if (u < n) {
        for (int c = 0; c < 3; ++c) {
          FX[c][u] -= ch.fp[c][k];
          TX[c][u] -= rj * ch.nxft[c][k];
          if constexpr (Rolling) TX[c][u] += ch.roll[c][k];
        }
        ++nc;
      }
      const double delta = ch.delta[k], rmin = std::min(ri, rj);
      if (delta > worst * rmin) {  // largest overlap / smaller radius, divided only when larger
        worst = delta / rmin;
        const bool ownI = i < n;
        worstId = p.id[ownI ? i : u];
        worstPartner = p.id[ownI ? u : i];
      }
    }
    ch.m = 0;
  };
  // pass 1: every entry in list order; a touching one is appended (the store is unconditional,
  // the count advances by the test), a contact that starts or ends takes or frees its slot
  ch.m = 0;
  constexpr int kAhead = 24;
  const int eLast = std::max(search.list.rowStart[nAll] - 1, 0);
  for (std::size_t q = 0; q < nAll; ++q) {
    const int e0 = search.list.rowStart[q], e1 = search.list.rowStart[q + 1];
    if (e0 == e1) continue;
    const auto i = static_cast<std::size_t>(search.bins.binItems[q]);
    const Body& bi = B[i];
    const double ri = bi.r;
    const double xi[3] = {bi.x[0], bi.x[1], bi.x[2]};
    const int coefRow = single ? 0 : mat[i] * nMat;
    for (int e = e0; e < e1; ++e) {
      const int j = nbrs[e];
      const int k = ch.m;
      // the partner of the entry kAhead on, whose line the distance test will read
      __builtin_prefetch(B + std::max(nbrs[std::min(e + kAhead, eLast)], 0));
      bool touch;
      if (j >= 0) {
        const auto u = static_cast<std::size_t>(j);
        const Body& bu = B[u];
        const double dx[3] = {xi[0] - bu.x[0], xi[1] - bu.x[1], xi[2] - bu.x[2]};
        const double r2 = dx[0] * dx[0] + dx[1] * dx[1] + dx[2] * dx[2];
        const double rs = ri + bu.r;
        touch = !(r2 >= rs * rs);
        // the partner's lines that passes 2 and 3 read and write, fetched a chunk ahead
        for (int c = 0; c < 3; ++c) {
          __builtin_prefetch(in.w[c] + u);
          __builtin_prefetch(FX[c] + u, 1);
          __builtin_prefetch(TX[c] + u, 1);
        }
        ch.u[k] = j;
        ch.coef[k] = single ? 0 : coefRow + mat[u];
        ch.wall[k] = -1;
        for (int c = 0; c < 3; ++c) ch.dx[c][k] = dx[c];
        ch.r2[k] = r2;
      } else {
        const int w = -1 - j, d = w / 2, s = w % 2;
        const double dist = s == 0 ? xi[d] - search.bins.origin[d]
                                   : search.bins.origin[d] + search.bins.L[d] - xi[d];
        touch = !(ri - dist <= 0);
        ch.u[k] = static_cast<int>(i);  // stand-in values for pass 2 (see pairChunk)
        ch.coef[k] = 0;
        ch.wall[k] = w;
        ch.dx[0][k] = 1;
        ch.dx[1][k] = ch.dx[2][k] = 0;
        ch.r2[k] = 1;
      }
      if (touch != (sl[e] >= 0)) {  // a contact starts or ends (rare)
        if (touch) {
          sl[e] = search.hist.newSlot();
          in.hS = search.hist.hS.data();  // the pool may have grown
        } else {
          search.hist.freeSlot(sl[e]);
          sl[e] = -1;
        }
      }
      ch.i[k] = static_cast<int>(i);
      ch.slot[k] = sl[e];
      __builtin_prefetch(in.hS + 3 * std::max(sl[e], 0), 1);  // the history, read and written
      ch.m = k + (touch ? 1 : 0);
      if (ch.m == kChunk) flush();
    }
  }
  flush();
  tally = {nc, nw, worst, worstId, worstPartner};
}

double DemSolver::contactEnergy() const {
  const auto& m = *impl_;
  const auto& p = m.p;
  const std::size_t n = p.nOwned;
  double e = 0;
  for (std::size_t q = 0; q < p.size(); ++q) {
    const auto i = static_cast<std::size_t>(m.search.bins.binItems[q]);
    for (int k = m.search.list.rowStart[q]; k < m.search.list.rowStart[q + 1]; ++k) {
      const int j = m.search.list.nbr[static_cast<std::size_t>(k)];
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
        const double dist = s == 0 ? p.x[d][i] - m.search.bins.origin[d]
                                   : m.search.bins.origin[d] + m.search.bins.L[d] - p.x[d][i];
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
