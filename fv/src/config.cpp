// The "fluid.*" keys of the case file (see docs/fv.md for the meaning of each choice), and their
// typed values (params.hpp).
#include "coloc/fv/fluid.hpp"
#include "params.hpp"

namespace coloc::fv {

namespace {
std::map<std::string, Schema> boundaryTypes() {
  std::map<std::string, Schema> t;
  t["auto"] = Schema();
  t["periodic"] = Schema();
  Schema inlet;
  inlet.vec3("velocity", std::nullopt, "inlet velocity vector (m/s)");
  inlet.boolean("superficial", false,
                "the normal velocity is superficial (volume flux per area): the face gets "
                "U / eps of the adjacent cell, e.g. a fluidised bed resting on the inlet; "
                "false: Dirichlet on the interstitial velocity u (docs/fv.md)");
  t["inlet"] = inlet;
  Schema outlet;
  outlet.number("pressure", 0.0, "outlet kinematic pressure p/rho_f (m^2/s^2)");
  t["outlet"] = outlet;
  Schema wall;
  wall.vec3("velocity", std::array<double, 3>{0, 0, 0},
            "tangential wall velocity (m/s), e.g. a moving lid; the normal component must be 0");
  t["wall"] = wall;
  t["slip"] = Schema();
  return t;
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
                  "inlet{velocity}, outlet{pressure}, wall{velocity}, slip");
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
           "pressure)}; a cell next to the face belongs to the last patch containing its face "
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
  s.string("fluid.pressure.solver", "pfmg", "preconditioner of hypre Struct PCG", {"pfmg", "smg"});
  s.number("fluid.pressure.tol", 1.0e-8,
           "PCG stops when ||r||_2 <= tol * max(||b||_2, ||s||_2), s the per-cell flux scale "
           "sum_f |eps_f u*_f|/h + |d eps/dt| (the divergence left is below tol of the fluxes "
           "through the cells)",
           Range::openClosed(0.0, 1.0));
  s.integer("fluid.pressure.max_iter", 200, "PCG iteration cap", Range::atLeast(1));
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
  p.solver = cfg.string("fluid.pressure.solver") == "smg" ? PressureSolver::Kind::Smg
                                                          : PressureSolver::Kind::Pfmg;
  p.pressureTol = cfg.number("fluid.pressure.tol");
  p.pressureMaxIter = static_cast<int>(cfg.integer("fluid.pressure.max_iter"));
  p.bc = boundaryFromConfig(cfg, grid);
  return p;
}

}  // namespace coloc::fv
