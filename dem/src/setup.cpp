// dem/src/setup.cpp — setup of the DEM: materials, bins, the time-step check, the initial
// particles.
#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>
#include <span>
#include <string>

#include "coloc/partition/tiled.hpp"
#include "impl.hpp"
#include "rows.hpp"

namespace coloc::dem {

using namespace detail;

// ---------------------------------------------------------------------------------------------
// setup

DemSolver::Impl::Impl(const Decomposition& d, const Config& cfg, Timers& t, DemState* initial)
    : dec(d), comm(d.comm()), timers(t) {
  ScopedPhase setup(timers, Phase::Setup);
  const auto& grid = dec.grid();
  integrator.dt = cfg.number("particles.dt");
  forces.law.model =
      cfg.string("particles.contact_model") == "linear" ? Model::Linear : Model::HertzMindlin;
  const auto grav = cfg.vec3("gravity");
  for (int k = 0; k < 3; ++k) integrator.g[k] = grav[k];
  overlapLimit = cfg.number("particles.overlap_limit");
  dtFraction = cfg.number("particles.dt_fraction");
  search.mutableHistory().hStart.assign(1, 0);
  readMaterials(cfg);
  heat.setup(cfg, mats, p);  // registers the temperature fields when particles.heat is on
  for (const auto& m : mats) forces.law.rolling = forces.law.rolling || m.rollingFriction > 0;

  const auto info = detail::inspectSources(cfg, grid, forces.law.nMat);
  inflow = detail::inspectInflow(cfg, grid, forces.law.nMat);
  seed = static_cast<std::uint64_t>(cfg.integer("particles.seed"));
  const detail::SourceTotals totals = detail::sourceTotals(info);
  double rmax = totals.rmax;
  long long total = totals.count;
  inflowIdBase = total;
  flow.due.assign(inflow.size(), 0);
  flow.inserted.assign(inflow.size(), 0);
  flow.dueMass.assign(inflow.size(), 0.0);
  flow.waiting.assign(inflow.size(), {});
  for (const auto& f : inflow) rmax = std::max(rmax, f.size.rmax());
  // bins must exist for the particles to come (setupBins checks them only when any will)
  const long long binTotal = total + (inflow.empty() ? 0 : 1);
  if (initial) {
    // a restart: the bins are those of the case (same sources: same bins as the run that wrote
    // the state), widened only if the state holds larger particles than the sources
    double rs = 0;
    for (const double r : initial->particles.radius) rs = std::max(rs, r);
    rmax = std::max(rmax, comm.max(rs));
    // (with inflow the bins stay those of the case: the run that wrote the state had them)
    if (total == 0 && inflow.empty())
      total = comm.sum(static_cast<long long>(initial->particles.nOwned));
  }
  if (total > 0 && forces.law.nMat == 0)
    throw ConfigError("particles.materials", "at least one material is required");
  const double dmax = 2 * rmax;
  skin = cfg.number("particles.skin") * dmax;
  rc = dmax + skin;
  search.setPruneMargin(cfg.number("particles.prune_margin") * dmax);
  {
    const std::string isa = cfg.string("particles.force_isa");
    const ForceIsa want = isa == "avx512"   ? ForceIsa::Avx512
                          : isa == "scalar" ? ForceIsa::Scalar
                                            : ForceIsa::Widest;
    if (!forces.selectIsa(want))
      throw ConfigError("particles.force_isa",
                        "avx512: this CPU lacks AVX-512 (F and VL); use scalar or widest");
  }
  setupFaces(cfg);
  for (int k = 0; k < 3; ++k)
    wallOn[k] = {face[k][0] == Face::Wall && dec.atLowBoundary(k),
                 face[k][1] == Face::Wall && dec.atHighBoundary(k)};
  setupBins(cfg, dmax, std::max(total, binTotal));

  if (initial) {
    restore(*initial);
    checkTimeStep();
    return;
  }
  // Two passes over the sources: count this rank's particles, size every array once (exactly),
  // then fill them (growing ~23 arrays particle by particle cost a third of a 2M-particle set-up
  // in copies and page faults).
  {
    const auto ownsX = [this](const double* x) { return search.bins().owns(x); };
    std::size_t count = 0;
    detail::generate(cfg, info, search.bins().lo, search.bins().hi, ownsX,
                     [&count](const detail::NewParticle&) { ++count; });
    detail::resizeAll(p, count);
    search.mutableHistory().hStart.assign(count + 1, 0);
    detail::generate(cfg, info, search.bins().lo, search.bins().hi, ownsX,
                     [this](const detail::NewParticle& q) { addParticle(q); });
  }
  checkTimeStep();
  {
    double m = 0;
    for (std::size_t i = 0; i < p.nOwned; ++i) m += p.mass[i];
    double buf[2] = {static_cast<double>(p.nOwned), m};
    comm.sumInPlace(std::span<double>(buf, 2));
    flow.countInitial = static_cast<long long>(buf[0]);
    flow.massInitial = buf[1];
  }
  if (flow.countInitial != totals.count) refuseMissingParticles(info);
  if (heat.on) heat.enthalpyInitial = comm.sum(heat.localEnthalpy(p));  // a reduction of its own
  rebuild(true);
  {
    ScopedPhase f(timers, Phase::DemForce);
    computeForces(false);
  }
  checkOverlap(comm.max(forces.tally().maxOverlap));
}

void DemSolver::Impl::refuseMissingParticles(const std::vector<detail::SourceInfo>& info) {
  // Every rank made the particles its bins own: a particle no rank owns (a position that does
  // not land in the box's bins at double precision, e.g. in a region of 1e16 m) is lost. Which
  // source lost it, by the ids (source s holds [base_s, base_s + count_s)).
  std::vector<double> made(info.size(), 0.0);
  for (std::size_t i = 0; i < p.nOwned; ++i) {
    long long base = 0;
    for (std::size_t s = 0; s < info.size(); ++s) {
      if (p.id[i] < base + info[s].count) {
        made[s] += 1;
        break;
      }
      base += info[s].count;
    }
  }
  comm.sumInPlace(std::span<double>(made));
  for (std::size_t s = 0; s < info.size(); ++s)
    if (static_cast<long long>(made[s]) != info[s].count)
      throw ConfigError(fmt::format("particles.sources[{}]", s),
                        fmt::format("placed {} of its {} particles: the others' positions fall "
                                    "outside every block of the box (a region or box so large "
                                    "that the particle positions lose their precision?)",
                                    static_cast<long long>(made[s]), info[s].count));
  throw Error(fmt::format("placed {} of the sources' {} particles", flow.countInitial,
                          detail::sourceTotals(info).count));
}

void DemSolver::Impl::readMaterials(const Config& cfg) {
  mats = detail::readMaterials(cfg);  // checks.cpp (also `coloc check`)
  ContactLaw& law = forces.law;
  const int nMat = law.nMat = static_cast<int>(mats.size());
  if (nMat == 0) return;
  const auto wm = cfg.integer("particles.wall_material");
  const double kn = cfg.number("particles.linear.kn");
  const double ktr = cfg.number("particles.linear.kt_ratio");
  law.pair.resize(static_cast<std::size_t>(nMat * nMat));
  law.wall.resize(static_cast<std::size_t>(nMat));
  for (int a = 0; a < nMat; ++a) {
    for (int b = 0; b < nMat; ++b)
      law.pair[static_cast<std::size_t>(a * nMat + b)] = detail::mix(mats[a], mats[b], kn, ktr);
    law.wall[static_cast<std::size_t>(a)] =
        detail::mix(mats[a], mats[static_cast<std::size_t>(wm)], kn, ktr);
  }
}

BinLayout binLayout(const Config& cfg, const GlobalGrid& grid,
                    const std::array<std::vector<int>, 3>& cuts, double dmax, double skin,
                    long long total) {
  const bool any = total > 0;
  const double rc = dmax + skin;
  BinLayout out;
  // Automatic split of large cells: bins near the interaction range, but never (much) more
  // bins than particles: a few spheres in big cells must not allocate split^3 bins per cell.
  const double perCell = static_cast<double>(total) / static_cast<double>(grid.cellCount());
  const long long splitCap =
      std::max(1LL, static_cast<long long>(std::floor(std::cbrt(std::max(1.0, 8.0 * perCell)))));
  const long long kc = cfg.integer("particles.bin_cells");
  const long long ks = cfg.integer("particles.bin_split");
  if (kc > 0 && ks > 0)
    throw ConfigError("particles.bin_split",
                      "give particles.bin_cells or particles.bin_split, "
                      "not both");
  const auto range = [&] {
    return fmt::format("the interaction range {:.4g} m (largest diameter {:.4g} m + skin {:.4g} m)",
                       rc, dmax, skin);
  };
  for (int d = 0; d < 3; ++d) {
    const double h = grid.spacing(d);
    const auto& cd = cuts[d];
    const auto divides = [&](long long k) {
      return std::all_of(cd.begin(), cd.end(), [k](int c) { return c % k == 0; });
    };
    long long multiple = 1, split = 1;
    std::string key;
    if (ks > 0) {
      split = ks;
      key = "particles.bin_split";
    } else if (kc > 0) {
      multiple = kc;
      key = "particles.bin_cells";
      if (!divides(kc))
        throw ConfigError(key, fmt::format("a bin of {} cells does not fit the blocks along {}: "
                                           "every block edge (cell cuts of the decomposition) "
                                           "must fall on a bin edge",
                                           kc, kAxis[d]));
    } else {
      key = "particles.bin_cells";
      if (h >= rc) {
        // clamped as a double: h / rc may be beyond any integer
        split = rc > 0
                    ? static_cast<long long>(std::clamp(
                          std::floor(h / rc), 1.0, static_cast<double>(std::min(64LL, splitCap))))
                    : 1;
      } else {
        // A range wider than the box is refused before it becomes a bin count (a skin of 1e20
        // would overflow the cast and loop through every integer).
        if (!(rc / h <= static_cast<double>(grid.cells[d])))
          throw ConfigError("particles.skin",
                            fmt::format("{} is wider than the box along {} ({:.4g} m): lower "
                                        "particles.skin or the particle size",
                                        range(), kAxis[d], h * grid.cells[d]));
        multiple = static_cast<long long>(std::ceil(rc / h));
        while (multiple <= grid.cells[d] && (!divides(multiple) || multiple * h < rc)) ++multiple;
        if (multiple > grid.cells[d])
          throw ConfigError(key, fmt::format("no bin made of whole cells holds {} and fits the "
                                             "blocks along {} (cell {:.4g} m): use larger cells "
                                             "or fewer ranks",
                                             range(), kAxis[d], h));
      }
    }
    out.size[d] = split > 1 ? h / static_cast<double>(split) : h * static_cast<double>(multiple);
    out.split[d] = split;
    out.multiple[d] = split > 1 ? 1 : multiple;
    if (any && out.size[d] < rc)
      throw ConfigError(key, fmt::format("the bin edge {:.4g} m along {} is smaller than {}",
                                         out.size[d], kAxis[d], range()));
    out.globalBins[d] = split > 1 ? grid.cells[d] * split : grid.cells[d] / multiple;
    if (any && grid.periodic[d] && out.globalBins[d] < 2)
      throw ConfigError(key, fmt::format("a periodic axis needs at least 2 bins ({} has {}): the "
                                         "box must be at least twice {}",
                                         kAxis[d], out.globalBins[d], range()));
  }
  return out;
}

void DemSolver::Impl::setupBins(const Config& cfg, double dmax, long long total) {
  const auto& grid = dec.grid();
  // tiled: every box bound is a bin edge (the layout's cut planes)
  const BinLayout b = dec.isTiled()
                          ? binLayout(cfg, grid, boxLayoutOf(dec).cutPlanes(), dmax, skin, total)
                          : binLayout(cfg, grid, dec.cuts(), dmax, skin, total);
  search.setupBins(grid, b, dec.lo(), dec.hi());
  // the particle exchange of the layout (exchange.hpp), lent the solver's state
  exchange = detail::makeExchange({.dec = dec,
                                   .comm = comm,
                                   .timers = timers,
                                   .p = p,
                                   .hist = search.mutableHistory(),
                                   .bins = search.bins(),
                                   .rc = rc,
                                   .where = [this] { return where(); }},
                                  b);
}

CaseParticles caseParticles(const Config& cfg, const GlobalGrid& grid, bool rows) {
  const int nMat = static_cast<int>(cfg.at("particles.materials").size());
  const auto info = detail::inspectSources(cfg, grid, nMat);
  const detail::SourceTotals totals = detail::sourceTotals(info);
  CaseParticles out;
  const double dmax = 2 * totals.rmax;
  out.skin = cfg.number("particles.skin") * dmax;
  out.dmax = dmax;
  out.range = dmax + out.skin;
  out.total = totals.count;
  Real3 lo = grid.origin, hi{};
  for (int d = 0; d < 3; ++d) hi[d] = grid.origin[d] + grid.length[d];
  const auto all = [](const double*) { return true; };
  std::size_t count = 0;
  detail::generate(cfg, info, lo, hi, all, [&count](const detail::NewParticle&) { ++count; });
  for (auto& x : out.x) x.reserve(count);
  if (rows) {
    out.radius.reserve(count);
    out.id.reserve(count);
  }
  out.rMinOfMaterial.assign(static_cast<std::size_t>(nMat),
                            std::numeric_limits<double>::infinity());
  detail::generate(cfg, info, lo, hi, all, [&out, rows](const detail::NewParticle& q) {
    for (int d = 0; d < 3; ++d) out.x[d].push_back(q.x[d]);
    if (rows) {
      out.radius.push_back(q.radius);
      out.id.push_back(q.id);
    }
    auto& rm = out.rMinOfMaterial[static_cast<std::size_t>(q.material)];
    rm = std::min(rm, q.radius);
    out.rMin = out.x[0].size() == 1 ? q.radius : std::min(out.rMin, q.radius);
    out.rMax = std::max(out.rMax, q.radius);
  });
  return out;
}

void DemSolver::Impl::checkTimeStep() {
  // The check of `coloc check` (checks.cpp) on the smallest radius of each material over all
  // ranks: the limit grows with the radius, so this is the smallest limit over the particles.
  std::vector<double> negMin(static_cast<std::size_t>(forces.law.nMat),
                             -std::numeric_limits<double>::infinity());
  for (std::size_t i = 0; i < p.nOwned; ++i) {
    const auto m = static_cast<std::size_t>(p.material[i]);
    if (m < negMin.size()) negMin[m] = std::max(negMin[m], -p.radius[i]);
  }
  comm.maxInPlace(std::span<double>(negMin));
  std::vector<double> rMin(negMin.size());
  for (std::size_t m = 0; m < rMin.size(); ++m) rMin[m] = -negMin[m];
  detail::checkTimeStep({integrator.dt, dtFraction, forces.law.model,
                         forces.law.pair.empty() ? 0.0 : forces.law.pair[0].kn, mats, inflow,
                         rMin});
  if (heat.on) {
    for (const auto& f : inflow) {
      auto& r = rMin[static_cast<std::size_t>(f.material)];
      r = std::min(r, f.size.rmin());
    }
    heat.checkTimeStep(integrator.dt, overlapLimit, mats, rMin);
  }
}

void DemSolver::Impl::addParticle(const detail::NewParticle& q) {
  const std::size_t n = p.nOwned + 1;
  if (p.id.size() < n) detail::resizeAll(p, n);  // sized beforehand by the counting pass
  const std::size_t i = n - 1;
  p.nOwned = n;
  for (auto& e : p.extra)
    for (auto& c : e.data) c[i] = 0;
  if (heat.on) p.extra[heat.iT].data[0][i] = q.temperature;
  p.id[i] = q.id;
  p.material[i] = q.material;
  p.radius[i] = q.radius;
  p.mass[i] = massOf(q.material, q.radius);
  for (int d = 0; d < 3; ++d) {
    p.x[d][i] = q.x[d];
    p.v[d][i] = q.v[d];
    p.omega[d][i] = p.f[d][i] = p.torque[d][i] = p.fExt[d][i] = 0;
  }
  if (search.mutableHistory().hStart.size() < n + 1) {
    ensure(search.mutableHistory().hStart, n + 1);
    search.mutableHistory().hStart.resize(n + 1);
  }
  search.mutableHistory().hStart[n] = search.mutableHistory().hStart[n - 1];
}

}  // namespace coloc::dem
