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

#include <array>
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
  double temperature = 0;  // K (the source's; used with particles.heat)
};

/// A size distribution (by number, in diameter), drawn per particle from one uniform number of
/// its id's stream: fixed, discrete (diameters with weights), uniform in d, log-normal (ln d
/// normal) truncated to [min, max] by inverting its CDF.
struct SizeDist {
  enum Kind { Fixed, Discrete, Uniform, LogNormal } kind = Fixed;
  double r0 = 0;               // Fixed: the radius
  std::vector<double> d, cum;  // Discrete: diameters, cumulative weights (last = 1)
  double dmin = 0, dmax = 0;   // Uniform, LogNormal: bounds
  double mu = 0, sigma = 1;    // LogNormal: of ln d
  double fa = 0, fb = 1;       // LogNormal: the normal CDF at the cut-offs
  double rmin() const;
  double rmax() const;
  /// Radius for a uniform number u in [0, 1).
  double radius(double u) const;
  bool fixed() const { return kind == Fixed; }
};

/// Reads the "size" object of a source (radius: its "radius" key); throws ConfigError naming
/// key + ".size" or key + ".radius".
SizeDist sizeDistribution(const Json& src, const std::string& key);

struct SourceInfo {
  long long count = 0;
  double rmax = 0;
  double rmin = 0;
};

/// A particle inflow source (particles.inflow[n]), parsed and checked once.
struct InflowInfo {
  int axis = 0, side = 0;                     // face: axis, 0 = low, 1 = high
  int a = 1, b = 2;                           // the two in-plane axes, in axis order
  double pmin[2] = {0, 0}, pmax[2] = {0, 0};  // the patch, in (a, b)
  double s = 0;                               // site edge 2 r_max (1 + gap)
  long long na = 1, nb = 1;                   // sites along a, b
  double rate = 0, massRate = 0, start = 0, end = 0;
  int material = 0;
  SizeDist size;
  std::array<double, 3> v{};
  double spread = 0;
  double temperature = 0;  // K
};

/// Checks particles.inflow against the box, its periodic axes and the materials (ConfigError
/// naming the key).
std::vector<InflowInfo> inspectInflow(const Config& cfg, const GlobalGrid& grid, int nMaterials);

/// Checks every source against the box and the materials (same verdict on every rank: throws
/// ConfigError naming the key) and returns each source's particle count and largest radius.
std::vector<SourceInfo> inspectSources(const Config& cfg, const GlobalGrid& grid, int nMaterials);
/// Over the sources that place particles: the largest radius, and the count of all of them.
struct SourceTotals {
  double rmax = 0;
  long long count = 0;
};
SourceTotals sourceTotals(const std::vector<SourceInfo>& info);

/// Calls add() for every particle whose centre `owns` accepts; only sites near
/// [blockLo, blockHi] are visited (list sources are scanned whole).
void generate(const Config& cfg, const std::vector<SourceInfo>& info, const Real3& blockLo,
              const Real3& blockHi, const std::function<bool(const double*)>& owns,
              const std::function<void(const NewParticle&)>& add);

}  // namespace coloc::dem::detail
