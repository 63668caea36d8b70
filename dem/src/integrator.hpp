// dem/src/integrator.hpp — the velocity Verlet integration of the owned particles as a part (as
// LAMMPS's fix nve/sphere): the half kick and drift before the forces (initialIntegrate), the
// half kick after them (finalIntegrate). It holds the time step and gravity and works on the
// particles and the force part passed to each call (integrator.cpp).
#pragma once

#include "coloc/dem/dem.hpp"
#include "contact_forces.hpp"

namespace coloc::dem::detail {

class Integrator {
 public:
  double dt = 1e-5;
  double g[3] = {0, 0, 0};

  /// v += dt/2 F/m, x += dt v, omega += dt/2 T/I. While the force part's bodies match the
  /// particles (ContactForces::packed), also the first part of the next force computation: the
  /// owned bodies written and the force and torque sums reset to gravity + fExt. Returns the
  /// largest |v|^2 of the drift (NaN and inf: the largest double), 0 without particles.
  double initialIntegrate(ParticleStore& p, ContactForces& forces) const;
  /// v += dt/2 F/m, omega += dt/2 T/I.
  void finalIntegrate(ParticleStore& p) const;
};

}  // namespace coloc::dem::detail
