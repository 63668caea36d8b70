// dem/src/forces.cpp — contact and wall forces over the half list (the same terms in the same order
// at any rank count), and the elastic contact energy. The part (ContactForces) is declared in
// contact_forces.hpp.
#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>
#include <span>
#include <string>

#include "contact_forces.hpp"
#include "impl.hpp"
#include "pairs.hpp"

namespace coloc::dem {

using namespace detail;

// ---------------------------------------------------------------------------------------------
// the tally

namespace {

/// A wall contact of owned particle `id` with overlap delta (radius ri).
inline void tallyWall(ContactTally& t, double delta, double ri, std::int64_t id) {
  ++t.walls;
  const double ov = delta / ri;
  if (ov > t.maxOverlap) t.maxOverlap = ov, t.maxOverlapId = id, t.maxOverlapPartner = -1;
}

/// A contact of particles i and u (radii ri, rj; the first n owned; ids `id`) with overlap delta:
/// a contact of each owned one; the largest overlap / smaller radius, divided only when larger.
inline void tallyPair(ContactTally& t, double delta, double ri, double rj, std::size_t i,
                      std::size_t u, std::size_t n, const std::int64_t* id) {
  t.contacts += (i < n ? 1 : 0) + (u < n ? 1 : 0);
  const double rmin = std::min(ri, rj);
  if (delta > t.maxOverlap * rmin) {
    t.maxOverlap = delta / rmin;
    const bool ownI = i < n;
    t.maxOverlapId = id[ownI ? i : u];
    t.maxOverlapPartner = id[ownI ? u : i];
  }
}

// ---------------------------------------------------------------------------------------------
// one force pass

// Each pair is computed once (Newton's third law inside the rank; an owned-ghost pair is
// computed by each rank for its own particle, "newton off" across ranks, so nothing goes back to
// a ghost's owner). Holders are visited in K order (see buildLists), so a particle receives the
// terms of its lower-K partners (pushed by their rows, in increasing K), then those of its own
// row (increasing K), then its walls: the same sum in the same order at any rank count, and the
// pair term itself is computed from the same operands (lower K first) everywhere. The touching
// entries go through a PairChunk (pairs.hpp) in three passes: gathered in list order (gather),
// their contact law computed on the vector units (pairChunk), the results added in list order
// (scatter: pairContact, wallContact), the order above.
template <Model M, bool Rolling>
class ForcePass {
 public:
  ForcePass(const ForceInputs& fi, const ContactLaw& law, const Body* B, PairChunk& ch, bool update)
      : n_(fi.p.nOwned),
        nAll_(fi.p.size()),
        FX_{fi.p.f[0].data(), fi.p.f[1].data(), fi.p.f[2].data()},
        TX_{fi.p.torque[0].data(), fi.p.torque[1].data(), fi.p.torque[2].data()},
        B_(B),
        mat_(fi.p.material.data()),
        id_(fi.p.id.data()),
        nbrs_(fi.search.list().nbr.data()),
        sl_(fi.search.listSlots()),
        rowStart_(fi.search.list().rowStart.data()),
        items_(fi.search.bins().binItems.data()),
        bins_(fi.search.bins()),
        hist_(fi.search.mutableHistory()),
        wallC_(law.wall.data()),
        nMat_(law.nMat),
        single_(law.nMat == 1),
        dt_(fi.dt),
        update_(update),
        in_{B,
            {fi.p.omega[0].data(), fi.p.omega[1].data(), fi.p.omega[2].data()},
            fi.search.mutableHistory().hS.data(),
            law.pair.data(),
            fi.dt},
        ch_(ch) {}

  /// Every list entry, then the last chunk; the tally of what was seen.
  ContactTally run() {
    gather();
    flush();
    return t_;
  }

