// coupling/src/particle_coupling.hpp — the coupling physics at the particles (private to
// coloc_coupling; Simulation sequences it).
//
// One object holds what the coupling computes per particle in a step and the parameters of
// that physics (coupling.kernel, coupling.drag, coupling.self_velocity, coupling.eps_min,
// fluid.rho, fluid.nu): the stencils, the sampled fields, the drag law and the particles'
// implicit response to it, the deposits, and the coupling force. The fluid's fields and the
// halo work stay with the Simulation, which calls these in the order of the step:
//
//   locate()          stencils and volumes of the particles of the view
//   evaluateDrag()    range by range: the 7 drag fields sampled, beta from the law, the response;
//                     with convection each particle's exchange coefficient H'
//   deposit()         V_p, beta', beta' v~ -> solid, K, K u_p (one pass over the stencils), and
//                     with convection H' T_p -> the fluid's heat source, H' -> its coefficient
//   sampleForForces() u^{n+1}, grad p^{n+1} (and with convection the step's mean fluid
//                     temperature) at the particles (one pass)
//   applyForces()     F = beta' (u - v~) - V_p rho_f grad p (+ the self-velocity share)
//   applyHeat()       q of each particle to the DEM's heat_ext (convection)
//
// Convection (coupling.heat_transfer, heat_transfer.hpp), semi-implicit as the drag:
// H = Nu k_f pi d and H' = H / (1 + dt H / (m c_p)), the particle's backward-Euler response over
// the step (as beta' for the drag: a particle whose thermal time is shorter than the step relaxes
// to the fluid's temperature without overshoot). The fluid takes sum H' T_p and sum H' per cell
// and treats the exchange implicitly in its own temperature (fv::CouplingInputs); each particle
// then receives q = H' (Tmean(x_p) - T_p), Tmean the mean fluid temperature of the step's heat
// sub-steps sampled with the same stencil: by the adjointness of deposit and interpolation the
// heat the particles gain is the heat the fluid loses, to round-off.
// The response (simulation.hpp's header comment): beta' = beta / (1 + dt beta / m) and
// v~ = v + dt (f_nondrag - V_p rho_f grad p) / m, written once (responseDenominator(),
// velocityWithoutDrag()) and used both by the array-at-a-time common case and by the
// particle-at-a-time one (self-velocity correction, particles that cannot move).
#pragma once

#include <array>
#include <cstddef>
#include <string>
#include <vector>

#include "coloc/core/config.hpp"
#include "coloc/core/timers.hpp"
#include "coloc/coupling/drag.hpp"
#include "coloc/coupling/heat_transfer.hpp"
#include "coloc/coupling/kernel.hpp"
#include "coloc/coupling/self_velocity.hpp"
#include "coloc/coupling/transfer.hpp"
#include "coloc/partition/decomposition.hpp"
#include "coloc/partition/field.hpp"

namespace coloc::coupling {

class ParticleCoupling {
 public:
  /// The 7 fields the drag samples: eps, u (3), grad p (3).
  using DragFields = std::array<const CellField*, 7>;
  /// The fields the forces sample: u (3), grad p (3), and with convection Tmean (the 7th).
  using ForceFields = std::array<const CellField*, 7>;

  ParticleCoupling() = default;
  /// The coupling.* keys of `cfg`; `frozen`: the particles cannot move (run.mode dummy_dem).
  ParticleCoupling(const Config& cfg, const Decomposition& dec, Timers& timers, bool frozen);

  KernelKind kernel() const { return kernel_; }
  DragLaw dragLaw() const { return drag_; }
  double fluidDensity() const { return rhoF_; }
  double minFluidFraction() const { return epsMin_; }
  /// With fluid-particle convection (coupling.heat_transfer other than none).
  bool convects() const { return heatLaw_ != HeatLaw::None; }
  HeatLaw heatLaw() const { return heatLaw_; }
  /// The largest Biot number h d / (6 k_p) of the particles of the last evaluateDrag (0 without
  /// convection): lumped capacitance holds well below 0.1.
  double biotMax() const { return biotMax_; }
  std::size_t count() const { return stencils_.count(); }

