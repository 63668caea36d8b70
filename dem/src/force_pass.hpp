// dem/src/force_pass.hpp — one force pass over the half list (ContactForces::compute,
// contact_forces.hpp), compiled once per instruction set: forces.cpp for the build's target,
// forces_avx512.cpp with AVX-512 (F, VL); ContactForces calls the widest one the CPU runs
// (particles.force_isa). The two differ only in how pass 1 reads a row (the Rows policy: entry by
// entry here, eight entries at a time in force_rows_avx512.hpp); every other line is this file's,
// and both give the same bits. Everything here has internal linkage (one copy per instruction
// set: no inline function of one can stand in for the other's at link time).
//
// Each pair is computed once (Newton's third law inside the rank; an owned-ghost pair is
// computed by each rank for its own particle, "newton off" across ranks, so nothing goes back to
// a ghost's owner). Holders are visited in K order (see buildLists), so a particle receives the
// terms of its lower-K partners (pushed by their rows, in increasing K), then those of its own
// row (increasing K), then its walls: the same sum in the same order at any rank count, and the
// pair term itself is computed from the same operands (lower K first) everywhere. The touching
// entries go through a PairChunk (pairs.hpp) in three passes: gathered in list order (pass 1,
// the Rows policy), their contact law computed on the vector units (pairChunk), the results added
// in list order (pass 3: pairContact, wallContact), the order above.
//
// The inner list (neighbour_search.hpp: the list's keep masks). A pass over the whole (outer)
// list also marks, row by row, the entries whose gap is below the prune margin (and every entry
// that touches); while no particle can have closed the margin since (the owner's displacement
// bound), the passes visit only the marked entries: the others cannot touch, hold no history
// slot and would add nothing, so the chunk, the slots taken and freed and every sum are the same
// as the outer pass's, in the same order.
//
// Heat conduction (particles.heat with contact conduction) rides pass 3 when `Heat`: the
// conduction of a touching pair (or wall) is added to Q in list order from the same operands as
// HeatTransfer::conduct (heat.cpp), which the frozen sub-step still uses: the same bits.
#pragma once

#include <algorithm>
#include <bit>
#include <cmath>
#include <cstdint>

#include "contact_forces.hpp"
#include "heat.hpp"
#include "pairs.hpp"

namespace coloc::dem::detail {

/// One force pass: the forces (and heat) into the particles of `in`, the tally returned.
struct ForcePassArgs {
  const ForceInputs& in;
  const ContactLaw& law;
  const Body* body;
  PairChunk& chunk;
  bool update;
  HeatPass* heat;  // nullptr: no conduction in this pass
};
ContactTally forcePassBuild(const ForcePassArgs& a);
ContactTally forcePassAvx512(const ForcePassArgs& a);

namespace {  // NOLINT(google-build-namespaces,cert-dcl59-cpp): one copy per instruction set

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

/// The holder of a row as pass 1 reads it.
struct Row {
  std::size_t i;     // the holder (local index)
  double xi[3], ri;  // its position and radius
  int coefRow;       // material_i * nMat (0 with one material)
  int e0, e1;        // its entries
  unsigned keep;     // the inner list's mask of the row (neighbours.hpp: KeepMask)
};

template <Model M, bool Rolling, bool Heat, class Rows>
class ForcePass {
 public:
  explicit ForcePass(const ForcePassArgs& a)
      : n_(a.in.p.nOwned),
        nAll_(a.in.p.size()),
        FX_{a.in.p.f[0].data(), a.in.p.f[1].data(), a.in.p.f[2].data()},
        TX_{a.in.p.torque[0].data(), a.in.p.torque[1].data(), a.in.p.torque[2].data()},
        B_(a.body),
        mat_(a.in.p.material.data()),
        id_(a.in.p.id.data()),
        nbrs_(a.in.search.list().nbr.data()),
        sl_(a.in.search.listSlots()),
        keep_(a.in.search.listKeep()),
        rowStart_(a.in.search.list().rowStart.data()),
        items_(a.in.search.bins().binItems.data()),
        bins_(a.in.search.bins()),
        hist_(a.in.search.mutableHistory()),
        wallC_(a.law.wall.data()),
        nMat_(a.law.nMat),
        single_(a.law.nMat == 1),
        dt_(a.in.dt),
        update_(a.update),
        inner_(a.in.search.innerListValid()),
        prune_(!inner_ && a.in.search.pruneMargin() > 0),
        margin_(a.in.search.pruneMargin()),
        heat_(a.heat),
        in_{a.body,
            {a.in.p.omega[0].data(), a.in.p.omega[1].data(), a.in.p.omega[2].data()},
            a.in.search.mutableHistory().hS.data(),
            a.law.pair.data(),
            a.in.dt},
        ch_(a.chunk) {}

