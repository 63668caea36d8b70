// dem/src/flow.cpp — face conditions, outflow removal and inflow insertion; the flow tallies
// (DemFlow).
#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>
#include <span>
#include <string>

#include "impl.hpp"
#include "rng.hpp"

namespace coloc::dem {

using namespace detail;

void DemSolver::Impl::setupFaces(const Config& cfg) {
  face = detail::faceKinds(cfg, dec.grid(), inflow);  // checks.cpp (also `coloc check`)
  for (const auto& side : face)
    for (const Face f : side) anyOutflow = anyOutflow || f == Face::Outflow;
}

// ---------------------------------------------------------------------------------------------
// outflow and inflow

bool DemSolver::Impl::beyondOutflow(std::size_t i, int* which) const {
  for (int d = 0; d < 3; ++d) {
    const double x = p.x[d][i];
    if (face[d][0] == Face::Outflow && x < search.bins().origin[d]) {
      if (which) *which = 2 * d;
      return true;
    }
    if (face[d][1] == Face::Outflow && x > search.bins().origin[d] + search.bins().L[d]) {
      if (which) *which = 2 * d + 1;
      return true;
    }
  }
  return false;
}

void DemSolver::Impl::removeOutflow() {
  // After packHistory (rows per owned particle): particles whose centre is beyond an outflow
  // face leave with their rows; rows of other particles keyed by their ids are taken by no list
  // entry at the next build and become free slots (the histories are dropped).
  const std::size_t n = p.nOwned;
  std::size_t w = 0;
  int hw = 0;
  for (std::size_t i = 0; i < n; ++i) {
    const int h0 = search.history().hStart[i], h1 = search.history().hStart[i + 1];
    int fc = 0;
    if (beyondOutflow(i, &fc)) {
      ++flow.countOut;
      flow.massOut += p.mass[i];
      if (heat.on) heat.leave(p, i, integrator.dt);
      ++flow.countOutByFace[static_cast<std::size_t>(fc)];
      continue;
    }
    keepRow(i, w, h0, h1, hw);
    ++w;
  }
  if (w == n) return;
  p.nOwned = w;
  p.nGhost = 0;
  search.mutableHistory().truncate(w, hw);
}

void DemSolver::Impl::insertInflow() {
  // At the start of a step (owned and ghost positions current): the particles due by now join
  // their source's waiting list (in id order); the first min(waiting, sites) of them are
  // candidates, candidate j on site P(j) of the patch (P a pseudo-random permutation drawn per
  // step, so candidates never overlap each other), at an offset drawn from its id and the step.
  // A candidate is checked by the rank owning its centre against the local particles (owned and
  // ghosts: every particle within a diameter of it is one); one allreduce of the verdicts, and
  // the accepted candidates enter while the others wait for the next step (another site).
  // Everything but the overlap test is computed alike on every rank.
  const double t = static_cast<double>(steps) * integrator.dt;
  const std::size_t nIn = inflow.size();
  std::size_t total = 0;
  for (std::size_t n = 0; n < nIn; ++n) {
    const auto& f = inflow[n];
    const double te = f.end > 0 ? std::min(t, f.end) : t;
    const long long before = flow.due[n];
    if (te > f.start) {
      if (f.rate > 0) {
        // Bounded before the cast (the case checks bound the run's total far below this).
        const double due = std::min(std::floor(f.rate * (te - f.start)), 0x1p53);
        flow.due[n] = std::max(flow.due[n], static_cast<long long>(due));
      } else {
        while (flow.dueMass[n] < f.massRate * (te - f.start)) {
          const auto id = static_cast<std::uint64_t>(
              inflowIdBase + flow.due[n] * static_cast<long long>(nIn) + static_cast<long long>(n));
          flow.dueMass[n] += massOf(f.material, f.size.radius(detail::uniform01(seed, id, 1)));
          ++flow.due[n];
        }
      }
    }
    auto& w = flow.waiting[n];
    for (long long k = before; k < flow.due[n]; ++k) w.push_back(k);
    total += static_cast<std::size_t>(std::min(static_cast<long long>(w.size()), f.na * f.nb));
  }
  if (total == 0) return;
  const auto candidate = [&](std::size_t n, long long j, detail::NewParticle& q) {
    const auto& f = inflow[n];
    const detail::RandomPermutation perm(
        static_cast<std::uint64_t>(f.na * f.nb),
        detail::hash3(seed, 0x1f10 + n, static_cast<std::uint64_t>(steps)));
    const auto site = static_cast<long long>(perm(static_cast<std::uint64_t>(j)));
    q.id = inflowIdBase +
           flow.waiting[n][static_cast<std::size_t>(j)] * static_cast<long long>(nIn) +
           static_cast<long long>(n);
    const auto uid = static_cast<std::uint64_t>(q.id);
    q.material = f.material;
    q.temperature = f.temperature;
    q.radius = f.size.radius(detail::uniform01(seed, uid, 1));
    const long long ij[2] = {site % f.na, site / f.na};
    const int ab[2] = {f.a, f.b};
    const double free = std::max(0.0, 0.5 * f.s - q.radius);
    const auto stream = 1000 + 4 * static_cast<std::uint64_t>(steps);
    for (int k = 0; k < 2; ++k)
      q.x[ab[k]] =
          f.pmin[k] + (static_cast<double>(ij[k]) + 0.5) * f.s +
          free * (2.0 * detail::uniform01(seed, uid, stream + static_cast<std::uint64_t>(k)) - 1.0);
    q.x[f.axis] = f.side == 0 ? search.bins().origin[f.axis] + 0.5 * f.s
                              : search.bins().origin[f.axis] + search.bins().L[f.axis] - 0.5 * f.s;
    for (int d = 0; d < 3; ++d) {
      q.v[d] = f.v[static_cast<std::size_t>(d)];
      if (f.spread > 0)
        q.v[d] += f.spread *
                  (2.0 * detail::uniform01(seed, uid, 10 + static_cast<std::uint64_t>(d)) - 1.0);
    }
  };
  const auto overlaps = [&](const detail::NewParticle& q) {
    int b[3];
    for (int d = 0; d < 3; ++d)
      b[d] = static_cast<int>(std::clamp(search.bins().gbinRaw(q.x[d], d) - search.bins().binLo[d],
                                         0LL, static_cast<long long>(search.bins().nb[d] - 1))) +
             1;
    for (int z = b[2] - 1; z <= b[2] + 1; ++z)
      for (int y = b[1] - 1; y <= b[1] + 1; ++y)
        for (int x = b[0] - 1; x <= b[0] + 1; ++x) {
          const auto bin =
              static_cast<std::size_t>(x + search.bins().nbx[0] * (y + search.bins().nbx[1] * z));
          for (int e = search.bins().binStart[bin]; e < search.bins().binStart[bin + 1]; ++e) {
            const auto i =
                static_cast<std::size_t>(search.bins().binItems[static_cast<std::size_t>(e)]);
            double r2 = 0;
            for (int d = 0; d < 3; ++d) r2 += (p.x[d][i] - q.x[d]) * (p.x[d][i] - q.x[d]);
            const double rs = p.radius[i] + q.radius;
            if (r2 < rs * rs) return true;
          }
        }
    return false;
  };
  // verdicts: 1 = rejected by the owner of the candidate's centre (max over the ranks)
  ensure(inScr, total);
  inScr.assign(total, 0);
  detail::NewParticle q;
  for (std::size_t n = 0, c = 0; n < nIn; ++n) {
    const long long m =
        std::min(static_cast<long long>(flow.waiting[n].size()), inflow[n].na * inflow[n].nb);
    for (long long j = 0; j < m; ++j, ++c) {
      candidate(n, j, q);
      if (search.bins().owns(q.x) && overlaps(q)) inScr[c] = 1;
    }
  }
  comm.maxInPlace(std::span<int>(inScr.data(), total));
  for (std::size_t n = 0, c = 0; n < nIn; ++n) {
    auto& w = flow.waiting[n];
    const long long m = std::min(static_cast<long long>(w.size()), inflow[n].na * inflow[n].nb);
    std::size_t keep = 0;
    for (long long j = 0; j < m; ++j, ++c) {
      const auto ju = static_cast<std::size_t>(j);
      if (inScr[c] != 0) {
        w[keep++] = w[ju];
        continue;
      }
      candidate(n, j, q);
      flow.massIn += massOf(q.material, q.radius);
      if (heat.on)
        heat.inflowEnthalpy += massOf(q.material, q.radius) *
                               heat.cp[static_cast<std::size_t>(q.material)] * q.temperature;
      ++flow.inserted[n];
      ++flow.countIn;
      forceRebuild = true;
      if (search.bins().owns(q.x)) {
        ensure(incoming, incoming.size() + 1);
        incoming.push_back(q);
      }
    }
    // the rejected candidates keep their order, ahead of the ones that were not candidates
    for (std::size_t j = static_cast<std::size_t>(m); j < w.size(); ++j) w[keep++] = w[j];
    w.resize(keep);
  }
}

std::vector<double> DemFlow::pack() const {
  std::vector<double> v = {static_cast<double>(countInitial), massInitial,
                           static_cast<double>(countIn),      massIn,
                           static_cast<double>(countOut),     massOut};
  for (long long c : countOutByFace) v.push_back(static_cast<double>(c));
  v.push_back(static_cast<double>(due.size()));
  for (std::size_t n = 0; n < due.size(); ++n) {
    v.push_back(static_cast<double>(due[n]));
    v.push_back(static_cast<double>(inserted[n]));
    v.push_back(dueMass[n]);
    const auto& w = n < waiting.size() ? waiting[n] : std::vector<long long>{};
    v.push_back(static_cast<double>(w.size()));
    for (long long k : w) v.push_back(static_cast<double>(k));
  }
  return v;
}

DemFlow DemFlow::unpack(const std::vector<double>& v) {
  DemFlow f;
  if (v.size() < 13) return f;
  f.countInitial = static_cast<long long>(v[0]);
  f.massInitial = v[1];
  f.countIn = static_cast<long long>(v[2]);
  f.massIn = v[3];
  f.countOut = static_cast<long long>(v[4]);
  f.massOut = v[5];
  for (std::size_t k = 0; k < 6; ++k) f.countOutByFace[k] = static_cast<long long>(v[6 + k]);
  const auto m = static_cast<std::size_t>(v[12]);
  std::size_t q = 13;
  for (std::size_t n = 0; n < m && q + 4 <= v.size(); ++n) {
    f.due.push_back(static_cast<long long>(v[q]));
    f.inserted.push_back(static_cast<long long>(v[q + 1]));
    f.dueMass.push_back(v[q + 2]);
    const auto nw = static_cast<std::size_t>(v[q + 3]);
    q += 4;
    std::vector<long long> w;
    for (std::size_t k = 0; k < nw && q < v.size(); ++k, ++q)
      w.push_back(static_cast<long long>(v[q]));
    f.waiting.push_back(std::move(w));
  }
  return f;
}

}  // namespace coloc::dem