 private:
  /// Pass 1: every entry in list order; a touching one is appended (the store is unconditional,
  /// the count advances by the test), a contact that starts or ends takes or frees its slot; a
  /// full chunk is flushed.
  void gather() {
    ch_.m = 0;
    constexpr int kAhead = 24;
    const int eLast = std::max(rowStart_[nAll_] - 1, 0);
    for (std::size_t q = 0; q < nAll_; ++q) {
      const int e0 = rowStart_[q], e1 = rowStart_[q + 1];
      if (e0 == e1) continue;
      const auto i = static_cast<std::size_t>(items_[q]);
      const Body& bi = B_[i];
      const double ri = bi.r;
      const double xi[3] = {bi.x[0], bi.x[1], bi.x[2]};
      const int coefRow = single_ ? 0 : mat_[i] * nMat_;
      for (int e = e0; e < e1; ++e) {
        const int j = nbrs_[e];
        const int k = ch_.m;
        // the partner of the entry kAhead on, whose line the distance test will read
        __builtin_prefetch(B_ + std::max(nbrs_[std::min(e + kAhead, eLast)], 0));
        const bool touch = j >= 0 ? gatherPair(k, xi, ri, coefRow, j) : gatherWall(k, i, xi, ri, j);
        if (touch != (sl_[e] >= 0)) {  // a contact starts or ends (rare)
          if (touch) {
            sl_[e] = hist_.newSlot();
            in_.hS = hist_.hS.data();  // the pool may have grown
          } else {
            hist_.freeSlot(sl_[e]);
            sl_[e] = -1;
          }
        }
        ch_.i[k] = static_cast<int>(i);
        ch_.slot[k] = sl_[e];
        __builtin_prefetch(in_.hS + 3 * std::max(sl_[e], 0), 1);  // the history, read and written
        ch_.m = k + (touch ? 1 : 0);
        if (ch_.m == kChunk) flush();
      }
    }
  }

  /// Pass 1 of a particle entry (partner j) at chunk position k: whether it touches.
  bool gatherPair(int k, const double (&xi)[3], double ri, int coefRow, int j) {
    const auto u = static_cast<std::size_t>(j);
    const Body& bu = B_[u];
    const double dx[3] = {xi[0] - bu.x[0], xi[1] - bu.x[1], xi[2] - bu.x[2]};
    const double r2 = dx[0] * dx[0] + dx[1] * dx[1] + dx[2] * dx[2];
    const double rs = ri + bu.r;
    const bool touch = !(r2 >= rs * rs);
    // the partner's lines that passes 2 and 3 read and write, fetched a chunk ahead
    for (int c = 0; c < 3; ++c) {
      __builtin_prefetch(in_.w[c] + u);
      __builtin_prefetch(FX_[c] + u, 1);
      __builtin_prefetch(TX_[c] + u, 1);
    }
    ch_.u[k] = j;
    ch_.coef[k] = single_ ? 0 : coefRow + mat_[u];
    ch_.wall[k] = -1;
    for (int c = 0; c < 3; ++c) ch_.dx[c][k] = dx[c];
    ch_.r2[k] = r2;
    return touch;
  }

  /// Pass 1 of a wall entry (code j < 0) at chunk position k: whether it touches.
  bool gatherWall(int k, std::size_t i, const double (&xi)[3], double ri, int j) {
    const int w = -1 - j, d = w / 2, s = w % 2;
    const double dist = s == 0 ? xi[d] - bins_.origin[d] : bins_.origin[d] + bins_.L[d] - xi[d];
    const bool touch = !(ri - dist <= 0);
    ch_.u[k] = static_cast<int>(i);  // stand-in values for pass 2 (see pairChunk)
    ch_.coef[k] = 0;
    ch_.wall[k] = w;
    ch_.dx[0][k] = 1;
    ch_.dx[1][k] = ch_.dx[2][k] = 0;
    ch_.r2[k] = 1;
    return touch;
  }

  /// Passes 2 and 3 over the chunk gathered so far.
  void flush() {
    if (single_)
      pairChunk<M, Rolling, true>(in_, update_, ch_);
    else
      pairChunk<M, Rolling, false>(in_, update_, ch_);
    for (int k = 0; k < ch_.m; ++k) {
      if (ch_.wall[k] >= 0)
        wallContact(k);
      else
        pairContact(k);
    }
    ch_.m = 0;
  }

  /// Pass 3 of a pair entry: the shear written back, the pair's results added to its owned
  /// particles.
  void pairContact(int k) {
    const auto i = static_cast<std::size_t>(ch_.i[k]);
    const auto u = static_cast<std::size_t>(ch_.u[k]);
    const double ri = B_[i].r, rj = B_[u].r;
    double* sh = &hist_.hS[3 * static_cast<std::size_t>(ch_.slot[k])];
    for (int c = 0; c < 3; ++c) sh[c] = ch_.shear[c][k];
    if (i < n_) {
      for (int c = 0; c < 3; ++c) {
        FX_[c][i] += ch_.fp[c][k];
        TX_[c][i] -= ri * ch_.nxft[c][k];
        if constexpr (Rolling) TX_[c][i] -= ch_.roll[c][k];
      }
    }
    if (u < n_) {
      for (int c = 0; c < 3; ++c) {
        FX_[c][u] -= ch_.fp[c][k];
        TX_[c][u] -= rj * ch_.nxft[c][k];
        if constexpr (Rolling) TX_[c][u] += ch_.roll[c][k];
      }
    }
    tallyPair(t_, ch_.delta[k], ri, rj, i, u, n_, id_);
  }

