// fv/src/momentum.hpp — explicit momentum terms on the staggered grid (private).
//
// For face component d, on the control volume around the face (finite volume, uniform spacing):
//   H_d = - sum_e d/dx_e ( m_e  u_d )  +  sum_e d/dx_e ( eps nu (du_d/dx_e + du_e/dx_d) )
// Convective mass fluxes m_e are built from the face mass fluxes M_e = eps_f u_e (eps_f the
// arithmetic mean of the two cells, as in the pressure equation) averaged to the faces of the
// staggered control volume, so the momentum control volumes conserve mass exactly when the
// cells do. The transported u_d at a control-volume face is the central average, or a TVD
// (van Leer or minmod) upwind-biased value u_U + psi(r)/2 (u_D - u_U), r = (u_U-u_UU)/(u_D-u_U).
// Viscous stresses: normal stress 2 eps nu du_d/dx_d at cell centres (eps of the cell), shear
// stresses at cell edges with eps the mean of the four cells around the edge.
#pragma once

#include "coloc/partition/field.hpp"

namespace coloc::fv {

enum class Convection { Central, VanLeer, Minmod };

struct MomentumParams {
  double nu = 0;
  Real3 h{1, 1, 1};
  Convection convection = Convection::Central;
};

/// M_d = 0.5 (eps(c-e_d) + eps(c)) u_d on every face where both cells are allocated.
void massFluxes(const FaceField& u, const CellField& eps, FaceField& M);

/// H for component d on the faces of `box` (local face indices).
void explicitTerms(int d, const FaceField& u, const FaceField& M, const CellField& eps,
                   const MomentumParams& prm, const IndexBox& box, Field3<double>& H);

/// The predictor's inputs on the faces `box` of component c (step.cpp, predictVelocity()).
struct PredictFaces {
  int c = 0;
  IndexBox box;
  const CellField *eps = nullptr, *epsOld = nullptr, *K = nullptr, *KUp = nullptr;
  const Field3<double>*Hn = nullptr, *Ho = nullptr;  // H at n and n - 1 (layout of U)
  double ca = 1, cb = 0;                             // E = ca Hn + cb Ho
  double idt = 0, g = 0;                             // 1 / dt, gravity along c
};
/// On the faces of p.box, with the face means eps_f = (eps(c - e_c) + eps(c)) / 2 (and of
/// eps_old, K, KUp): P = U, then U = (eps_old_f U / dt + E + eps_f g + KUp_f) / (eps_f / dt + K_f).
void predictFaces(const PredictFaces& p, Field3<double>& U, Field3<double>& P);

/// The instruction sets explicitTerms() and predictFaces() are compiled for (momentum_kernels.hpp):
/// Widest is the widest one the CPU runs, what they call. All give the same bits.
enum class MomentumIsa { Widest, Build, Avx2, Avx512 };
/// explicitTerms() on the given instruction set (tests compare them); false (and nothing
/// computed) where the CPU lacks the instructions.
bool explicitTermsOn(MomentumIsa isa, int d, const FaceField& u, const FaceField& M,
                     const CellField& eps, const MomentumParams& prm, const IndexBox& box,
                     Field3<double>& H);
/// predictFaces() on the given instruction set; false (and nothing computed) where the CPU lacks
/// the instructions.
bool predictFacesOn(MomentumIsa isa, const PredictFaces& p, Field3<double>& U, Field3<double>& P);

}  // namespace coloc::fv
