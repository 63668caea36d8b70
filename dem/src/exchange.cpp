// dem/src/exchange.cpp — what both particle exchanges share (exchange.hpp): the periodic wrap and
// face crossing of a migrating particle, and the migrant rows (the kOpMigrate row of the field
// table, then the particle's contact-history rows).
#include "exchange.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <string>

#include "rows.hpp"

namespace coloc::dem::detail {

int crossAxis(ParticleStore& p, const Bins& bins, std::size_t i, int d) {
  double& x = p.x[d][i];
  if (!std::isfinite(x) || !std::isfinite(p.v[d][i]) || !std::isfinite(p.omega[d][i])) return kLost;
  if (bins.periodic[d]) {
    const double top = bins.origin[d] + bins.L[d];
    if (x < bins.origin[d]) {
      x += bins.L[d];
      if (x >= top) x = bins.origin[d];
      return -1;
    }
    if (x >= top) {
      x -= bins.L[d];
      if (x < bins.origin[d]) x = bins.origin[d];
      return +1;
    }
  } else if (x < bins.origin[d] || x > bins.origin[d] + bins.L[d]) {
    return kLost;
  }
  const long long b = bins.gbinClamped(x, d);
  return b < bins.binLo[d] ? -1 : (b >= bins.binHi[d] ? +1 : 0);
}

std::string lostMessage(const ParticleStore& p, const Bins& bins, std::size_t i, int d,
                        const std::string& where) {
  const double x = p.x[d][i];
  if (!std::isfinite(x) || !std::isfinite(p.v[d][i]) || !std::isfinite(p.omega[d][i]))
    return fmt::format(
        "particle {} has a non-finite {}{}: the run blew up (time step too large, or a NaN in "
        "the forces)",
        p.id[i],
        !std::isfinite(x)           ? "position"
        : !std::isfinite(p.v[d][i]) ? "velocity"
                                    : "angular velocity",
        where);
  return fmt::format(
      "particle {} left the box through the {}{} face{} (x = {:.4g}, {:.4g}, {:.4g}): too fast "
      "for the walls, or walls are off",
      p.id[i], x < bins.origin[d] ? "low " : "high ", kAxis[d], where, p.x[0][i], p.x[1][i],
      p.x[2][i]);
}

void ParticleExchange::packMigrant(std::size_t i, std::size_t W, std::span<double> out) const {
  const HistoryPool& hist = c_.hist;
  const auto h0 = static_cast<std::size_t>(hist.hStart[i]);
  const auto h1 = static_cast<std::size_t>(hist.hStart[i + 1]);
  packRow(c_.p, kOpMigrate, i, nullptr, out.data());
  std::size_t q = W;
  out[q++] = static_cast<double>(h1 - h0);
  for (std::size_t e = h0; e < h1; ++e) {
    out[q++] = hist.hKey[e];
    for (std::size_t k = 0; k < 3; ++k) out[q++] = hist.hS[3 * e + k];
  }
}

void ParticleExchange::unpackMigrants(std::span<const double> rows, std::size_t W) {
  ParticleStore& p = c_.p;
  HistoryPool& hist = c_.hist;
  std::size_t q = 0;
  while (q < rows.size()) {
    const std::size_t i = p.nOwned;
    resizeAll(p, i + 1);
    p.nOwned = i + 1;
    unpackRow(p, kOpMigrate, rows.data() + q, i, true);
    const auto nh = static_cast<std::size_t>(rows[q + W]);
    q += W + 1;
    ensure(hist.hKey, hist.hKey.size() + nh);
    ensure(hist.hS, hist.hS.size() + 3 * nh);
    ensure(hist.hStart, hist.hStart.size() + 1);
    for (std::size_t e = 0; e < nh; ++e, q += 4) {
      hist.hKey.push_back(rows[q]);
      hist.hS.insert(hist.hS.end(), rows.begin() + static_cast<std::ptrdiff_t>(q + 1),
                     rows.begin() + static_cast<std::ptrdiff_t>(q + 4));
    }
    hist.hStart.push_back(static_cast<int>(hist.hKey.size()));
  }
}

}  // namespace coloc::dem::detail
