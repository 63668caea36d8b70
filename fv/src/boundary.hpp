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
#include <vector>

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
  // fluid.heat: inlet temperature (inflow and face value), or a wall's / slip face's fixed
  // temperature (K); fixedTemperature false: adiabatic (wall, slip) or none (outlet).
  bool fixedTemperature = false;
  double temperature = 0;
};

/// The conditions of the six box faces: each face has its default condition, and
/// `fluid.patches` may give rectangles of a face their own (inlet, outlet, wall, slip). A cell
/// next to a face belongs to the last patch of that face that contains its face centre.
struct BoxBc {
  std::array<std::array<FaceBc, 2>, 3> face;  // face[axis][side] (side 0 = low, 1 = high)
  std::vector<FaceBc> patch;                  // the patches' conditions
  /// Per face, over the global cells of its two tangential axes (ascending axis order, first
  /// axis fastest): 0 = the face's default, k = patch[k - 1]. Empty: the face is uniform.
  std::array<std::array<std::vector<int>, 2>, 3> map;
  Int3 cells{0, 0, 0};                             // global cells
  std::array<std::array<unsigned, 2>, 3> types{};  // per face: bit t set if BcType t occurs

  static int tangential(int axis, int which) {
    return which == 0 ? (axis == 0 ? 1 : 0) : (axis == 2 ? 1 : 2);
  }
  bool uniform(int axis, int side) const { return map[axis][side].empty(); }
  /// Code (0 default, k patch k-1) of the cell at global tangential indices (clamped).
  int code(int axis, int side, int g1, int g2) const;
  const FaceBc& byCode(int axis, int side, int code) const {
    return code == 0 ? face[axis][side] : patch[static_cast<std::size_t>(code - 1)];
  }
  /// Condition at the face cell whose global tangential indices are g1, g2 (clamped).
  const FaceBc& at(int axis, int side, int g1, int g2) const {
    return uniform(axis, side) ? face[axis][side] : byCode(axis, side, code(axis, side, g1, g2));
  }
  /// Condition of face (axis, side) next to local cell or face index (i, j, k) of block `dec`
  /// (the index along `axis` is not used).
  const FaceBc& atLocal(const Decomposition& dec, int axis, int side, int i, int j, int k) const {
    if (uniform(axis, side)) return face[axis][side];
    const int idx[3] = {i, j, k};
    const int t1 = tangential(axis, 0), t2 = tangential(axis, 1);
    return at(axis, side, dec.lo()[t1] + idx[t1], dec.lo()[t2] + idx[t2]);
  }
  /// Whether any part of face (axis, side) has condition t.
  bool anyOnFace(int axis, int side, BcType t) const;
  /// Whether any part of any face has condition t.
  bool any(BcType t) const;
};

/// Reads fluid.boundary.* and fluid.patches and checks them against domain.periodic.*
/// (ConfigError naming the key).
BoxBc boundaryFromConfig(const Config& cfg, const GlobalGrid& grid);

/// Fill the ghosts of face component c at the physical faces of this block (over the whole
/// allocated range of the other axes), and set the boundary-face normal values of Dirichlet faces.
/// `eps` (the cell fluid fraction, ghosts included): for a superficial inlet the face gets
/// U / eps of the adjacent cell; nullptr: eps = 1.
void applyVelocityBc(const Decomposition& dec, const BoxBc& bc, int c, Field3<double>& u,
                     const Field3<double>* eps = nullptr);
/// Zero-gradient (mirror) ghosts of a cell field at the physical faces of this block.
void applyScalarBc(const Decomposition& dec, Field3<double>& f);

// ---- the pressure and the normal velocity at the box faces (every step) ----------------------
// Only an outlet fixes the pressure (p = p_out at the face, half a cell from the centre of the
// adjacent cell, which gives the face its eps and K); inlet, wall and slip faces are dp/dn = 0
// and add nothing to the pressure equation. These are the outlet's rules; the fluid step calls
// them, it writes none of its own.

/// Whether this block touches box face (axis, side).
inline bool touches(const Decomposition& dec, int axis, int side) {
  return side == 0 ? dec.atLowBoundary(axis) : dec.atHighBoundary(axis);
}

/// fn(i, j, k, condition) for the faces of this block on box face (axis, side), local face
/// indices (the index along `axis` is 0 or n); nothing when the block does not touch the face.
template <class F>
void forBoxFace(const Decomposition& dec, const BoxBc& bc, int axis, int side, F&& fn) {
  if (!touches(dec, axis, side)) return;
  const Int3 n = dec.cells();
  IndexBox b{{0, 0, 0}, n};
  b.lo[axis] = side == 0 ? 0 : n[axis];
  b.hi[axis] = b.lo[axis] + 1;
  forEach(b, [&](int i, int j, int k) { fn(i, j, k, bc.atLocal(dec, axis, side, i, j, k)); });
}

/// Coefficient of an outlet face in the pressure row of its cell (for q = p dt):
/// 2 eps^2 / ((eps + K dt) h^2), eps and K of the cell (twice an interior face's: half a cell).
inline double outletWeight(double eps, double K, double dt, double h) {
  return 2.0 * eps * eps / ((eps + K * dt) * h * h);
}

/// The pressure difference across the half cell next to an outlet face, along +axis:
/// p_cell - p_out at a low face, p_out - p_cell at a high one (the gradient is it * 2/h).
inline double outletDifference(int side, double pCell, double pOut) {
  return side == 0 ? pCell - pOut : pOut - pCell;
}

/// Predictor at the box faces of component c (faces 0 and n along c where the block touches the
/// box): they keep u^n (uPrev = u there, the Dirichlet values), except that an outlet face takes
/// the predicted velocity of the next interior face (du/dn = 0).
void predictBoxFaces(const Decomposition& dec, const BoxBc& bc, int c, Field3<double>& u,
                     Field3<double>& uPrev);

/// Projection of the outlet faces of component c: u -= eps/(eps + K dt) dt (2/h) outletDifference
/// with the adjacent cell's eps, K and p (the pressure p, not q; ih = dt / h_c).
void projectOutletFaces(const Decomposition& dec, const BoxBc& bc, int c, Field3<double>& u,
                        const Field3<double>& eps, const Field3<double>& K, const Field3<double>& p,
                        double dt, double ih);

}  // namespace coloc::fv
