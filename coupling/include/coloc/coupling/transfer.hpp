// coloc/coupling/transfer.hpp — how the coupling kernels reach the particles, and how the
// forces reach the DEM: one interface, one implementation per kind of partition.
//
//   co-located   (uniform, balanced) the fluid block and the DEM block are the same region of
//                the same rank: the view points into the DEM's own arrays (no copy) and the
//                forces are stored straight into its external-force array.
//   proxy        (independent) the DEM has its own blocks: every particle's coupling data
//                (x, v, non-drag force, radius, mass, id: 12 values) travels through a
//                CommPlan (partition/comm_plan.hpp) to the rank whose fluid block holds its
//                centre, and the force comes back through the same plan, reversed. With
//                convection (coupling.heat_transfer) the row also carries the temperature and
//                the material, and the heat rate comes back with the force. The plan is
//                rebuilt each step (the particles move) and reused for the way back. Booked as
//                inter-physics exchange: rows to other ranks `proxy` (remote), rows a rank keeps
//                `force_handover` (local).
#pragma once

#include <array>
#include <cstdint>
#include <memory>

#include "coloc/core/timers.hpp"
#include "coloc/dem/dem.hpp"
#include "coloc/partition/decomposition.hpp"

namespace coloc::coupling {

/// Doubles a particle's row carries through the proxy transfer (independent strategy): to the
/// fluid's rank x, v, the non-drag force (3 each), radius, mass, id; back, the force (3). With
/// convection, kProxyHeatDoubles more to the fluid's rank (temperature, material) and
/// kHeatRowDoubles more back (the heat rate).
inline constexpr int kProxyRowDoubles = 12, kForceRowDoubles = 3;
inline constexpr int kProxyHeatDoubles = 2, kHeatRowDoubles = 1;

/// What the coupling kernels see of the particles (n of them).
struct ParticleView {
  std::size_t n = 0;
  /// The non-drag force on particle i is force[d][i] - held[d][i]: the DEM's last total force
  /// less the coupling force it held (co-located), or the value received with the proxy
  /// (held is null).
  std::array<const double*, 3> x{}, v{}, force{}, held{};
  double nonDrag(int d, std::size_t i) const { return force[d][i] - (held[d] ? held[d][i] : 0.0); }
  const double* radius = nullptr;
  const double* mass = nullptr;
  const std::int64_t* id = nullptr;
  /// With convection (else null): temperature (K) and material index of each particle.
  const double* temperature = nullptr;
  const int* material = nullptr;
};

class ParticleTransfer {
 public:
  virtual ~ParticleTransfer() = default;
  /// The particles the fluid's rank couples this step. Collective (proxy).
  virtual ParticleView gather(Timers& timers) = 0;
  /// Where the coupling force of view particle i goes (3 arrays of at least view.n entries).
  virtual std::array<double*, 3> forceTarget() = 0;
  /// With convection, where the heat rate of view particle i goes (else null).
  virtual double* heatTarget() = 0;
  /// The forces written to forceTarget() to the DEM's external-force array, and the heat rates
  /// written to heatTarget() to its heat_ext field. Collective (proxy).
  virtual void handBack(Timers& timers) = 0;
};

/// The view on `dem`'s own arrays; `heat`: with convection (the DEM has particles.heat).
std::unique_ptr<ParticleTransfer> colocatedTransfer(dem::DemSolver& dem, bool heat);
/// Proxies on the fluid blocks `fluid` of the particles of `dem` (on its own blocks).
std::unique_ptr<ParticleTransfer> proxyTransfer(const Decomposition& fluid, dem::DemSolver& dem,
                                                bool heat);

}  // namespace coloc::coupling
