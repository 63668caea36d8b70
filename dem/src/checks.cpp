// dem/src/checks.cpp — the DEM's checks of a case, callable without a solver (`coloc check`):
// materials, faces, bins, the time step against the smallest particle of each material, and
// overlaps of the initial particles. A DemSolver's construction runs the same functions.
#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>
#include <string>
#include <utility>
#include <vector>

#include "impl.hpp"

namespace coloc::dem {

namespace detail {

std::vector<Material> readMaterials(const Config& cfg) {
  std::vector<Material> mats;
  for (const auto& m : cfg.at("particles.materials")) {
    Material mt;
    mt.density = m["density"].get<double>();
    mt.young = m["young"].get<double>();
    mt.poisson = m["poisson"].get<double>();
    mt.restitution = m["restitution"].get<double>();
    mt.friction = m["friction"].get<double>();
    mt.rollingFriction = m["rolling_friction"].get<double>();
    // optional keys: absent (0 here) unless given; required with particles.heat
    mt.heatCapacity = m.value("heat_capacity", 0.0);
    mt.conductivity = m.value("conductivity", 0.0);
    if (cfg.boolean("particles.heat")) {
      const std::string key = fmt::format("particles.materials[{}]", mats.size());
      if (!m.contains("heat_capacity"))
        throw ConfigError(key + ".heat_capacity",
                          "required (> 0, J/(kg K)) when particles.heat is true");
      if (!m.contains("conductivity"))
        throw ConfigError(key + ".conductivity",
                          "required (> 0, W/(m K)) when particles.heat is true");
    }
    mats.push_back(mt);
  }
  const auto n = static_cast<long long>(mats.size());
  if (n > 0 && cfg.integer("particles.wall_material") >= n)
    throw ConfigError("particles.wall_material", fmt::format("no such material ({} declared)", n));
  return mats;
}

FaceKinds faceKinds(const Config& cfg, const GlobalGrid& grid,
                    const std::vector<InflowInfo>& inflow) {
  FaceKinds face{};
  const bool wallsOn = cfg.boolean("particles.walls");
  const char* names[3][2] = {{"xlo", "xhi"}, {"ylo", "yhi"}, {"zlo", "zhi"}};
  for (int d = 0; d < 3; ++d)
    for (int s = 0; s < 2; ++s) {
      const std::string key = std::string("particles.boundary.") + names[d][s];
      const std::string v = cfg.string(key);
      Face f;
      if (v == "auto") {
        f = grid.periodic[d] ? Face::Periodic : (wallsOn ? Face::Wall : Face::Open);
      } else if (v == "periodic") {
        if (!grid.periodic[d])
          throw ConfigError(key,
                            std::string("periodic needs a periodic fluid axis (domain.periodic.") +
                                kAxis[d] + " = true)");
        f = Face::Periodic;
      } else {
        if (grid.periodic[d])
          throw ConfigError(key, "'" + v + "' on a periodic axis (domain.periodic." + kAxis[d] +
                                     " = true): use periodic or auto");
        f = v == "wall" ? Face::Wall : Face::Outflow;
      }
      face[d][s] = f;
    }
  for (std::size_t n = 0; n < inflow.size(); ++n) {
    const auto& f = inflow[n];
    if (face[f.axis][f.side] == Face::Outflow)
      throw ConfigError(fmt::format("particles.inflow[{}].face", n),
                        std::string("the face ") + names[f.axis][f.side] +
                            " is an outflow face (particles.boundary): the particles would "
                            "leave as they enter");
    for (std::size_t m = 0; m < n; ++m) {
      const auto& g = inflow[m];
      if (g.axis == f.axis && g.side == f.side && f.pmin[0] < g.pmax[0] && g.pmin[0] < f.pmax[0] &&
          f.pmin[1] < g.pmax[1] && g.pmin[1] < f.pmax[1])
        throw ConfigError(
            fmt::format("particles.inflow[{}].patch", n),
            fmt::format("overlaps the patch of particles.inflow[{}] on the same face", m));
    }
  }
  return face;
}

void checkTimeStep(const TimeStepInput& in) {
  // Rayleigh time (Hertz): pi r sqrt(rho/G) / (0.1631 nu + 0.8766), G = E/(2(1+nu))
  // (Li, Xu & Thornton 2005); linear: collision time pi sqrt(m*/k_n) with m* = m_min/2.
  // Both grow with the radius: the smallest particle of each material sets the limit; the
  // particles to come (inflow) count with the smallest radius of their distribution.
  double tLim = std::numeric_limits<double>::infinity();
  const auto limit = [&](int mat, double r) {
    const auto& m = in.mats[static_cast<std::size_t>(mat)];
    double t;
    if (in.model == Model::HertzMindlin) {
      const double G = m.young / (2 * (1 + m.poisson));
      t = M_PI * r * std::sqrt(m.density / G) / (0.1631 * m.poisson + 0.8766);
    } else {
      const double mass = m.density * 4.0 / 3.0 * M_PI * r * r * r;
      t = M_PI * std::sqrt(0.5 * mass / in.kn);
    }
    tLim = std::min(tLim, t);
  };
  for (std::size_t m = 0; m < in.rMinOfMaterial.size(); ++m)
    if (std::isfinite(in.rMinOfMaterial[m])) limit(static_cast<int>(m), in.rMinOfMaterial[m]);
  for (const auto& f : in.inflow) limit(f.material, f.size.rmin());
  if (!std::isfinite(tLim)) return;
  if (in.dt > in.fraction * tLim) {
    const char* what = in.model == Model::HertzMindlin ? "Rayleigh time" : "linear collision time";
    throw ConfigError("particles.dt",
                      fmt::format("time step {:.4g} s is above {:.4g} of the {} {:.4g} s of the "
                                  "smallest particle: use at most {:.4g} s",
                                  in.dt, in.fraction, what, tLim, in.fraction * tLim));
  }
}

namespace {

/// The largest overlap of the particles `parts` (radius and id filled), as the first force
/// computation of a DemSolver measures it: (r_i + r_j - |x_i - x_j|) / min(r_i, r_j) over pairs
/// (nearest periodic image), (r - distance to the face) / r against wall faces.
void checkOverlaps(const Config& cfg, const GlobalGrid& grid, const CaseParticles& parts,
                   const FaceKinds& face) {
  const std::size_t n = parts.radius.size();
  if (n == 0) return;
  const double limitFrac = cfg.number("particles.overlap_limit");
  double worst = 0;
  std::int64_t worstId = -1, worstPartner = 0;
  const auto note = [&](double ov, std::int64_t a, std::int64_t b) {
    if (ov > worst) worst = ov, worstId = a, worstPartner = b;
  };
  // walls
  for (std::size_t i = 0; i < n; ++i) {
    const double r = parts.radius[i];
    for (int d = 0; d < 3; ++d)
      for (int s = 0; s < 2; ++s) {
        if (face[d][s] != Face::Wall) continue;
        const double x = parts.x[d][i];
        const double dist = s == 0 ? x - grid.origin[d] : grid.origin[d] + grid.length[d] - x;
        if (r - dist > 0) note((r - dist) / r, parts.id[i], -1);
      }
  }
  // pairs: cubes of edge >= the largest diameter (no more cubes than about 2 per particle), the
  // 27 neighbours of each
  double edge = std::max(2 * parts.rMax, 1e-300);
  std::array<long long, 3> nc{};
  for (;;) {
    for (int d = 0; d < 3; ++d)
      nc[d] = std::clamp(static_cast<long long>(std::floor(grid.length[d] / edge)), 1LL, 1LL << 20);
    if (static_cast<double>(nc[0]) * static_cast<double>(nc[1]) * static_cast<double>(nc[2]) <=
        2.0 * static_cast<double>(n) + 8)
      break;
    edge *= 1.25;
  }
  const auto cellOf = [&](int d, double x) {
    const auto c = static_cast<long long>(
        std::floor((x - grid.origin[d]) / grid.length[d] * static_cast<double>(nc[d])));
    return std::clamp(c, 0LL, nc[d] - 1);
  };
  const auto key = [&](long long a, long long b, long long c) {
    return a + nc[0] * (b + nc[1] * c);
  };
  // particles sorted by cube (a counting sort: start[c] .. start[c + 1] in `order`)
  const auto nCubes = static_cast<std::size_t>(nc[0] * nc[1] * nc[2]);
  std::vector<std::size_t> start(nCubes + 1, 0), order(n);
  std::vector<long long> cubeOf(n);
  for (std::size_t i = 0; i < n; ++i) {
    cubeOf[i] = key(cellOf(0, parts.x[0][i]), cellOf(1, parts.x[1][i]), cellOf(2, parts.x[2][i]));
    ++start[static_cast<std::size_t>(cubeOf[i]) + 1];
  }
  for (std::size_t c = 0; c < nCubes; ++c) start[c + 1] += start[c];
  {
    std::vector<std::size_t> fill(start.begin(), start.end() - 1);
    for (std::size_t i = 0; i < n; ++i) order[fill[static_cast<std::size_t>(cubeOf[i])]++] = i;
  }
  for (std::size_t kc = 0; kc < nCubes; ++kc) {
    if (start[kc] == start[kc + 1]) continue;
    const auto k = static_cast<long long>(kc);
    const long long c0[3] = {k % nc[0], (k / nc[0]) % nc[1], k / (nc[0] * nc[1])};
    std::array<std::vector<long long>, 3> near;  // neighbour cubes along each axis, no repeats
    for (int d = 0; d < 3; ++d)
      for (long long o = -1; o <= 1; ++o) {
        long long c = c0[d] + o;
        if (grid.periodic[d]) c = (c % nc[d] + nc[d]) % nc[d];
        if (c < 0 || c >= nc[d]) continue;
        if (std::find(near[d].begin(), near[d].end(), c) == near[d].end()) near[d].push_back(c);
      }
    for (long long cz : near[2])
      for (long long cy : near[1])
        for (long long cx : near[0]) {
          const auto other = static_cast<std::size_t>(key(cx, cy, cz));
          for (std::size_t a = start[kc]; a < start[kc + 1]; ++a)
            for (std::size_t b = start[other]; b < start[other + 1]; ++b) {
              const std::size_t i = order[a], j = order[b];
              if (parts.id[j] <= parts.id[i]) continue;  // each pair once
              double d2 = 0;
              for (int d = 0; d < 3; ++d) {
                double dx = parts.x[d][i] - parts.x[d][j];
                if (grid.periodic[d]) dx -= grid.length[d] * std::round(dx / grid.length[d]);
                d2 += dx * dx;
              }
              const double ri = parts.radius[i], rj = parts.radius[j];
              const double delta = ri + rj - std::sqrt(d2);
              if (delta > 0) note(delta / std::min(ri, rj), parts.id[i], parts.id[j]);
            }
        }
  }
  if (worst > limitFrac)
    throw Error(fmt::format(
        "particle {} overlaps {} by {:.4g} of the smaller radius where the case places them "
        "(limit particles.overlap_limit = {:.4g}): move the particles apart or shrink them",
        worstId,
        worstPartner < 0 ? std::string("a wall") : fmt::format("particle {}", worstPartner), worst,
        limitFrac));
}

}  // namespace
}  // namespace detail

void checkCase(const Config& cfg, const GlobalGrid& grid, const CaseParticles& parts) {
  // In the order of a DemSolver's construction (setup.cpp), so that the first error is the same.
  const auto mats = detail::readMaterials(cfg);
  const int nMat = static_cast<int>(mats.size());
  const auto info = detail::inspectSources(cfg, grid, nMat);
  const auto inflow = detail::inspectInflow(cfg, grid, nMat);
  const detail::SourceTotals totals = detail::sourceTotals(info);
  double rmax = totals.rmax;
  long long total = totals.count;
  for (const auto& f : inflow) rmax = std::max(rmax, f.size.rmax());
  const long long binTotal = total + (inflow.empty() ? 0 : 1);
  if (total > 0 && nMat == 0)
    throw ConfigError("particles.materials", "at least one material is required");
  const detail::FaceKinds face = detail::faceKinds(cfg, grid, inflow);
  const double dmax = 2 * rmax;
  std::array<std::vector<int>, 3> one;
  for (int d = 0; d < 3; ++d) one[d] = {0, grid.cells[d]};
  binLayout(cfg, grid, one, dmax, cfg.number("particles.skin") * dmax, std::max(total, binTotal));
  const Model model =
      cfg.string("particles.contact_model") == "linear" ? Model::Linear : Model::HertzMindlin;
  detail::checkTimeStep({cfg.number("particles.dt"), cfg.number("particles.dt_fraction"), model,
                         cfg.number("particles.linear.kn"), mats, inflow, parts.rMinOfMaterial});
  detail::checkOverlaps(cfg, grid, parts, face);
}

}  // namespace coloc::dem
