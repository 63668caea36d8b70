// dem/src/heat.cpp — particle temperature: set-up, contact conduction, the explicit update and
// its stability check (HeatTransfer, heat.hpp).
#include "heat.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <string>

#include "buffers.hpp"

namespace coloc::dem::detail {

void HeatTransfer::setup(const Config& cfg, const std::vector<Material>& mats, ParticleStore& p) {
  on = cfg.boolean("particles.heat");
  if (!on) return;
  conduction = cfg.boolean("particles.contact_conduction");
  wallT = cfg.optionalNumber("particles.wall_temperature").value_or(0.0);  // 0: adiabatic
  nMat = static_cast<int>(mats.size());
  cp.clear();
  kPair.assign(static_cast<std::size_t>(nMat * nMat), 0.0);
  kWall.assign(static_cast<std::size_t>(nMat), 0.0);
  const auto keff = [](double a, double b) { return 2.0 * a * b / (a + b); };
  const auto wm = static_cast<std::size_t>(std::max(0LL, cfg.integer("particles.wall_material")));
  for (int a = 0; a < nMat; ++a) {
    const Material& ma = mats[static_cast<std::size_t>(a)];
    cp.push_back(ma.heatCapacity);
    for (int b = 0; b < nMat; ++b)
      kPair[static_cast<std::size_t>(a * nMat + b)] =
          keff(ma.conductivity, mats[static_cast<std::size_t>(b)].conductivity);
    if (wm < mats.size())
      kWall[static_cast<std::size_t>(a)] = keff(ma.conductivity, mats[wm].conductivity);
  }
  iT = p.addField("temperature", 1, kOpGhostBuild | kOpGhostUpdate | kOpMigrate | kOpState);
  iQ = p.addField("heat_rate", 1, 0);
  iExt = p.addField("heat_ext", 1, kOpMigrate | kOpState);
}

// The entries in the force pass's order (force_pass.hpp: ForcePass::run): holders in K order,
// each pair once with the lower-K particle (the holder) first, then the holder's walls. The
// touching test is the force pass's (same operands: the bodies are copies of x).
void HeatTransfer::conduct(ParticleStore& p, const NeighbourSearch& s) {
  const std::size_t n = p.nOwned, nAll = p.size();
  double* Q = p.extra[iQ].data[0].data();
  std::fill(Q, Q + n, 0.0);
  wallRate_ = 0;
  if (!conduction) return;
  const double* T = p.extra[iT].data[0].data();
  const double *X0 = p.x[0].data(), *X1 = p.x[1].data(), *X2 = p.x[2].data();
  const double* R = p.radius.data();
  const int* mat = p.material.data();
  const int* nbr = s.list().nbr.data();
  const int* rowStart = s.list().rowStart.data();
  const int* slot = s.listSlots();
  const int* items = s.bins().binItems.data();
  const bool walls = wallT > 0;
  double wallRate = 0;
  for (std::size_t q = 0; q < nAll; ++q) {
    const int e0 = rowStart[q], e1 = rowStart[q + 1];
    if (e0 == e1) continue;
    const auto i = static_cast<std::size_t>(items[q]);
    const double xi[3] = {X0[i], X1[i], X2[i]};
    const double ri = R[i];
    for (int e = e0; e < e1; ++e) {
      // Only the entries the last force pass found touching (those holding a history slot):
      // the others are skipped without reading their partner (the test below would reject
      // them with the same operands).
      if (slot[e] < 0) continue;
      const int j = nbr[e];
      if (j >= 0) {
        const auto u = static_cast<std::size_t>(j);
        const double dx[3] = {xi[0] - X0[u], xi[1] - X1[u], xi[2] - X2[u]};
        const double r2 = dx[0] * dx[0] + dx[1] * dx[1] + dx[2] * dx[2];
        const double rs = ri + R[u];
        if (r2 >= rs * rs) continue;
        const double delta = rs - std::sqrt(r2);
        const double a = std::sqrt(ri * R[u] / rs * delta);  // Hertz contact radius
        const double H = 2.0 * kPair[static_cast<std::size_t>(mat[i] * nMat + mat[u])] * a;
        const double heat = H * (T[u] - T[i]);  // into i, out of u
        if (i < n) Q[i] += heat;
        if (u < n) Q[u] -= heat;
      } else if (walls) {
        const int w = -1 - j, d = w / 2, sd = w % 2;
        const double dist =
            sd == 0 ? xi[d] - s.bins().origin[d] : s.bins().origin[d] + s.bins().L[d] - xi[d];
        const double delta = ri - dist;
        if (!(delta > 0)) continue;
        const double a = std::sqrt(ri * delta);
        const double heat = 2.0 * kWall[static_cast<std::size_t>(mat[i])] * a * (wallT - T[i]);
        Q[i] += heat;  // a wall entry's particle is owned
        wallRate += heat;
      }
    }
  }
  wallRate_ = wallRate;
}

void HeatTransfer::integrate(ParticleStore& p, double dt) {
  const std::size_t n = p.nOwned;
  double* T = p.extra[iT].data[0].data();
  const double* Q = p.extra[iQ].data[0].data();
  const double* E = p.extra[iExt].data[0].data();
  const double* m = p.mass.data();
  const int* mat = p.material.data();
  const double* c = cp.data();
  double ext = 0;
  for (std::size_t i = 0; i < n; ++i) {
    T[i] += dt * (Q[i] + E[i]) / (m[i] * c[mat[i]]);
    ext += E[i];
  }
  extHeat += dt * ext;
  wallHeat += dt * wallRate_;
  if (heldSubsteps > 0) --heldSubsteps;
}

void HeatTransfer::checkTimeStep(double dt, double overlapLimit, const std::vector<Material>& mats,
                                 const std::vector<double>& rMin) const {
  if (!on || !conduction) return;
  for (std::size_t a = 0; a < rMin.size() && a < mats.size(); ++a) {
    const double r = rMin[a];
    if (!std::isfinite(r) || !(r > 0)) continue;
    const double C = mats[a].density * 4.0 / 3.0 * M_PI * r * r * r * mats[a].heatCapacity;
    const double delta = overlapLimit * r;
    const double hPair =
        2.0 * kPair[a * static_cast<std::size_t>(nMat) + a] * std::sqrt(0.5 * r * delta);
    const double hWall = wallT > 0 ? 2.0 * kWall[a] * std::sqrt(r * delta) : 0.0;
    const double H = std::max(hPair, hWall);
    const double limit = kStableFraction * C / H;
    if (!(dt > limit)) continue;
    // A limit far below any DEM step is a material key out of its range (a conductivity in the
    // wrong units), not a step to lower: named so.
    const bool material = !(limit > 1e-4 * dt);
    const std::string key = material ? fmt::format("particles.materials[{}].conductivity", a)
                                     : std::string("particles.dt");
    throw ConfigError(
        key,
        fmt::format("particles.dt = {:.4g} s is above {:.4g} s, the explicit limit ({:g} m c_p / "
                    "H) of the temperature update for the smallest particle of material {} (r = "
                    "{:.4g} m, heat_capacity {:g} J/(kg K), conductivity {:g} W/(m K)) at the "
                    "overlap limit (H = 2 k_eff a, a = sqrt(R* delta)): {}",
                    dt, limit, kStableFraction, a, r, mats[a].heatCapacity, mats[a].conductivity,
                    material ? "check the conductivity (and heat_capacity) of the material"
                             : "lower particles.dt, or raise heat_capacity"));
  }
}

}  // namespace coloc::dem::detail