  /// Every list entry (the inner list's while it is valid), then the last chunk; the tally of
  /// what was seen. A pass over the outer list with a margin prunes it (the owner is told by
  /// pruned()).
  ContactTally run() {
    ch_.m = 0;
    for (std::size_t q = 0; q < nAll_; ++q) {
      if constexpr (Rows::kRowsAhead > 0) prefetchRow(q + Rows::kRowsAhead);
      const int e0 = rowStart_[q], e1 = rowStart_[q + 1];
      if (e0 == e1 || (inner_ && keep_[q] == 0 && e1 - e0 <= kKeepBits)) continue;
      const auto i = static_cast<std::size_t>(items_[q]);
      const Body& bi = B_[i];
      const Row row{i,  {bi.x[0], bi.x[1], bi.x[2]}, bi.r, single_ ? 0 : mat_[i] * nMat_, e0,
                    e1, inner_ ? keep_[q] : ~0u};
      const unsigned kept = Rows::row(*this, row);
      if (prune_) keep_[q] = static_cast<KeepMask>(kept);
    }
    flush();
    return t_;
  }
  bool pruned() const { return prune_; }

  // ---- used by the Rows policies (pass 1) ----

  /// Pass 1 of a particle entry (partner j) at chunk position k: whether it touches; `kept`
  /// (Prune): whether its gap is below the prune margin (or it touches).
  template <bool Prune>
  bool gatherPair(int k, const Row& r, int j, bool& kept) {
    const auto u = static_cast<std::size_t>(j);
    const Body& bu = B_[u];
    const double dx[3] = {r.xi[0] - bu.x[0], r.xi[1] - bu.x[1], r.xi[2] - bu.x[2]};
    const double r2 = dx[0] * dx[0] + dx[1] * dx[1] + dx[2] * dx[2];
    const double rs = r.ri + bu.r;
    const bool touch = !(r2 >= rs * rs);
    if constexpr (Prune) {
      const double rm = rs + margin_;
      kept = !(r2 >= rm * rm);
    }
    // the partner's lines that passes 2 and 3 read and write, fetched a chunk ahead
    prefetchPartner(u);
    ch_.u[k] = j;
    ch_.coef[k] = single_ ? 0 : r.coefRow + mat_[u];
    ch_.wall[k] = -1;
    for (int c = 0; c < 3; ++c) ch_.dx[c][k] = dx[c];
    ch_.r2[k] = r2;
    return touch;
  }

  /// Pass 1 of a wall entry (code j < 0) at chunk position k: whether it touches; `kept`
  /// (Prune) as above.
  template <bool Prune>
  bool gatherWall(int k, const Row& r, int j, bool& kept) {
    const int w = -1 - j, d = w / 2, s = w % 2;
    const double dist = s == 0 ? r.xi[d] - bins_.origin[d] : bins_.origin[d] + bins_.L[d] - r.xi[d];
    const bool touch = !(r.ri - dist <= 0);
    if constexpr (Prune) kept = !(r.ri - dist <= -margin_);
    ch_.u[k] = static_cast<int>(r.i);  // stand-in values for pass 2 (see pairChunk)
    ch_.coef[k] = 0;
    ch_.wall[k] = w;
    ch_.dx[0][k] = 1;
    ch_.dx[1][k] = ch_.dx[2][k] = 0;
    ch_.r2[k] = 1;
    return touch;
  }

  /// A contact starts (take a slot) or ends (free it) at entry e (rare).
  void fixSlot(int e, bool touch) {
    if (touch) {
      sl_[e] = hist_.newSlot();
      in_.hS = hist_.hS.data();  // the pool may have grown
    } else {
      hist_.freeSlot(sl_[e]);
      sl_[e] = -1;
    }
  }

  /// The packed lines of the partners of row q (the inner list's while it is valid), which the
  /// distance tests will read.
  void prefetchRow(std::size_t q) const {
    if (q >= nAll_) return;
    const int e0 = rowStart_[q], e1 = rowStart_[q + 1];
    const int eMask = std::min(e1, e0 + kKeepBits);
    const auto one = [&](int e) { __builtin_prefetch(B_ + std::max(nbrs_[e], 0)); };
    if (inner_)
      for (unsigned b = keep_[q]; b != 0; b &= b - 1) one(e0 + std::countr_zero(b));
    else
      for (int e = e0; e < eMask; ++e) one(e);
    for (int e = eMask; e < e1; ++e) one(e);
  }

  /// The lines of partner u that passes 2 and 3 read and write.
  void prefetchPartner(std::size_t u) const {
    for (int c = 0; c < 3; ++c) {
      __builtin_prefetch(in_.w[c] + u);
      __builtin_prefetch(FX_[c] + u, 1);
      __builtin_prefetch(TX_[c] + u, 1);
    }
  }

  /// Passes 2 and 3 over the chunk gathered so far.
  void flush() {
    if (single_)
      pairChunk<M, Rolling, true, Rows::kHolderInChunk>(in_, update_, ch_);
    else
      pairChunk<M, Rolling, false, Rows::kHolderInChunk>(in_, update_, ch_);
    for (int k = 0; k < ch_.m; ++k) {
      if (ch_.wall[k] >= 0)
        wallContact(k);
      else
        pairContact(k);
    }
    ch_.m = 0;
  }