  /// The stencils of the particles of `view` on fields of `layout`, and their volumes.
  /// Collective: a particle more than one cell outside its block is an error on every rank.
  void locate(const ParticleView& view, const FieldLayout& layout);
  /// Range by range (kSampleChunk particles): the fields sampled at them (none at set-up:
  /// fields null), then the drag law and each particle's response over dt. `time`: the run's
  /// time at the start of the step (the self-velocity correction's age of the flow).
  /// Collective with coupling.self_velocity (a particle too large for the model).
  void evaluateDrag(const DragFields* fields, double dt, double time);
  /// solid += V_p / V_cell, K += beta' / (rho_f V_cell), K u_p += beta' v~ / (rho_f V_cell) in
  /// one pass over the stencils (the fields as they are: the caller zeroes them); with
  /// convection in the same pass heatSource += H' T_p (W) and heatCoefficient += H' (W/K).
  void deposit(CellField& solid, CellField& K, const std::array<CellField*, 3>& KUp,
               CellField* heatSource = nullptr, CellField* heatCoefficient = nullptr) const;
  /// u^{n+1}, grad p^{n+1} (and Tmean with convection) at the particles.
  void sampleForForces(const ForceFields& fields);
  /// The coupling force of each particle into out[d][i]; adds to sums[d] the particles' drag
  /// impulse over dt and to sums[6 + d] the gross exchanged momentum sum beta' (|u| + |v~|) dt.
  void applyForces(const std::array<double*, 3>& out, double dt, double sums[9]) const;
  /// Convection: the heat rate q = H' (Tmean - T_p) of each particle into out[i] (W); adds to
  /// sums[0] the heat the particles receive over dt and to sums[1] the gross sum H' (|Tmean| +
  /// |T_p|) dt (the scale of the round-off of the two sides' sums), and to sums[2] the heat
  /// exchanged, sum |q| dt.
  void applyHeat(double* out, double dt, double sums[3]) const;

 private:
  /// beta' = beta / responseDenominator(): the implicit response over dt of a particle of mass m.
  static double responseDenominator(double beta, double dt, double m) {
    return 1.0 + dt * beta / m;
  }
  /// v~ = v + dt a: the velocity the particle would reach without drag, a its non-drag
  /// acceleration (contacts and gravity, and the pressure-gradient force -V rho_f grad p).
  double velocityWithoutDrag(double v, double nonDrag, double volume, double gradP, double dt,
                             double m) const {
    return v + dt * (nonDrag - volume * rhoF_ * gradP) / m;
  }
  void resize(std::size_t n);
  /// Convection on particles first .. first + count - 1: H' from the sampled fields (`sampled`
  /// false, at set-up: none, H' = 0).
  void exchangeHeatOn(std::size_t first, std::size_t count, double dt, bool sampled);
  /// The drag on particles first .. first + count - 1.
  void evaluateDragOn(std::size_t first, std::size_t count, double dt, double time);
  /// Particle i's implicit response to its drag coefficient beta (the law's value at eps, slip);
  /// `still`: it cannot move (frozen particles, or dt <= 0); `self`: with the correction.
  void respondToDrag(std::size_t i, double eps, double slip, double beta, double dt, double time,
                     bool still, bool self);
  /// coupling.self_velocity: beta re-evaluated at the undisturbed slip and fluid fraction
  /// epsUndisturbed; returns 1 + dt beta / m - c beta (self_velocity.hpp; dt = 0 for particles
  /// that cannot move), c at tRun after the run's start in fluid of fraction epsFluid; pressure:
  /// the particle's own pressure-gradient response (SelfResponse). A particle too large for the
  /// model is noted in failure_.
  double correctForSelfVelocity(std::size_t i, double epsFluid, double epsUndisturbed,
                                double slipSampled, double dt, double tRun, double& beta,
                                std::array<double, 3>& pressure);

  const Decomposition* dec_ = nullptr;
  Timers* timers_ = nullptr;
  KernelKind kernel_ = KernelKind::Trilinear;
  DragLaw drag_ = DragLaw::DiFelice;
  SelfVelocity selfVelocity_ = SelfVelocity::None;
  bool frozen_ = false;
  double epsMin_ = 0.3, rhoF_ = 1.0, nu_ = 1e-6;
  // The first particle the drag evaluation of this step could not treat (empty: none), raised
  // on every rank at the end of evaluateDrag.
  std::string failure_;
  // Convection: the law, the fluid's conductivity k_f and Pr^(1/3), the materials' heat
  // capacities and conductivities.
  HeatLaw heatLaw_ = HeatLaw::None;
  double kF_ = 0, prandtl3_ = 1, biotMax_ = 0;
  std::vector<double> cpOfMaterial_, kOfMaterial_;

  // The particles of the view (grow-only buffers): 15 doubles and a compact stencil a particle.
  ParticleView view_;
  Stencils stencils_;
  std::vector<double> volume_, beta_, epsAt_;
  std::vector<double> TAt_, hEff_;  // convection: Tmean at the particle, H'
  std::array<std::vector<double>, 3> uAt_, vDep_, gradPAt_;
  /// coupling.self_velocity: V k_d per particle, its own pressure-gradient force per unit drag
  /// (SelfResponse::pressure), from evaluateDrag to applyForces of the same step.
  std::array<std::vector<double>, 3> ownPressure_;
  /// evaluateDragOn's chunk of particles: the law's inputs eps, d, slip and its output beta.
  static constexpr std::size_t kDragChunk = 256;
  /// evaluateDrag's range (a multiple of kDragChunk): its 7 sampled values a particle
  /// (229 KB) stay in cache until the drag reads them; large enough that the timers of the
  /// nested phase cost little (~60 ranges for 250,000 particles).
  static constexpr std::size_t kSampleChunk = 4096;
  std::array<std::array<double, kDragChunk>, 4> dragChunk_{};
};

}  // namespace coloc::coupling
