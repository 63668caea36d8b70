// fv/src/params.hpp — the fluid's case-file keys, parsed once into typed values (private).
//
// fluidParams() reads every "fluid.*" key the solver uses (and gravity) when the solver is built;
// the step reads only these members, never a key.
#pragma once

#include "boundary.hpp"
#include "coloc/core/config.hpp"
#include "coloc/partition/decomposition.hpp"
#include "momentum.hpp"
#include "pressure_solver.hpp"

namespace coloc::fv {

/// fluid.heat and its material keys.
struct HeatParams {
  bool on = false;          // fluid.heat
  double rho = 0;           // fluid.rho (kg/m^3)
  double conductivity = 0;  // fluid.conductivity k_f (W/(m K))
  double capacity = 0;      // fluid.heat_capacity c_f (J/(kg K))
  double initial = 0;       // fluid.initial_temperature (K)
};

/// fluid.pressure.setup_interval, setup_iteration_growth (docs/fv.md, "Pressure set-up reuse").
struct SetupReuse {
  long long interval = 1;  // the most operators one set-up serves (1: every one)
  double growth = 1.5;     // a solve above growth x the set-up's first solve asks for a new one
  bool on() const { return interval > 1; }
};

/// The most sub-steps of the explicit energy update in one fluid step (fv/src/heat.cpp).
inline constexpr long long kMaxHeatSubsteps = 100000;

struct FluidParams {
  double nu = 0;          // fluid.nu (m^2/s)
  double dtFixed = 0;     // fluid.dt (s): the step, or the largest adaptive step
  bool adaptive = false;  // fluid.adaptive_dt
  double cfl = 0;         // fluid.cfl: target of the adaptive step
  double cflMax = 0;      // fluid.cfl_max: hard limit (error)
  double steadyTol = 0;   // fluid.steady_tol
  bool ab2 = true;        // fluid.time_scheme == ab2
  Real3 g{0, 0, 0};       // gravity + fluid.body_force (m/s^2)
  Real3 initialVelocity{0, 0, 0};
  Convection convection = Convection::VanLeer;  // fluid.convection, fluid.limiter
  PressureSolver::Options pressure;             // fluid.pressure.* but initial_guess
  bool warmStart = true;                        // fluid.pressure.initial_guess == previous
  SetupReuse reuse;                             // fluid.pressure.setup_*
  BoxBc bc;                                     // fluid.boundary.*, fluid.patches
  HeatParams heat;                              // fluid.heat, conductivity, heat_capacity, ...
};

/// Reads and checks the keys (ConfigError naming the key).
FluidParams fluidParams(const Config& cfg, const GlobalGrid& grid);

}  // namespace coloc::fv
