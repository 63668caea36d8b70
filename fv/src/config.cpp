// The "fluid.*" keys of the case file (see docs/fv.md for the meaning of each choice), and their
// typed values (params.hpp).
#include <fmt/format.h>

#include <cmath>

#include "coloc/fv/fluid.hpp"
#include "params.hpp"

namespace coloc::fv {

namespace {
/// A temperature (K): not below absolute zero, and below what any enthalpy sum of a run holds
/// with round-off to spare (1e6 K: hotter than any material stays solid or liquid).
const Range kTemperatureRange = Range::between(0.0, 1e6);

/// The thermal key of a boundary type (fluid.heat): optional, absent means "none given" (an
/// adiabatic wall; an inlet then needs it), never a sentinel value.
void temperatureKey(Schema& s, const char* help) {
  s.optionalNumber("temperature", help, kTemperatureRange);
}

std::map<std::string, Schema> boundaryTypes() {
  std::map<std::string, Schema> t;
  t["periodic"] = Schema();
  Schema inlet;
  inlet.vec3("velocity", std::nullopt, "inlet velocity vector (m/s)");
  inlet.boolean("superficial", false,
                "the normal velocity is superficial (volume flux per area): the face gets "
                "U / eps of the adjacent cell, e.g. a fluidised bed resting on the inlet; "
                "false: Dirichlet on the interstitial velocity u (docs/fv.md)");
  temperatureKey(inlet,
                 "fluid.heat: temperature of the inflow (K), also the face's value for "
                 "conduction; required with fluid.heat = true");
  t["inlet"] = inlet;
  Schema outlet;
  outlet.number("pressure", 0.0, "outlet kinematic pressure p/rho_f (m^2/s^2)");
  t["outlet"] = outlet;  // thermal: zero gradient, the outflow carries its enthalpy out
  Schema wall;
  wall.vec3("velocity", std::array<double, 3>{0, 0, 0},
            "tangential wall velocity (m/s), e.g. a moving lid; the normal component must be 0");
  temperatureKey(wall, "fluid.heat: fixed wall temperature (K); absent: adiabatic wall");
  t["wall"] = wall;
  Schema slip;
  temperatureKey(slip, "fluid.heat: fixed face temperature (K); absent: adiabatic");
  t["slip"] = slip;
  Schema autoType;
  temperatureKey(autoType,
                 "fluid.heat: on a wall (a non-periodic axis) its fixed temperature (K); "
                 "absent: adiabatic");
  t["auto"] = autoType;
  return t;
}
}  // namespace

namespace {
/// fluid.heat: the explicit energy update takes at least dt k_f / (rho_f c_f) sum_d 2 / h_d^2
/// sub-steps a fluid step for the conduction alone (a cell of fluid, eps = 1); more than the
/// solver's bound is refused here, naming the conductivity, instead of at the first step.
void checkHeatSubsteps(const FluidParams& p, const GlobalGrid& grid) {
  const HeatParams& h = p.heat;
  double perH2 = 0;
  for (int d = 0; d < 3; ++d) {
    const double hd = grid.length[d] / grid.cells[d];
    perH2 += 2.0 / (hd * hd);
  }
  const double alpha = h.conductivity / (h.rho * h.capacity);
  const double need = std::ceil(p.dtFixed * alpha * perH2);
  if (!(need <= static_cast<double>(kMaxHeatSubsteps)))
    throw ConfigError(
        "fluid.conductivity",
        fmt::format("{:g} W/(m K) with fluid.heat_capacity = {:g} J/(kg K) and fluid.rho = {:g} "
                    "kg/m^3 is a thermal diffusivity of {:.3g} m^2/s: the explicit energy update "
                    "would need {:.3g} sub-steps of fluid.dt = {:g} s on these cells (at most {}); "
                    "check the conductivity's units, or reduce fluid.dt",
                    h.conductivity, h.capacity, h.rho, alpha, need, p.dtFixed, kMaxHeatSubsteps));
}
}  // namespace

void declareConfig(Schema& s) {
  s.number("fluid.nu", 1.0e-6, "kinematic viscosity (m^2/s)", Range::positive());
  s.number("fluid.rho", 1000.0, "fluid density (kg/m^3)", Range::positive());
  s.vec3("fluid.body_force", std::array<double, 3>{0, 0, 0},
         "body acceleration on the fluid (m/s^2), added to the top-level gravity; e.g. the "
         "driving pressure gradient of a periodic channel");
  s.vec3("fluid.initial_velocity", std::array<double, 3>{0, 0, 0}, "initial velocity (m/s)");
  const char* faces[6] = {"xlo", "xhi", "ylo", "yhi", "zlo", "zhi"};
  for (const char* f : faces)
    s.variant(std::string("fluid.boundary.") + f, boundaryTypes(), "auto",
              std::string("condition on the ") + f +
                  " face: auto (periodic on a periodic axis, else no-slip wall), periodic, "
                  "inlet{velocity, superficial, temperature}, outlet{pressure}, "
                  "wall{velocity, temperature}, slip{temperature}; with fluid.heat a wall or "
                  "slip face without temperature is adiabatic, an outlet zero-gradient");
  {
    // Patches: a rectangle of a face with its own condition (the rest keeps the face's).
    std::map<std::string, Schema> patch;
    for (auto& [type, schema] : boundaryTypes()) {
      if (type == "auto" || type == "periodic") continue;
      Schema p = schema;
      p.string("face", std::nullopt, "the face: xlo, xhi, ylo, yhi, zlo, zhi",
               {"xlo", "xhi", "ylo", "yhi", "zlo", "zhi"});
      p.numberList("min", std::nullopt,
                   "lower corner (m) on the face's two tangential axes in axis order (xlo/xhi: "
                   "y, z; ylo/yhi: x, z; zlo/zhi: x, y)");
      p.numberList("max", std::nullopt, "upper corner (m), same axes as min");
      patch[type] = p;
    }
    s.list("fluid.patches", patch,
           "rectangles of a box face with their own condition: {type: inlet|outlet|wall|slip, "
           "face, min: [a, b], max: [a, b], and the type's keys (velocity, superficial, "
           "pressure, temperature)}; a cell next to the face belongs to the last patch containing "
           "its face "
           "centre, the rest of the face keeps fluid.boundary.<face>");
  }
  s.number("fluid.dt", 1.0e-3,
           "fluid time step (s); with fluid.adaptive_dt the first and the largest step. "
           "coupled, dummy_dem: rounded down to a whole number of particles.dt (at least one), "
           "not used when coupling.dem_substeps > 0; ignored in particles mode",
           Range::positive());
  s.boolean("fluid.adaptive_dt", false,
            "adapt dt to fluid.cfl and the explicit-viscous limit every step (coupled: only "
            "with coupling.dem_substeps = 0, then rounded down to a multiple of particles.dt)");
  s.number("fluid.cfl", 0.5, "target convective CFL number of the adaptive step",
           Range::openClosed(0.0, 10.0));
  s.number("fluid.cfl_max", 1.0,
           "hard limit: a step whose CFL exceeds it stops the run with an error",
           Range::positive());
  s.string("fluid.convection", "tvd",
           "convection of the eps-weighted momentum: central (2nd order) or tvd (bounded, "
           "limiter fluid.limiter)",
           {"central", "tvd"});
  s.string("fluid.limiter", "van_leer", "TVD limiter", {"van_leer", "minmod"});
  s.string("fluid.time_scheme", "ab2",
           "explicit terms: ab2 (Adams-Bashforth 2, variable step) or euler (1st order)",
           {"ab2", "euler"});
  s.string("fluid.pressure.solver", "pfmg",
           "hypre Struct multigrid: PCG's preconditioner (or alone with fluid.pressure.krylov = "
           "none)",
           {"pfmg", "smg"});
  s.number("fluid.pressure.tol", 1.0e-8,
           "PCG stops when ||r||_2 <= tol * max(||b||_2, ||s||_2), s the per-cell flux scale "
           "sum_f |eps_f u*_f|/h + |d eps/dt| (the divergence left is below tol of the fluxes "
           "through the cells)",
           Range::openClosed(0.0, 1.0));
  s.integer("fluid.pressure.max_iter", 200,
            "iteration cap: PCG iterations, or multigrid cycles with fluid.pressure.krylov = none",
            Range::between(1, 1e6));
  s.string("fluid.pressure.on_no_convergence", "warn",
           "a pressure solve that stops at max_iter above its tolerance: warn (a warning on the "
           "first, counted in report.json fluid.unconverged_solves) or error (the run stops, "
           "status 3)",
           {"warn", "error"});
  s.string("fluid.pressure.krylov", "pcg",
           "pcg: PCG preconditioned by one multigrid cycle; none: the multigrid cycle alone, "
           "repeated until the same stopping test (docs/fv.md, pressure solver options)",
           {"pcg", "none"});
  s.string("fluid.pressure.initial_guess", "previous",
           "the solve starts from the previous step's pressure (previous; it is in the "
           "checkpoint) or from zero",
           {"previous", "zero"});
  s.integer("fluid.pressure.pre_sweeps", 1,
            "smoothing sweeps before the coarse-grid correction, per level and cycle (PFMG, SMG)",
            Range::between(0, 10));
  s.integer("fluid.pressure.post_sweeps", 1,
            "smoothing sweeps after the coarse-grid correction, per level and cycle (PFMG, "
            "SMG); pre_sweeps + post_sweeps >= 1, and equal for a symmetric PCG preconditioner",
            Range::between(0, 10));
  s.string("fluid.pressure.pfmg.relax", "rbgs",
           "PFMG smoother: rbgs (red-black Gauss-Seidel, black-red after the correction: "
           "symmetric), weighted_jacobi (weight per level from the grid spacings: fewer, cheaper "
           "iterations but a 2.4x set-up, for a matrix set up once, e.g. fluid-only runs), "
           "jacobi, rbgs_nonsymmetric (red-black both times: not symmetric, for krylov = none)",
           {"jacobi", "weighted_jacobi", "rbgs", "rbgs_nonsymmetric"});
  s.string("fluid.pressure.pfmg.rap", "galerkin",
           "PFMG coarse operators: galerkin (R A P; 7-point stencils grow to 15/19 points) or "
           "non_galerkin (7-point stencils on every level, averaged coefficients)",
           {"galerkin", "non_galerkin"});
  s.boolean("fluid.pressure.pfmg.skip_relax", true,
            "PFMG smooths the finest level and then only where its coarsening (one axis a "
            "level) returns to an axis it already halved: one level in three on cubic cells "
            "(hypre's skip_relax, for isotropic problems); false: every level");
  s.integer("fluid.pressure.setup_interval", 20,
            "the most pressure operators one multigrid set-up serves: the hierarchy set up on one "
            "step's operator preconditions the next steps' (their own finest level, the old "
            "coarse levels) until this many, or until a solve needs more iterations than "
            "setup_iteration_growth allows; 1: a set-up whenever eps, K or dt change (docs/fv.md, "
            "pressure set-up reuse)",
            Range::between(1, 1e9));
  s.number("fluid.pressure.setup_iteration_growth", 1.5,
           "a new set-up before the next operator when a solve needed more than this times the "
           "iterations of the first solve on the set-up (and at least one more)",
           Range::between(1.0, 1e9));
  s.boolean("fluid.heat", false,
            "solve the fluid energy equation (docs/heat.md): needs fluid.conductivity, "
            "fluid.heat_capacity, fluid.initial_temperature and an inlet temperature per inlet; "
            "off: no temperature at all");
  // Optional keys (no default, no sentinel): required with fluid.heat.
  // Bounded far above any real material (diamond conducts ~2e3 W/(m K); hydrogen holds
  // ~1.4e4 J/(kg K)), so that no value makes the run's numbers overflow.
  s.optionalNumber("fluid.conductivity",
                   "fluid.heat: thermal conductivity k_f (W/(m K)); required with fluid.heat",
                   Range::between(0.0, 1e6));
  s.optionalNumber("fluid.heat_capacity",
                   "fluid.heat: specific heat capacity c_f (J/(kg K)); required with fluid.heat",
                   Range::openClosed(0.0, 1e8));
  s.optionalNumber("fluid.initial_temperature",
                   "fluid.heat: initial fluid temperature (K); required with fluid.heat",
                   kTemperatureRange);
  s.number("fluid.steady_tol", 0.0,
           "steady-state stop: max|u^{n+1}-u^n| / max|u| below this ends a fluid-only run (0: off)",
           Range::nonNegative());
}

FluidParams fluidParams(const Config& cfg, const GlobalGrid& grid) {
  FluidParams p;
  p.nu = cfg.number("fluid.nu");
  p.dtFixed = cfg.number("fluid.dt");
  p.adaptive = cfg.boolean("fluid.adaptive_dt");
  p.cfl = cfg.number("fluid.cfl");
  p.cflMax = cfg.number("fluid.cfl_max");
  p.steadyTol = cfg.number("fluid.steady_tol");
  p.ab2 = cfg.string("fluid.time_scheme") == "ab2";
  const auto gr = cfg.vec3("gravity");
  const auto bf = cfg.vec3("fluid.body_force");
  for (int a = 0; a < 3; ++a) p.g[a] = gr[a] + bf[a];
  const auto u0 = cfg.vec3("fluid.initial_velocity");
  for (int a = 0; a < 3; ++a) p.initialVelocity[a] = u0[a];
  p.convection = cfg.string("fluid.convection") == "central" ? Convection::Central
                 : cfg.string("fluid.limiter") == "minmod"   ? Convection::Minmod
                                                             : Convection::VanLeer;
  auto& o = p.pressure;
  o.kind = cfg.string("fluid.pressure.solver") == "smg" ? PressureSolver::Kind::Smg
                                                        : PressureSolver::Kind::Pfmg;
  o.tol = cfg.number("fluid.pressure.tol");
  o.maxIter = static_cast<int>(cfg.integer("fluid.pressure.max_iter"));
  o.pcg = cfg.string("fluid.pressure.krylov") == "pcg";
  o.errorOnNoConvergence = cfg.string("fluid.pressure.on_no_convergence") == "error";
  o.preSweeps = static_cast<int>(cfg.integer("fluid.pressure.pre_sweeps"));
  o.postSweeps = static_cast<int>(cfg.integer("fluid.pressure.post_sweeps"));
  if (o.preSweeps + o.postSweeps == 0)
    throw ConfigError("fluid.pressure.post_sweeps",
                      "fluid.pressure.pre_sweeps and post_sweeps are both 0: the multigrid cycle "
                      "would not smooth at all");
  const std::string relax = cfg.string("fluid.pressure.pfmg.relax");
  o.relax = relax == "jacobi"            ? PressureSolver::Relax::Jacobi
            : relax == "weighted_jacobi" ? PressureSolver::Relax::WeightedJacobi
            : relax == "rbgs"            ? PressureSolver::Relax::RbgsSymmetric
                                         : PressureSolver::Relax::RbgsNonsymmetric;
  o.rap = cfg.string("fluid.pressure.pfmg.rap") == "galerkin" ? PressureSolver::Rap::Galerkin
                                                              : PressureSolver::Rap::NonGalerkin;
  o.skipRelax = cfg.boolean("fluid.pressure.pfmg.skip_relax");
  p.reuse.interval = cfg.integer("fluid.pressure.setup_interval");
  p.reuse.growth = cfg.number("fluid.pressure.setup_iteration_growth");
  p.warmStart = cfg.string("fluid.pressure.initial_guess") == "previous";
  p.bc = boundaryFromConfig(cfg, grid);
  auto& h = p.heat;
  h.on = cfg.boolean("fluid.heat");
  h.rho = cfg.number("fluid.rho");
  const auto k = cfg.optionalNumber("fluid.conductivity");
  const auto c = cfg.optionalNumber("fluid.heat_capacity");
  const auto t0 = cfg.optionalNumber("fluid.initial_temperature");
  if (h.on) {
    if (!k)
      throw ConfigError("fluid.conductivity",
                        "fluid.heat = true needs the fluid's thermal conductivity (W/(m K), >= 0)");
    if (!c)
      throw ConfigError("fluid.heat_capacity",
                        "fluid.heat = true needs the fluid's heat capacity (J/(kg K), > 0)");
    if (!t0)
      throw ConfigError("fluid.initial_temperature",
                        "fluid.heat = true needs the initial fluid temperature (K, > 0)");
    h.conductivity = *k;
    h.capacity = *c;
    h.initial = *t0;
    checkHeatSubsteps(p, grid);
  }
  return p;
}

}  // namespace coloc::fv
