// fv/src/boundary.hpp — boundary conditions of the box faces (private).
//
// Per face of the box one of:
//   inlet   u = U (given vector): Dirichlet velocity, dp/dn = 0; with "superficial": true the
//           normal U is a volume flux per area and the face gets U / eps of the adjacent cell
//           (the inflow is U A whatever the porosity of the first cell, e.g. a bed resting on
//           the inlet; with eps = 1 there both are the same)
//   outlet  p = p_out: Dirichlet pressure at the face, du/dn = 0 (the outlet-face normal velocity
//           is extrapolated in the predictor and then corrected by the pressure gradient over the
//           half cell, so continuity holds in the last cell to solver tolerance)
//   wall    no slip, u = U_wall (tangential, optional: moving lid), dp/dn = 0
//   slip    free slip: u_n = 0, du_t/dn = 0, dp/dn = 0
//   periodic (both faces of an axis, must match domain.periodic.<axis>)
// Ghost values (two layers) of the staggered velocity: tangential components are reflected about
// the face value (u_g = 2 U - u_inner, second-order Dirichlet) or copied (zero gradient); the
// normal component beyond a Dirichlet face is reflected about the face value, beyond an outlet
// copied. Cell scalars (eps, K, K u_p) get zero-gradient ghosts (u_g = u_inner, mirror).
#pragma once

#include <array>
#include <string>

#include "coloc/core/config.hpp"
#include "coloc/partition/decomposition.hpp"
#include "coloc/partition/field.hpp"

namespace coloc::fv {

enum class BcType { Periodic, Inlet, Outlet, Wall, Slip };

struct FaceBc {
  BcType type = BcType::Wall;
  Real3 velocity{0, 0, 0};   // inlet velocity, or wall velocity
  bool superficial = false;  // inlet: velocity is a volume flux per area (u = U / eps)
  double pressure = 0;       // outlet kinematic pressure
};

/// bc[axis][side]: side 0 = low face, 1 = high face.
using BoxBc = std::array<std::array<FaceBc, 2>, 3>;

/// Reads fluid.boundary.* and checks it against domain.periodic.* (ConfigError naming the key).
BoxBc boundaryFromConfig(const Config& cfg, const GlobalGrid& grid);

/// Fill the ghosts of face component c at the physical faces of this block (over the whole
/// allocated range of the other axes), and set the boundary-face normal values of Dirichlet faces.
/// `eps` (the cell fluid fraction, ghosts included): for a superficial inlet the face gets
/// U / eps of the adjacent cell; nullptr: eps = 1.
void applyVelocityBc(const Decomposition& dec, const BoxBc& bc, int c, Field3<double>& u,
                     const Field3<double>* eps = nullptr);
/// Zero-gradient (mirror) ghosts of a cell field at the physical faces of this block.
void applyScalarBc(const Decomposition& dec, Field3<double>& f);

}  // namespace coloc::fv
