// diagnostics.hpp — what a fluidised-bed or suspension user looks at first, from the state of a
// run: pressure drops, bed height, particle speeds, contacts, the solid fraction profile
// (docs/output.md, "Bed and suspension diagnostics"). Collective over the run's ranks; the
// values do not depend on the decomposition except for the order of floating-point sums.
#pragma once

#include <array>
#include <string>
#include <vector>

#include "coloc/core/config.hpp"
#include "coloc/coupling/simulation.hpp"

namespace coloc {

struct BedDiagnostics {
  // Vertical axis: the axis of gravity (the longest axis without gravity); heights are measured
  // from the bottom of the box (against gravity).
  int axis = 2;
  long long particles = 0;
  double bedHeight = 0;       // 95th percentile (nearest rank) of particle-centre heights (m)
  double lowestParticle = 0;  // the lowest particle centre (m)
  double meanSpeed = 0, maxSpeed = 0;  // |v| of the particles (m/s)
  double contactsPerParticle = 0;      // particle-particle contacts per particle (coordination)
  // rho_f (p_bottom - p_top) of plane-averaged p (kinematic p times fluid.rho), in Pa:
  double dpBox = 0;  // between the lowest and the highest layer of cell centres
  double dpBed = 0;  // between the layers holding lowestParticle and bedHeight
  // The same less the hydrostatic part rho_f a dz of the fluid's body acceleration a (gravity +
  // fluid.body_force) along the axis: what the particles hold up (compare with bedWeight).
  double dpBoxExcess = 0, dpBedExcess = 0;
  double bedWeight = 0;  // buoyant weight of the particles per box cross-section (Pa)
  // Solid fraction per layer of cells along the axis: volume of the particles whose centres lie
  // in the layer / the layer's volume (bottom layer first).
  std::vector<double> solidProfile;
  double solidMax = 0;      // the largest layer value
  double solidBedMean = 0;  // mean over the layers from the bottom up to the one of bedHeight
  bool fluid = false, dem = false;
};

/// The vertical axis: gravity's (the longest axis of the box without gravity); `up` when heights
/// grow along +axis (gravity pointing to -axis, or none).
struct VerticalAxis {
  int axis = 2;
  bool up = true;
};
VerticalAxis verticalAxis(const std::array<double, 3>& gravity, const GlobalGrid& g);

/// Collective. Reads the owned particles and (when there is a fluid) the owned pressure cells.
BedDiagnostics bedDiagnostics(coupling::Simulation& sim, const Config& cfg);

/// The CSV column names (without a leading comma) and the values of one row, %.17g.
std::vector<std::string> bedDiagnosticsColumns();
std::vector<double> bedDiagnosticsRow(const BedDiagnostics& d);

/// report.json section "bed".
Json bedDiagnosticsJson(const BedDiagnostics& d);

}  // namespace coloc