  /// Pass 3 of a wall entry: the wall contact law of its (owned) particle, computed here.
  void wallContact(int k) {
    const auto i = static_cast<std::size_t>(ch_.i[k]);
    const Body& bi = B_[i];
    const double ri = bi.r;
    double* sh = &hist_.hS[3 * static_cast<std::size_t>(ch_.slot[k])];
    const int w = ch_.wall[k], d = w / 2, s = w % 2;
    const double xi = bi.x[d];
    const double dist = s == 0 ? xi - bins_.origin[d] : bins_.origin[d] + bins_.L[d] - xi;
    const double delta = ri - dist;
    double nrm[3] = {0, 0, 0};
    nrm[d] = s == 0 ? 1.0 : -1.0;
    const double wi[3] = {in_.w[0][i], in_.w[1][i], in_.w[2][i]};
    const double ws[3] = {ri * wi[0], ri * wi[1], ri * wi[2]};
    double F[3] = {FX_[0][i], FX_[1][i], FX_[2][i]}, T[3] = {TX_[0][i], TX_[1][i], TX_[2][i]};
    detail::contactForce<M>(wallC_[static_cast<std::size_t>(mat_[i])], dt_, update_, nrm, delta, ri,
                            bi.m, ri, bi.v, ws, wi, sh, F, T);
    for (int c = 0; c < 3; ++c) FX_[c][i] = F[c], TX_[c][i] = T[c];
    tallyWall(t_, delta, ri, id_[i]);
  }

  const std::size_t n_, nAll_;
  double* const FX_[3];
  double* const TX_[3];
  const Body* const B_;
  const int* const mat_;
  const std::int64_t* const id_;
  const int* const nbrs_;
  int* const sl_;
  const int* const rowStart_;
  const int* const items_;
  const Bins& bins_;
  HistoryPool& hist_;
  const PairCoeff* const wallC_;
  const int nMat_;
  const bool single_;
  const double dt_;
  const bool update_;
  PairInputs in_;
  PairChunk& ch_;
  ContactTally t_;
};

}  // namespace

// ---------------------------------------------------------------------------------------------
// ContactForces

void ContactForces::compute(const ForceInputs& in, bool update, bool stepped) {
  if (law.model == Model::HertzMindlin)
    law.rolling ? run<Model::HertzMindlin, true>(in, update, stepped)
                : run<Model::HertzMindlin, false>(in, update, stepped);
  else
    law.rolling ? run<Model::Linear, true>(in, update, stepped)
                : run<Model::Linear, false>(in, update, stepped);
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

void ContactForces::packBodies(const ParticleStore& p, std::size_t from) {
  const double *X0 = p.x[0].data(), *X1 = p.x[1].data(), *X2 = p.x[2].data();
  const double *V0 = p.v[0].data(), *V1 = p.v[1].data(), *V2 = p.v[2].data();
  const double *R = p.radius.data(), *Ms = p.mass.data();
  Body* Bw = body_.data();
  for (std::size_t i = from; i < p.size(); ++i)
    Bw[i] = Body{{X0[i], X1[i], X2[i]}, R[i], {V0[i], V1[i], V2[i]}, Ms[i]};
}

template <Model M, bool Rolling>
void ContactForces::run(const ForceInputs& in, bool update, bool stepped) {
  // inside a step without a rebuild, the integration has reset the sums and packed the owned
  // bodies; else both here. The ghosts' bodies are packed here.
  const bool ownedCurrent = stepped && packed_;
  if (!ownedCurrent) resetSums(in);
  packBodies(in.p, ownedCurrent ? in.p.nOwned : 0);
  packed_ = true;
  tally_ = ForcePass<M, Rolling>(in, law, body_.data(), chunk_, update).run();
}

void DemSolver::Impl::computeForces(bool update, bool stepped) {
  forces.compute({p, search, integrator.dt, integrator.g}, update, stepped);
  if (heat.on) heat.conduct(p, search);  // a pass of its own: the force pass is unchanged
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
