// `coloc check CASE [--ranks N]`: validate a case and show what a run on N ranks would do, in one
// process, running nothing (docs/case-files.md). `coloc keys [PREFIX]`.
#include "check.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <numeric>
#include <sstream>

#include "coloc/core/config.hpp"
#include "coloc/core/error.hpp"
#include "coloc/core/files.hpp"
#include "coloc/core/provenance.hpp"
#include "coloc/core/run_config.hpp"
#include "coloc/coupling/case_checks.hpp"
#include "coloc/coupling/simulation.hpp"
#include "coloc/dem/dem.hpp"
#include "coloc/partition/balance.hpp"
#include "coloc/partition/setup.hpp"
#include "coloc/partition/strategy.hpp"
#include "layout_svg.hpp"
#include "run.hpp"

namespace coloc {
namespace {

/// One strategy's layout for N ranks: every rank's fluid box and particle box (the same but in
/// independent), and the layout's shape for the table.
struct Plan {
  std::string strategy;
  std::vector<IndexBox> fluid, particles;
  std::string fluidShape, particleShape;  // "2x1x3" (a process grid) or "7 boxes" (tiled)
  std::array<std::vector<int>, 3> fluidCuts, particleCuts;  // process grids only (--verbose)
  std::string error;     // the strategy cannot lay out this case on N ranks
  double imbalance = 0;  // largest / mean block cost (the table's)
};

std::string shapeOf(const Blocks& b) {
  return fmt::format("{}x{}x{}", b.dims[0], b.dims[1], b.dims[2]);
}

/// Sum of `perCell` (x fastest) over each box.
std::vector<double> boxSums(const GlobalGrid& g, const std::vector<IndexBox>& boxes,
                            const std::vector<double>& perCell) {
  std::vector<double> out;
  for (const auto& b : boxes) {
    double sum = 0;
    forEach(b, [&](int i, int j, int k) {
      sum += perCell[static_cast<std::size_t>(i + g.cells[0] * (j + 1LL * g.cells[1] * k))];
    });
    out.push_back(sum);
  }
  return out;
}

Int3 extent(const IndexBox& b) {
  return {b.hi[0] - b.lo[0], b.hi[1] - b.lo[1], b.hi[2] - b.lo[2]};
}

std::vector<long long> boxCells(const std::vector<IndexBox>& boxes) {
  std::vector<long long> out;
  for (const auto& b : boxes) out.push_back(b.volume());
  return out;
}

std::string g6(double v) {
  char b[48];
  std::snprintf(b, sizeof b, "%.4g", v);
  return b;
}

template <class T>
std::string minMax(const std::vector<T>& v) {
  if (v.empty()) return "-";
  const auto [lo, hi] = std::minmax_element(v.begin(), v.end());
  return g6(static_cast<double>(*lo)) + " .. " + g6(static_cast<double>(*hi));
}

/// --draw: every strategy's layout in one SVG, with the command and where it was drawn.
void drawLayouts(const CheckOptions& opts, const Config& cfg, const GlobalGrid& g,
                 const std::vector<double>& particlesPerCell, const std::vector<Plan>& plans,
                 const std::string& chosen) {
  std::vector<LayoutDrawing> panels;
  for (const Plan& p : plans) {
    LayoutDrawing d;
    d.strategy = p.strategy;
    d.chosen = p.strategy == chosen;
    if (!p.error.empty()) {
      d.summary = "cannot lay out this case: " + p.error;
    } else {
      d.fluid = p.fluid;
      d.particles = p.particles;
      char s[200];
      if (p.fluidShape == p.particleShape)
        std::snprintf(s, sizeof s, "%s, imbalance %.3f", p.fluidShape.c_str(), p.imbalance);
      else
        std::snprintf(s, sizeof s, "fluid %s, particles %s, imbalance %.3f", p.fluidShape.c_str(),
                      p.particleShape.c_str(), p.imbalance);
      d.summary = s;
    }
    panels.push_back(std::move(d));
  }
  const Json prov = provenance(Comm(MPI_COMM_SELF), opts.commandLine);
  const std::string dirty =
      prov["git_dirty"].is_boolean() && prov["git_dirty"].get<bool>() ? ", dirty" : "";
  const std::string caption = "coloc " + prov["coloc_version"].get<std::string>() + " (" +
                              prov["git_commit"].get<std::string>().substr(0, 12) + dirty +
                              "): " + opts.commandLine + "  |  " + prov["date"].get<std::string>() +
                              ", " + prov["host"].get<std::string>() + " (" +
                              prov["cpu_model"].get<std::string>() + ")";
  writeLayoutSvg(opts.drawPath, g, layoutPlane(g, cfg.vec3("gravity"), opts.plane),
                 particlesPerCell, panels, caption);
  std::printf("coloc check: drew the layouts in %s\n", opts.drawPath.c_str());
}

}  // namespace

int checkCase(const CheckOptions& opts) {
  // The rank count bounds every layout's arithmetic (int block counts, cells / ranks): the same
  // bound as coloc plan's.
  const int N = opts.ranks;
  if (N < 1 || N > (1 << 24))
    throw ConfigError("--ranks",
                      fmt::format("{} is not a rank count coloc lays out (1 .. {})", N, 1 << 24));
  const Comm self(MPI_COMM_SELF);
  const Config cfg = Config::load(self, opts.casePath, opts.overrides, coupling::caseSchema());
  // --draw PATH: a new file, or an SVG of an earlier check (never the case file, a link or a
  // device: coloc/core/files.hpp), refused before the work
  if (!opts.drawPath.empty()) checkUserFile("--draw", opts.drawPath, "<?xml");
  const std::vector<std::string> notes = coupling::checkCase(cfg);
  const GlobalGrid g = gridFromConfig(cfg);
  const RunMode mode = runMode(cfg);
  const std::string strategy = cfg.string("partition.strategy");
  std::printf(
      "coloc check: case '%s' (%s), mode %s, %d x %d x %d = %lld cells, box %g x %g x %g m, "
      "%d rank(s)\n",
      cfg.string("name").c_str(), opts.casePath.c_str(), runModeName(mode), g.cells[0], g.cells[1],
      g.cells[2], g.cellCount(), g.length[0], g.length[1], g.length[2], N);

  // Memory first (nothing allocated yet): the run's own check (largest uniform block, mean
  // particles a rank), with N ranks on this node.
  std::string how;
  const double limit = coupling::memoryLimitPerRank(cfg, N, &how);
  const auto est = coupling::estimateMemory(
      cfg, coupling::largestUniformBlock(cfg, N),
      (coupling::sourceParticleCount(cfg) + coupling::inflowParticleCount(cfg)) / N);
  std::printf(
      "coloc check: memory estimate a rank: %s (fluid and pressure solver %s, coupling "
      "%s, particles %s, inflow waiting lists %s, base %s)\n",
      coupling::bytesText(est.total()).c_str(), coupling::bytesText(est.fluidBytes).c_str(),
      coupling::bytesText(est.couplingBytes).c_str(),
      coupling::bytesText(est.particleBytes).c_str(), coupling::bytesText(est.inflowBytes).c_str(),
      coupling::bytesText(est.baseBytes).c_str());
  std::printf("coloc check: this machine offers %s a rank (%s, all %d ranks on this node)\n",
              limit > 0 ? coupling::bytesText(limit).c_str() : "?", how.c_str(), N);
  if (limit > 0 && est.total() > limit) {
    std::fprintf(stderr,
                 "coloc: error: domain.cells, particles.sources: the case needs about %s a rank, "
                 "the machine offers %s (%s): a run on %d rank(s) here would be refused\n",
                 coupling::bytesText(est.total()).c_str(), coupling::bytesText(limit).c_str(),
                 how.c_str(), N);
    return 2;
  }
  // The per-cell cost arrays of the layouts (what the balanced run itself builds on every rank)
  // must fit in this one process too.
  const double perCellBytes = 3.0 * 8.0 * static_cast<double>(g.cellCount());
  if (limit > 0 && perCellBytes > 0.5 * limit * N) {
    std::printf(
        "coloc check: %lld cells: the per-cell layouts (%s) are not computed in one "
        "process; nothing was run\n",
        g.cellCount(), coupling::bytesText(perCellBytes).c_str());
    for (const auto& n : notes) std::printf("coloc: note: %s\n", n.c_str());
    return 0;
  }

  // The particles as the run generates them (dem::caseParticles, the generator of the run's cost
  // probe: deterministic, the same on any rank count), and the DEM's own checks of the case
  // (dem::checkCase: what a DemSolver's construction checks, and the initial overlaps). No solver.
  std::vector<double> particlesPerCell(static_cast<std::size_t>(g.cellCount()), 0.0);
  double particleCount = 0, rMin = 0, rMax = 0;
  const Decomposition one = Decomposition::uniform(self, g, {1, 1, 1});
  const double demDt = cfg.number("particles.dt");
  if (mode != RunMode::FluidOnly) {
    const dem::CaseParticles parts = dem::caseParticles(cfg, g, /*rows=*/true);
    dem::checkCase(cfg, g, parts);
    const std::size_t n = parts.x[0].size();
    if (n > 0) {
      particlesPerCell = cellCosts(one, parts.x[0], parts.x[1], parts.x[2], CostModel{0.0, 1.0});
      particleCount = static_cast<double>(n);
      rMin = parts.rMin;
      rMax = parts.rMax;
    }
  }
  std::printf("coloc check: %.0f particles", particleCount);
  if (particleCount > 0) std::printf(", radius %g .. %g m", rMin, rMax);
  std::printf("\n");

  // The layouts each strategy would choose for N ranks (the run's own partition code).
  const StrategyInput in = coupling::strategyInput(cfg, N);
  const CostModel caseModel{cfg.number("partition.cost.cell"),
                            cfg.number("partition.cost.particle")};
  std::vector<double> caseCost(particlesPerCell.size());
  for (std::size_t c = 0; c < caseCost.size(); ++c)
    caseCost[c] = caseModel.perCell + caseModel.perParticle * particlesPerCell[c];
  std::vector<Plan> plans;
  const double haloCell = cfg.number("partition.cost.halo_cell");
  for (const PartitionStrategy* s : PartitionStrategy::all()) {
    Plan p;
    p.strategy = s->name();
    try {
      // As a run chooses (PartitionStrategy::layoutFor): a fluid-only run keeps the start layout.
      const StrategyLayout l =
          s->layoutFor(mode, in, CellWork{caseCost, particlesPerCell, haloCell});
      p.fluid = l.fluid.box;
      p.particles = l.particles.box;
      if (l.isGrid()) {
        const Blocks& pb = l.particleBlocks ? *l.particleBlocks : *l.fluidBlocks;
        p.fluidShape = shapeOf(*l.fluidBlocks);
        p.particleShape = shapeOf(pb);
        p.fluidCuts = l.fluidBlocks->cuts;
        p.particleCuts = pb.cuts;
      } else {
        p.fluidShape = p.particleShape = fmt::format("{} boxes", N);
      }
    } catch (const Error& e) {
      p.error = e.what();
    }
    plans.push_back(std::move(p));
  }
  if (cfg.integer("partition.calibrate_steps") > 0)
    std::printf(
        "coloc check: partition.calibrate_steps: the run measures the cost weights first; "
        "shown here with partition.cost.cell = %g, partition.cost.particle = %g\n",
        caseModel.perCell, caseModel.perParticle);

  std::printf("\n  %-12s %-9s %-9s %-20s %-20s %-10s %s\n", "strategy", "fluid", "DEM",
              "cells/rank", "particles/rank", "imbalance", "memory/rank (max)");
  double caseMem = 0;
  for (Plan& p : plans) {
    const bool chosen = p.strategy == strategy;
    if (!p.error.empty()) {
      std::printf("%s %-12s cannot lay out this case: %s\n", chosen ? "*" : " ", p.strategy.c_str(),
                  p.error.c_str());
      continue;
    }
    const auto cells = boxCells(p.fluid);
    const auto parts = boxSums(g, p.particles, particlesPerCell);
    // A rank's work: its fluid block's cells and its particle box's particles (the same box
    // but in independent partitions, whose particles are balanced on boxes of their own; as
    // coloc plan counts it).
    std::vector<double> cost(cells.size());
    for (std::size_t r = 0; r < cost.size(); ++r)
      cost[r] =
          caseModel.perCell * static_cast<double>(cells[r]) + caseModel.perParticle * parts[r];
    const double avg =
        std::accumulate(cost.begin(), cost.end(), 0.0) / static_cast<double>(cost.size());
    const double imb = avg > 0 ? *std::max_element(cost.begin(), cost.end()) / avg : 1.0;
    double mem = 0;
    for (int r = 0; r < N; ++r)
      mem =
          std::max(mem, coupling::estimateMemory(cfg, extent(p.fluid[static_cast<std::size_t>(r)]),
                                                 parts[static_cast<std::size_t>(r)])
                            .total());
    if (chosen) caseMem = mem;
    p.imbalance = imb;
    std::printf("%s %-12s %-9s %-9s %-20s %-20s %-10.3f %s\n", chosen ? "*" : " ",
                p.strategy.c_str(), p.fluidShape.c_str(), p.particleShape.c_str(),
                minMax(cells).c_str(), minMax(parts).c_str(), imb,
                coupling::bytesText(mem).c_str());
    if (opts.verbose && !p.fluidCuts[0].empty()) {
      for (int a = 0; a < 3; ++a) {
        std::printf("      cuts %c:", "xyz"[a]);
        for (int c : p.fluidCuts[a]) std::printf(" %d", c);
        if (p.particleCuts[a] != p.fluidCuts[a]) {
          std::printf("   DEM:");
          for (int c : p.particleCuts[a]) std::printf(" %d", c);
        }
        std::printf("\n");
      }
    }
  }
  std::printf(
      "  (* the case's partition.strategy; imbalance: largest / mean block cost with "
      "partition.cost.*)\n\n");

  std::printf(
      "coloc check: memory of the busiest rank of the case's layout (its particles, "
      "its block): %s\n",
      coupling::bytesText(caseMem).c_str());
  if (!opts.drawPath.empty()) drawLayouts(opts, cfg, g, particlesPerCell, plans, strategy);

  // Time-step limits.
  const auto& mats = cfg.at("particles.materials");
  if (mode != RunMode::FluidOnly && particleCount > 0 && !mats.empty()) {
    const bool hertz = cfg.string("particles.contact_model") == "hertz_mindlin";
    double tLim = std::numeric_limits<double>::infinity(), tHertz = tLim;
    // impact speed: the fastest of the inlets, the initial velocities and a fall over the box
    double vRef = std::sqrt(
        2.0 * std::hypot(cfg.vec3("gravity")[0], cfg.vec3("gravity")[1], cfg.vec3("gravity")[2]) *
        std::max({g.length[0], g.length[1], g.length[2]}));
    for (const auto& s : cfg.at("particles.sources")) {
      const auto& v = s.at("velocity");
      vRef = std::max(vRef, std::hypot(v[0].get<double>(), v[1].get<double>(), v[2].get<double>()) +
                                std::sqrt(3.0) * s.at("velocity_spread").get<double>());
    }
    for (const auto& m : mats) {
      const double E = m.at("young").get<double>(), nu = m.at("poisson").get<double>();
      const double rho = m.at("density").get<double>();
      const double mass = rho * 4.0 / 3.0 * M_PI * rMin * rMin * rMin;
      if (hertz) {
        const double G = E / (2 * (1 + nu));
        tLim = std::min(tLim, M_PI * rMin * std::sqrt(rho / G) / (0.1631 * nu + 0.8766));
        const double Es = E / (2 * (1 - nu * nu)), Rs = rMin / 2, ms = mass / 2;
        if (vRef > 0)
          tHertz = std::min(tHertz, 2.87 * std::pow(ms * ms / (Rs * Es * Es * vRef), 0.2));
      } else {
        tLim = std::min(tLim, M_PI * std::sqrt(0.5 * mass / cfg.number("particles.linear.kn")));
      }
    }
    std::printf(
        "coloc check: DEM: particles.dt = %g s = %.3g of the %s %.3g s (limit "
        "particles.dt_fraction = %g)",
        demDt, demDt / tLim, hertz ? "Rayleigh time" : "linear collision time", tLim,
        cfg.number("particles.dt_fraction"));
    if (hertz && std::isfinite(tHertz))
      std::printf("; Hertz contact time at %.3g m/s: %.3g s = %.0f DEM steps", vRef, tHertz,
                  tHertz / demDt);
    std::printf("\n");
  }
  std::string cflKey, cflError;  // a CFL the run would stop at (below)
  if (mode != RunMode::ParticlesOnly) {
    double h = std::min({g.spacing(0), g.spacing(1), g.spacing(2)});
    // The run's CFL of a cell is dt sum_d |u_d| / h_d (fv/src/step.cpp): the same measure of the
    // initial velocity and of each inlet's. `sure`: what the first step's CFL is at least (an
    // inlet face carries its velocity, a superficial one divided by eps <= 1 there, so at least
    // the velocity given); `possible`: the largest it may be (the initial velocity, a superficial
    // inlet divided by coupling.eps_min).
    double u = 0, sure = 0, possible = 0;
    const auto convective = [&](const double v[3], double scale) {
      double r = 0;
      for (int a = 0; a < 3; ++a) r += std::fabs(v[a]) * scale / g.spacing(a);
      return r;
    };
    const auto iv = cfg.vec3("fluid.initial_velocity");
    for (int a = 0; a < 3; ++a) u = std::max(u, std::fabs(iv[a]));
    {
      const double v[3] = {iv[0], iv[1], iv[2]};
      possible = convective(v, 1.0);
    }
    // The fastest inlet, a whole face or a patch of one (fluid.patches).
    std::vector<Json> inlets;
    for (const char* f : {"xlo", "xhi", "ylo", "yhi", "zlo", "zhi"})
      inlets.push_back(cfg.at(std::string("fluid.boundary.") + f));
    if (cfg.has("fluid.patches"))
      for (const auto& patch : cfg.at("fluid.patches")) inlets.push_back(patch);
    for (const Json& b : inlets) {
      if (b.at("type").get<std::string>() != "inlet" || !b.contains("velocity")) continue;
      double s = 0, v[3];
      for (int a = 0; a < 3; ++a) v[a] = b.at("velocity")[a].get<double>();
      for (int a = 0; a < 3; ++a) s = std::max(s, std::fabs(v[a]));
      double scale = 1.0;
      if (b.contains("superficial") && b.at("superficial").get<bool>() &&
          mode != RunMode::FluidOnly)
        scale = 1.0 / cfg.number("coupling.eps_min");
      u = std::max(u, s * scale);
      sure = std::max(sure, convective(v, 1.0));
      possible = std::max(possible, convective(v, scale));
    }
    double dt = cfg.number("fluid.dt");
    const long long sub = cfg.integer("coupling.dem_substeps");
    if ((mode == RunMode::Coupled || mode == RunMode::DummyDem) && sub > 0)
      dt = static_cast<double>(sub) * demDt;
    const double nu = cfg.number("fluid.nu"), cflMax = cfg.number("fluid.cfl_max");
    const std::string least = sure < possible ? fmt::format(", at least {:.3g}", sure * dt) : "";
    std::printf(
        "coloc check: CFD: step %g s%s, smallest cell %g m, reference speed %g m/s: CFL "
        "%.3g%s (fluid.cfl_max = %g), viscous number nu dt/h^2 = %.3g",
        dt, cfg.boolean("fluid.adaptive_dt") ? " (first; adaptive)" : "", h, u, possible * dt,
        least.c_str(), cflMax, nu * dt / (h * h));
    if (mode == RunMode::Coupled || mode == RunMode::DummyDem)
      std::printf(", %.0f DEM sub-steps a CFD step", dt / demDt);
    std::printf("\n");
    // The run stops at the first step whose CFL exceeds fluid.cfl_max (the first step is
    // fluid.dt even with fluid.adaptive_dt): a case whose inlet alone exceeds it is not valid;
    // one that may exceed it (inside a bed, from the initial velocity) is warned of.
    const bool bySubsteps = (mode == RunMode::Coupled || mode == RunMode::DummyDem) && sub > 0;
    const char* lower = bySubsteps ? "coupling.dem_substeps or particles.dt" : "fluid.dt";
    if (sure * dt > cflMax) {
      cflKey = bySubsteps ? "coupling.dem_substeps" : "fluid.dt";
      cflError = fmt::format(
          "the CFL of the first step would be at least {:.3g} (step {:g} s, an inlet's velocity), "
          "above fluid.cfl_max = {:g}: the run would stop in its first step; lower {}{}",
          sure * dt, dt, cflMax, lower,
          bySubsteps ? "" : " (fluid.adaptive_dt then keeps the later steps below it)");
    } else if (possible * dt > cflMax) {
      std::printf(
          "coloc check: warning: the CFL estimate exceeds fluid.cfl_max: the run may stop at its "
          "first steps (lower %s, or use fluid.adaptive_dt)\n",
          lower);
    }
  }
  for (const auto& n : notes) std::printf("coloc: note: %s\n", n.c_str());

  const Plan* chosen = nullptr;
  for (const Plan& p : plans)
    if (p.strategy == strategy) chosen = &p;
  if (chosen && !chosen->error.empty()) {
    std::fprintf(stderr, "coloc: error: %s\n", chosen->error.c_str());
    return 2;
  }
  if (!cflKey.empty()) throw ConfigError(cflKey, cflError);  // after the whole picture
  std::printf("coloc check: the case is valid for %d rank(s); nothing was run\n", N);
  return 0;
}

std::string describeKeys(const std::string& prefix) {
  const std::string all = describeKeys();
  if (prefix.empty()) return all;
  // Blocks: a line "  path  (kind...)" and its help lines (indented further).
  std::istringstream in(all);
  std::string line, out, block, path;
  auto flush = [&] {
    const bool match = path == prefix || path.rfind(prefix + ".", 0) == 0 ||
                       path.rfind(prefix + "[", 0) == 0 || path.rfind(prefix + "{", 0) == 0;
    if (!block.empty() && match) out += block;
    block.clear();
  };
  std::getline(in, line);  // the title
  while (std::getline(in, line)) {
    if (line.size() > 2 && line[0] == ' ' && line[1] == ' ' && line[2] != ' ') {
      flush();
      path = line.substr(2, line.find(' ', 2) - 2);
    }
    block += line + "\n";
  }
  flush();
  if (out.empty())
    throw ConfigError(prefix, "no case-file key starts with this (coloc keys lists them all)");
  return out;
}

}  // namespace coloc