  const std::size_t n_, nAll_;
  double* const FX_[3];
  double* const TX_[3];
  const Body* const B_;
  const int* const mat_;
  const std::int64_t* const id_;
  const int* const nbrs_;
  int* const sl_;
  KeepMask* const keep_;
  const int* const rowStart_;
  const int* const items_;
  const Bins& bins_;
  HistoryPool& hist_;
  const PairCoeff* const wallC_;
  const int nMat_;
  const bool single_;
  const double dt_;
  const bool update_;
  const bool inner_, prune_;
  const double margin_;
  HeatPass* const heat_;
  PairInputs in_;
  PairChunk& ch_;
  ContactTally t_;

 private:
  /// Pass 3 of a pair entry: the shear written back, the pair's results (and conduction) added
  /// to its owned particles.
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
    if constexpr (Heat) {  // HeatTransfer::conduct's arithmetic (Hertz contact radius a)
      const HeatPass& h = *heat_;
      const double rs = ri + rj;
      const double a = std::sqrt(ri * rj / rs * ch_.delta[k]);
      const double H = 2.0 * h.kPair[static_cast<std::size_t>(mat_[i] * h.nMat + mat_[u])] * a;
      const double heat = H * (h.T[u] - h.T[i]);  // into i, out of u
      if (i < n_) h.Q[i] += heat;
      if (u < n_) h.Q[u] -= heat;
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
    if constexpr (Heat) {
      HeatPass& h = *heat_;
      if (h.walls && delta > 0) {
        const double a = std::sqrt(ri * delta);
        const double heat =
            2.0 * h.kWall[static_cast<std::size_t>(mat_[i])] * a * (h.wallT - h.T[i]);
        h.Q[i] += heat;  // a wall entry's particle is owned
        h.wallRate += heat;
      }
    }
    tallyWall(t_, delta, ri, id_[i]);
  }
};

/// Pass 1 entry by entry (any instruction set): a touching entry is appended (the store is
/// unconditional, the count advances by the test), a contact that starts or ends takes or frees
/// its slot; a full chunk is flushed. Returns the row's keep mask (used by pruning passes).
struct ScalarRows {
  static constexpr std::size_t kRowsAhead = 0;   // (entry by entry, kAhead below)
  static constexpr bool kHolderInChunk = false;  // pass 2 gathers the holder's values
  template <class FP>
  static unsigned row(FP& f, const Row& r) {
    constexpr int kAhead = 24;
    const int eLast = std::max(f.rowStart_[f.nAll_] - 1, 0);
    unsigned kept = 0;
    // (always inlined: called from several loops, GCC otherwise makes it a function call an entry)
    const auto entry = [&]<bool Prune>(int e) __attribute__((always_inline)) {
      const int j = f.nbrs_[e];
      const int k = f.ch_.m;
      // the partner of the entry kAhead on, whose line the distance test will read
      __builtin_prefetch(f.B_ + std::max(f.nbrs_[std::min(e + kAhead, eLast)], 0));
      bool kb = false;
      const bool touch = j >= 0 ? f.template gatherPair<Prune>(k, r, j, kb)
                                : f.template gatherWall<Prune>(k, r, j, kb);
      if (touch != (f.sl_[e] >= 0)) f.fixSlot(e, touch);
      f.ch_.i[k] = static_cast<int>(r.i);
      f.ch_.slot[k] = f.sl_[e];
      __builtin_prefetch(f.in_.hS + 3 * std::max(f.sl_[e], 0), 1);  // read and written
      f.ch_.m = k + (touch ? 1 : 0);
      if (f.ch_.m == kChunk) f.flush();
      return kb;
    };
    if (f.inner_) {
      const int eMask = std::min(r.e1, r.e0 + kKeepBits);
      for (unsigned b = r.keep; b != 0; b &= b - 1)
        entry.template operator()<false>(r.e0 + std::countr_zero(b));
      for (int e = eMask; e < r.e1; ++e) entry.template operator()<false>(e);
    } else if (f.prune_) {
      for (int e = r.e0; e < r.e1; ++e)
        if (const bool kb = entry.template operator()<true>(e); e - r.e0 < kKeepBits)
          kept |= static_cast<unsigned>(kb) << (e - r.e0);
    } else {
      for (int e = r.e0; e < r.e1; ++e) entry.template operator()<false>(e);
    }
    return kept;
  }
};

/// The pass for the law and options of `a`, pass 1 by `Rows`.
template <class Rows>
ContactTally forcePass(const ForcePassArgs& a) {
  const auto go = [&]<Model M, bool Rolling>() {
    if (a.heat) {
      ForcePass<M, Rolling, true, Rows> f(a);
      const ContactTally t = f.run();
      if (f.pruned()) a.in.search.pruned();
      return t;
    }
    ForcePass<M, Rolling, false, Rows> f(a);
    const ContactTally t = f.run();
    if (f.pruned()) a.in.search.pruned();
    return t;
  };
  if (a.law.model == Model::HertzMindlin)
    return a.law.rolling ? go.template operator()<Model::HertzMindlin, true>()
                         : go.template operator()<Model::HertzMindlin, false>();
  return a.law.rolling ? go.template operator()<Model::Linear, true>()
                       : go.template operator()<Model::Linear, false>();
}

}  // namespace
}  // namespace coloc::dem::detail
