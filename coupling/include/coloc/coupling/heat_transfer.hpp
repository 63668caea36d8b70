// coloc/coupling/heat_transfer.hpp — fluid–particle convection: the Nusselt laws
// (coupling.heat_transfer; docs/heat.md, "Convection").
//
// Each particle exchanges heat with the fluid at its centre at the rate
//     q = h A (T_f - T_p) = Nu k_f pi d (T_f - T_p)     (W, into the particle),
// with Nu from one of the laws below, Re = eps d |u_f - v_p| / nu (the drag laws' superficial
// Reynolds number), Pr = rho_f nu c_f / k_f:
//
// Ranz & Marshall (1952), Chem. Eng. Prog. 48:141, a single sphere:
//     Nu = 2 + 0.6 Re^(1/2) Pr^(1/3)
// Gunn (1978), Int. J. Heat Mass Transfer 21:467, fixed and fluidised beds (0.35 <= eps <= 1,
// Re up to 1e5):
//     Nu = (7 - 10 eps + 5 eps^2)(1 + 0.7 Re^0.2 Pr^(1/3))
//          + (1.33 - 2.4 eps + 1.2 eps^2) Re^0.7 Pr^(1/3)
// (at eps = 1 and Re = 0 Gunn gives 2, the conduction limit of a sphere in still fluid, as
// Ranz–Marshall does).
#pragma once

#include <string>

#include "coloc/core/config.hpp"

namespace coloc::coupling {

enum class HeatLaw { None, RanzMarshall, Gunn };

/// "none", "ranz_marshall", "gunn" (ConfigError on coupling.heat_transfer otherwise).
HeatLaw heatLawFromName(const std::string& name);
const char* heatLawName(HeatLaw law);
/// coupling.heat_transfer of a case; a law other than none needs fluid.heat and particles.heat
/// (ConfigError on coupling.heat_transfer otherwise).
HeatLaw heatLawFromConfig(const Config& cfg);

/// Nu of one particle (law None: 0). re >= 0, pr > 0, eps in (0, 1].
double nusselt(HeatLaw law, double eps, double re, double pr);

}  // namespace coloc::coupling
