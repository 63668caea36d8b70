// The "coupling.*" keys and the schema of a whole case file (declared in simulation.hpp).
#include "coloc/coupling/simulation.hpp"
#include "coloc/partition/setup.hpp"

namespace coloc::coupling {

void declareConfig(Schema& s) {
  s.string("coupling.kernel", "trilinear",
           "deposition/interpolation kernel: centroid (PCM) or trilinear (cloud-in-cell)",
           {"centroid", "trilinear"});
  s.string("coupling.drag", "difelice", "drag law: stokes, difelice, gidaspow, beetstra",
           {"stokes", "difelice", "gidaspow", "beetstra"});
  s.number("coupling.eps_min", 0.3, "lower clip of the fluid fraction",
           Range::openClosed(0.0, 1.0));
  s.integer("coupling.smoothing_passes", 0,
            "passes of a conservative diffusion filter (alpha 1/8) on the deposited fields and, "
            "adjointly, on the fields sampled at the particles (0: off)",
            Range::between(0, 1000));
  s.string("coupling.self_velocity", "none",
           "correction of the self-induced velocity (the particle's own drag reaction in the fluid "
           "it samples): none, or stokeslet (the undisturbed flow of Balachandar, Liu & Lakhote "
           "2019 with this solver's discrete response to the trilinear deposit and its implicit "
           "drag, built up since the run's start; the drag law also sees the fluid fraction "
           "without the particle's own volume and the pressure-gradient force loses the "
           "particle's own share; trilinear kernel, no smoothing, cubic cells; docs/coupling.md)",
           {"none", "stokeslet"});
  s.string("coupling.heat_transfer", "none",
           "fluid-particle convection (needs fluid.heat and particles.heat): none, ranz_marshall "
           "(a single sphere), gunn (beds, Gunn 1978); q = Nu k_f pi d (T_f - T_p) into each "
           "particle, the opposite into the fluid cells of its stencil (docs/heat.md)",
           {"none", "ranz_marshall", "gunn"});
  s.integer("coupling.dem_substeps", 0,
            "DEM steps per step. coupled, dummy_dem: the CFD step is dem_substeps * particles.dt "
            "(fluid.dt and fluid.adaptive_dt are then not used); 0: the largest whole number of "
            "particles.dt in the fluid's step (fluid.dt, or the adaptive step), at least 1. "
            "particles mode: each step is max(1, dem_substeps) DEM steps (0 means one) and "
            "fluid.dt is ignored",
            Range::between(0, 1e6));
}

Schema caseSchema() {
  Schema s;
  declareRunConfig(s);
  declareDomainConfig(s);
  fv::declareConfig(s);
  dem::declareConfig(s);
  declareConfig(s);
  declareOutputConfig(s);
  return s;
}

}  // namespace coloc::coupling
