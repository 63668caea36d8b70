// dem/src/generate.hpp — particles from the case's sources, deterministic from global ids.
//
// Global ids run over the sources in order (source s gets [base_s, base_s + count_s)). Every
// random quantity of a particle is drawn from its own counter-based stream (rng.hpp), and the
// lattice-like sources (lattice, random, layered) enumerate only the sites near the calling
// rank's block, so each rank creates exactly its own particles and any rank count builds the
// same set. "random" places particle k on site P(k) of a cubic site lattice of edge
// 2 r_max (1 + gap), P a pseudo-random permutation (Feistel), at a random free offset inside the
// site: non-overlapping by construction, no global rejection loop. "layered" fills the same kind
// of sites layer after layer from the low end of an axis (the paper's case 3 bed).
#pragma once

#include <cstdint>
#include <functional>
#include <vector>

#include "coloc/core/config.hpp"
#include "coloc/partition/decomposition.hpp"

namespace coloc::dem::detail {

struct NewParticle {
  std::int64_t id = 0;
  int material = 0;
  double radius = 0;
  double x[3] = {0, 0, 0};
  double v[3] = {0, 0, 0};
};

struct SourceInfo {
  long long count = 0;
  double rmax = 0;
};

/// Checks every source against the box and the materials (same verdict on every rank: throws
/// ConfigError naming the key) and returns each source's particle count and largest radius.
std::vector<SourceInfo> inspectSources(const Config& cfg, const GlobalGrid& grid, int nMaterials);

/// Calls add() for every particle whose centre `owns` accepts; only sites near
/// [blockLo, blockHi] are visited (list sources are scanned whole).
void generate(const Config& cfg, const std::vector<SourceInfo>& info, const Real3& blockLo,
              const Real3& blockHi, const std::function<bool(const double*)>& owns,
              const std::function<void(const NewParticle&)>& add);

}  // namespace coloc::dem::detail
