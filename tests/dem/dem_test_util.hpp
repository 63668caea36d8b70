// Helpers of the DEM tests: a case from JSON text, a solver on it, global sums.
#pragma once

#include <cmath>
#include <memory>
#include <span>
#include <string>
#include <vector>

#include "coloc/core/run_config.hpp"
#include "coloc/dem/dem.hpp"
#include "coloc/partition/setup.hpp"

namespace demtest {

inline coloc::Schema schema() {
  coloc::Schema s;
  coloc::declareRunConfig(s);
  coloc::declareDomainConfig(s);
  coloc::dem::declareConfig(s);
  return s;
}

inline coloc::Config config(const std::string& text) {
  return coloc::Config::fromText(text, "test", {}, schema());
}

/// A solver with its decomposition and timers (the decomposition must outlive the solver).
struct Case {
  coloc::Config cfg;
  coloc::Decomposition dec;
  coloc::Timers timers;
  std::unique_ptr<coloc::dem::DemSolver> dem;
  Case(const std::string& text, const coloc::Comm& comm = coloc::Comm::world())
      : cfg(config(text)), dec(coloc::decompositionFromConfig(comm, cfg)) {
    dem = std::make_unique<coloc::dem::DemSolver>(dec, cfg, timers);
  }
  /// Same case on an explicit process grid of `comm` (serial references use MPI_COMM_SELF).
  Case(const std::string& text, const coloc::Comm& comm, coloc::Int3 dims)
      : cfg(config(text)),
        dec(coloc::Decomposition::uniform(comm, coloc::gridFromConfig(cfg), dims)) {
    dem = std::make_unique<coloc::dem::DemSolver>(dec, cfg, timers);
  }
  coloc::dem::ParticleStore& p() { return dem->particles(); }
  /// Index of the owned particle with this id, or -1.
  long find(std::int64_t id) {
    auto& s = p();
    for (std::size_t i = 0; i < s.nOwned; ++i)
      if (s.id[i] == id) return static_cast<long>(i);
    return -1;
  }
  /// Kinetic energy (translation + rotation) of all particles. Collective.
  double kinetic() {
    auto& s = p();
    double e = 0;
    for (std::size_t i = 0; i < s.nOwned; ++i) {
      const double I = 0.4 * s.mass[i] * s.radius[i] * s.radius[i];
      for (int d = 0; d < 3; ++d)
        e += 0.5 * s.mass[i] * s.v[d][i] * s.v[d][i] + 0.5 * I * s.omega[d][i] * s.omega[d][i];
    }
    return dec.comm().sum(e);
  }
};

}  // namespace demtest

namespace demtest {

/// Per-id table over all ranks: [count, x, y, z, vx, vy, vz, wx, wy, wz] for ids 0..n-1.
/// Collective over the run's communicator (a serial reference on MPI_COMM_SELF sums nothing).
inline std::vector<double> table(Case& r, long n) {
  std::vector<double> t(static_cast<std::size_t>(10 * n), 0.0);
  auto& s = r.p();
  for (std::size_t i = 0; i < s.nOwned; ++i) {
    const auto k = static_cast<std::size_t>(10 * s.id[i]);
    if (s.id[i] < 0 || s.id[i] >= n) continue;
    t[k] += 1;
    for (int d = 0; d < 3; ++d) {
      t[k + 1 + d] = s.x[d][i];
      t[k + 4 + d] = s.v[d][i];
      t[k + 7 + d] = s.omega[d][i];
    }
  }
  r.dec.comm().sumInPlace(std::span<double>(t));
  return t;
}

}  // namespace demtest
