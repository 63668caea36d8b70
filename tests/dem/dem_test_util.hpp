// Helpers of the DEM tests: a case from JSON text, a solver on it, global sums.
#pragma once

#include <algorithm>
#include <cmath>
#include <memory>
#include <span>
#include <string>
#include <utility>
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

/// A conveying channel of 30 x 16 x 16 mm: an inflow patch on xlo (20,000 particles/s of two
/// diameters, 1.5 and 2 mm, at 2 m/s with a spread), an outflow face xhi, walls elsewhere;
/// collisions. `extra`: more keys of "particles" (each after a comma); `material`: more keys of
/// its material, `inflow`: of its inflow source (the same way).
inline std::string channel(const std::string& extra = "", const std::string& material = "",
                           const std::string& inflow = "") {
  return R"({
  "domain": {"length": [0.03, 0.016, 0.016], "cells": [6, 4, 4]},
  "particles": {
    "dt": 1e-5,
    "boundary": {"xhi": "outflow"},
    "materials": [{"density": 2500, "young": 1e7, "poisson": 0.3, "restitution": 0.8,
                   "friction": 0.3)" +
         material + R"(}],
    "inflow": [{"face": "xlo", "patch": {"min": [0.002, 0.002], "max": [0.014, 0.014]},
                "rate": 20000, "velocity": [2, 0, 0], "velocity_spread": 0.5,
                "size": {"type": "discrete", "diameters": [0.0015, 0.002],
                         "weights": [2, 1]})" +
         inflow + R"(}])" + extra + R"(
  }
})";
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
  /// Same case on a given decomposition (a tiled layout: Decomposition::fromBoxes).
  Case(const std::string& text, coloc::Decomposition d) : cfg(config(text)), dec(std::move(d)) {
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

/// Largest difference between two tables of table(): positions relative to `length`, velocities
/// and angular velocities relative to their largest magnitude in `ref`; and the ids whose count
/// differs (missing or duplicated).
struct TableDiff {
  double x = 0, v = 0, omega = 0;
  long countsDiffer = 0;
};
inline TableDiff compare(const std::vector<double>& t, const std::vector<double>& ref,
                         double length) {
  TableDiff out;
  double vmax = 0, wmax = 0;
  for (std::size_t k = 0; k < ref.size(); k += 10)
    for (std::size_t d = 0; d < 3; ++d) {
      vmax = std::max(vmax, std::fabs(ref[k + 4 + d]));
      wmax = std::max(wmax, std::fabs(ref[k + 7 + d]));
    }
  for (std::size_t k = 0; k < ref.size(); k += 10) {
    if (t[k] != ref[k]) ++out.countsDiffer;
    for (std::size_t d = 0; d < 3; ++d) {
      out.x = std::max(out.x, std::fabs(t[k + 1 + d] - ref[k + 1 + d]) / length);
      if (vmax > 0) out.v = std::max(out.v, std::fabs(t[k + 4 + d] - ref[k + 4 + d]) / vmax);
      if (wmax > 0)
        out.omega = std::max(out.omega, std::fabs(t[k + 7 + d] - ref[k + 7 + d]) / wmax);
    }
  }
  return out;
}

/// Contact histories of saveState() (which rebuilds first) over all ranks, keyed by (holder id,
/// partner id; walls -1..-6 as partners n..n+5): [count, shear 3] per key. Collective.
inline std::vector<double> historyTable(Case& r, long n) {
  const auto st = r.dem->saveState();
  const auto cols = static_cast<std::size_t>(n + 6);
  std::vector<double> t(4 * static_cast<std::size_t>(n) * cols, 0.0);
  for (const auto& c : st.contacts) {
    if (c.holder < 0 || c.holder >= n || c.partner >= n) continue;
    const auto col = static_cast<std::size_t>(c.partner >= 0 ? c.partner : n - 1 - c.partner);
    const std::size_t k = 4 * (static_cast<std::size_t>(c.holder) * cols + col);
    t[k] += 1;
    for (std::size_t d = 0; d < 3; ++d) t[k + 1 + d] = c.shear[d];
  }
  r.dec.comm().sumInPlace(std::span<double>(t));
  return t;
}

}  // namespace demtest
