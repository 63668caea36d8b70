// Helpers for the coupled validation tests: build a case from JSON text, track one particle.
#pragma once

#include <gtest/gtest.h>

#include <array>
#include <string>

#include "coloc/coupling/simulation.hpp"

namespace coloc::test {

inline Config caseFromText(const std::string& text, std::vector<std::string> overrides = {}) {
  return Config::fromText(text, "test", overrides, coupling::caseSchema());
}

/// Position, velocity and external force of the particle with global id `id` (collective).
struct ParticleState {
  std::array<double, 3> x{}, v{}, f{};
  bool found = false;
};

inline ParticleState particleState(coupling::Simulation& sim, std::int64_t id) {
  double buf[10] = {0};
  const auto& p = sim.particles()->particles();
  for (std::size_t i = 0; i < p.nOwned; ++i) {
    if (p.id[i] != id) continue;
    for (int d = 0; d < 3; ++d) {
      buf[d] = p.x[d][i];
      buf[3 + d] = p.v[d][i];
      buf[6 + d] = p.fExt[d][i];
    }
    buf[9] = 1.0;
  }
  sim.decomposition().comm().sumInPlace(std::span<double>(buf, 10));
  ParticleState s;
  for (int d = 0; d < 3; ++d) {
    s.x[d] = buf[d];
    s.v[d] = buf[3 + d];
    s.f[d] = buf[6 + d];
  }
  s.found = buf[9] == 1.0;
  return s;
}

}  // namespace coloc::test
