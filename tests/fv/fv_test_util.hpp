// Helpers of the fluid validation tests: a case from JSON text, global reductions over owned
// cells and faces.
#pragma once

#include <cmath>
#include <functional>
#include <string>
#include <vector>

#include "coloc/core/config.hpp"
#include "coloc/core/run_config.hpp"
#include "coloc/core/timers.hpp"
#include "coloc/fv/fluid.hpp"
#include "coloc/partition/setup.hpp"

namespace fvtest {

inline coloc::Schema schema() {
  coloc::Schema s;
  coloc::declareRunConfig(s);
  coloc::declareDomainConfig(s);
  coloc::fv::declareConfig(s);
  return s;
}

inline coloc::Config config(const std::string& json,
                            const std::vector<std::string>& overrides = {}) {
  return coloc::Config::fromText(json, "test", overrides, schema());
}

/// Owned faces of component d: [0,n) plus face n at a non-periodic high box face.
inline coloc::IndexBox ownedFaces(const coloc::Decomposition& dec, int d) {
  return coloc::faceOwned(dec, d);
}

/// Physical position of local face (i,j,k) of component d.
inline coloc::Real3 facePos(const coloc::Decomposition& dec, int d, int i, int j, int k) {
  const auto& g = dec.grid();
  const int idx[3] = {i, j, k};
  coloc::Real3 x;
  for (int a = 0; a < 3; ++a)
    x[a] = g.origin[a] + (dec.lo()[a] + idx[a] + (a == d ? 0.0 : 0.5)) * g.spacing(a);
  return x;
}

inline coloc::Real3 cellPos(const coloc::Decomposition& dec, int i, int j, int k) {
  return facePos(dec, -1, i, j, k);
}

/// Run until the steady residual drops below `tol` or `maxSteps` are done; returns the steps.
inline long long runSteady(coloc::fv::FluidSolver& s, double tol, long long maxSteps) {
  long long n = 0;
  for (; n < maxSteps; ++n) {
    s.step(s.nextDt());
    if (n > 10 && s.diagnostics()["fluid"]["steady_residual"].get<double>() < tol) break;
  }
  return n + 1;
}

}  // namespace fvtest
