#include "generate.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <string>

#include "rng.hpp"

namespace coloc::dem::detail {
namespace {

std::string srcPath(std::size_t i) {
  return fmt::format("particles.sources[{}]", i);
}

std::array<double, 3> vec(const Json& j) {
  return {j[0].get<double>(), j[1].get<double>(), j[2].get<double>()};
}

void checkInside(const GlobalGrid& g, const std::array<double, 3>& p, const std::string& key) {
  for (int d = 0; d < 3; ++d) {
    const double lo = g.origin[d], hi = g.origin[d] + g.length[d];
    if (!(p[d] >= lo && p[d] <= hi))
      throw ConfigError(
          key, fmt::format("point ({:f}, {:f}, {:f}) lies outside the box", p[0], p[1], p[2]));
  }
}

struct SiteGrid {
  std::array<double, 3> lo{};
  double s = 1;
  std::array<long long, 3> n{1, 1, 1};
  long long total() const { return n[0] * n[1] * n[2]; }
};

/// The most sites a random or layered source's region may hold (the Feistel permutation's
/// domain, rng.hpp, and what a long long counts with room to spare).
constexpr double kMaxSites = 0x1p62;

SiteGrid siteGrid(const Json& src, double edge, const std::string& key) {
  SiteGrid g;
  g.lo = vec(src["lo"]);
  const auto hi = vec(src["hi"]);
  g.s = edge;
  if (!(edge > 0) || !std::isfinite(edge))
    throw ConfigError(key, fmt::format("the particle site (2 r_max (1 + gap) = {:.6g} m) is not a "
                                       "positive finite length: check radius, size and gap",
                                       edge));
  double total = 1;
  for (int d = 0; d < 3; ++d) {
    const double len = hi[d] - g.lo[d];
    if (!(len > 0)) throw ConfigError(key + ".hi", "must be above lo along every axis");
    // counted in double first: a tiny radius in a large region must not overflow the count
    const double n = std::floor(len / edge * (1 + 1e-12));
    if (n < 1)
      throw ConfigError(
          key, fmt::format("the region is thinner than one particle site ({:.6g} m) along an axis",
                           edge));
    total *= n;
    if (!(total <= kMaxSites))
      throw ConfigError(key, fmt::format("the region holds more than {:.3g} particle sites of "
                                         "{:.6g} m (the radius is tiny for the region): make the "
                                         "region smaller or the particles larger",
                                         kMaxSites, edge));
    g.n[d] = static_cast<long long>(n);
  }
  return g;
}

/// A source's velocity and spread, read from the case once per source (not per particle).
struct Velocity {
  std::array<double, 3> v{};
  double spread = 0;
  explicit Velocity(const Json& src)
      : v(vec(src["velocity"])), spread(src["velocity_spread"].get<double>()) {}
};

void applySpread(NewParticle& p, const Velocity& vel, std::uint64_t seed) {
  for (int d = 0; d < 3; ++d) {
    p.v[d] = vel.v[d];
    if (vel.spread > 0)
      p.v[d] +=
          vel.spread * (2.0 * uniform01(seed, static_cast<std::uint64_t>(p.id), 10 + d) - 1.0);
  }
}

/// Site-index range along d that may hold particles of [blockLo, blockHi].
void siteRange(double lo, double s, long long n, double bLo, double bHi, long long& a,
               long long& b) {
  // clamped in double before the cast (a block far from a region of tiny sites)
  const double top = static_cast<double>(n - 1);
  a = static_cast<long long>(std::clamp(std::floor((bLo - lo) / s) - 1, 0.0, top + 1));
  b = static_cast<long long>(std::clamp(std::floor((bHi - lo) / s) + 1, -1.0, top));
}

double normalCdf(double x) {
  return 0.5 * std::erfc(-x / std::sqrt(2.0));
}

/// x with normalCdf(x) = f (bisection: deterministic, and only run per new particle).
double normalQuantile(double f) {
  double lo = -40, hi = 40;
  for (int it = 0; it < 200 && hi - lo > 1e-15 * std::max(1.0, std::abs(lo)); ++it) {
    const double m = 0.5 * (lo + hi);
    if (normalCdf(m) < f)
      lo = m;
    else
      hi = m;
  }
  return 0.5 * (lo + hi);
}

}  // namespace

double SizeDist::rmin() const {
  switch (kind) {
    case Fixed:
      return r0;
    case Discrete: {
      double m = d[0];
      for (std::size_t i = 0; i < d.size(); ++i)
        if (cum[i] > (i ? cum[i - 1] : 0.0)) m = std::min(m, d[i]);
      return 0.5 * m;
    }
    default:
      return 0.5 * dmin;
  }
}

double SizeDist::rmax() const {
  switch (kind) {
    case Fixed:
      return r0;
    case Discrete: {
      double m = 0;
      for (std::size_t i = 0; i < d.size(); ++i)
        if (cum[i] > (i ? cum[i - 1] : 0.0)) m = std::max(m, d[i]);
      return 0.5 * m;
    }
    default:
      return 0.5 * dmax;
  }
}

double SizeDist::radius(double u) const {
  switch (kind) {
    case Fixed:
      return r0;
    case Discrete: {
      std::size_t i = 0;
      while (i + 1 < d.size() && !(u < cum[i])) ++i;
      return 0.5 * d[i];
    }
    case Uniform:
      return 0.5 * (dmin + (dmax - dmin) * u);
    case LogNormal: {
      const double dd = std::exp(mu + sigma * normalQuantile(fa + (fb - fa) * u));
      return 0.5 * std::clamp(dd, dmin, dmax);
    }
  }
  return r0;
}

SizeDist sizeDistribution(const Json& src, const std::string& key) {
  SizeDist sd;
  const auto& sz = src["size"];
  const std::string type = sz["type"].get<std::string>();
  const std::string sk = key + ".size";
  if (type == "fixed") {
    sd.r0 = src["radius"].get<double>();
    if (!(sd.r0 > 0)) throw ConfigError(key + ".radius", "must be positive (or give size)");
    return sd;
  }
  if (src.contains("radius") && src["radius"].get<double>() > 0)
    throw ConfigError(key + ".radius", "give radius or size, not both");
  if (type == "discrete") {
    sd.kind = SizeDist::Discrete;
    for (const auto& v : sz["diameters"]) sd.d.push_back(v.get<double>());
    if (sd.d.empty()) throw ConfigError(sk + ".diameters", "needs at least one diameter");
    std::vector<double> w;
    for (const auto& v : sz["weights"]) w.push_back(v.get<double>());
    if (w.empty()) w.assign(sd.d.size(), 1.0);
    if (w.size() != sd.d.size())
      throw ConfigError(sk + ".weights", "needs one weight per diameter");
    double tot = 0;
    for (double x : w) tot += x;
    if (!(tot > 0)) throw ConfigError(sk + ".weights", "needs a positive weight");
    double c = 0;
    for (double x : w) sd.cum.push_back((c += x) / tot);
    sd.cum.back() = 1.0;
  } else {
    sd.dmin = sz["min"].get<double>();
    sd.dmax = sz["max"].get<double>();
    if (!(sd.dmax >= sd.dmin)) throw ConfigError(sk + ".max", "must be >= min");
    if (type == "uniform") {
      sd.kind = SizeDist::Uniform;
    } else {
      sd.kind = SizeDist::LogNormal;
      sd.mu = std::log(sz["median"].get<double>());
      sd.sigma = sz["sigma"].get<double>();
      sd.fa = normalCdf((std::log(sd.dmin) - sd.mu) / sd.sigma);
      sd.fb = normalCdf((std::log(sd.dmax) - sd.mu) / sd.sigma);
      if (!(sd.fb - sd.fa > 1e-12))
        throw ConfigError(sk, "the cut-offs [min, max] hold no probability of this distribution");
    }
  }
  return sd;
}

std::vector<InflowInfo> inspectInflow(const Config& cfg, const GlobalGrid& grid, int nMaterials) {
  std::vector<InflowInfo> out;
  if (!cfg.has("particles.inflow")) return out;
  const auto& list = cfg.at("particles.inflow");
  for (std::size_t i = 0; i < list.size(); ++i) {
    const auto& src = list[i];
    const std::string key = fmt::format("particles.inflow[{}]", i);
    InflowInfo f;
    const std::string face = src["face"].get<std::string>();
    f.axis = face[0] - 'x';
    f.side = face.substr(1) == "hi" ? 1 : 0;
    f.a = f.axis == 0 ? 1 : 0;
    f.b = f.axis == 2 ? 1 : 2;
    if (grid.periodic[f.axis])
      throw ConfigError(key + ".face", "face " + face + " lies on a periodic axis");
    f.material = static_cast<int>(src["material"].get<long long>());
    if (f.material >= nMaterials)
      throw ConfigError(
          key + ".material",
          fmt::format("no such material ({} declared in particles.materials)", nMaterials));
    f.size = sizeDistribution(src, key);
    f.rate = src["rate"].get<double>();
    f.massRate = src["mass_rate"].get<double>();
    if ((f.rate > 0) == (f.massRate > 0))
      throw ConfigError(key + ".rate",
                        "give exactly one of rate (particles/s) and mass_rate "
                        "(kg/s), positive");
    f.start = src["start"].get<double>();
    f.end = src["end"].get<double>();
    if (f.end > 0 && !(f.end > f.start)) throw ConfigError(key + ".end", "must be after start");
    f.v = vec(src["velocity"]);
    f.spread = src["velocity_spread"].get<double>();
    f.temperature = src["temperature"].get<double>();
    const int ab[2] = {f.a, f.b};
    const auto& pmin = src["patch"]["min"];
    const auto& pmax = src["patch"]["max"];
    if (pmin.size() != pmax.size() || (pmin.size() != 0 && pmin.size() != 2))
      throw ConfigError(key + ".patch", "min and max need two numbers each (or neither)");
    for (int k = 0; k < 2; ++k) {
      const int d = ab[k];
      const double lo = grid.origin[d], hi = grid.origin[d] + grid.length[d];
      f.pmin[k] = pmin.empty() ? lo : pmin[k].get<double>();
      f.pmax[k] = pmax.empty() ? hi : pmax[k].get<double>();
      if (!(f.pmin[k] >= lo - 1e-12 * grid.length[d] && f.pmax[k] <= hi + 1e-12 * grid.length[d] &&
            f.pmax[k] > f.pmin[k]))
        throw ConfigError(key + ".patch", std::string("the rectangle along ") +
                                              static_cast<char>('x' + d) +
                                              " must satisfy box low <= min < max <= box high");
    }
    f.s = 2 * f.size.rmax() * (1 + src["gap"].get<double>());
    if (!(f.s > 0) || !std::isfinite(f.s))
      throw ConfigError(key + ".gap",
                        fmt::format("the insertion site (2 r_max (1 + gap) = {:.6g} m) is not a "
                                    "positive finite length",
                                    f.s));
    // counted in double first: a tiny radius on a large patch must not overflow the count
    const double na = std::floor((f.pmax[0] - f.pmin[0]) / f.s * (1 + 1e-12));
    const double nb = std::floor((f.pmax[1] - f.pmin[1]) / f.s * (1 + 1e-12));
    if (na < 1 || nb < 1)
      throw ConfigError(
          key + ".patch",
          fmt::format("the patch is narrower than one insertion site ({:.6g} m)", f.s));
    if (!(na * nb <= kMaxSites))
      throw ConfigError(key + ".patch",
                        fmt::format("the patch holds more than {:.3g} insertion sites of {:.6g} m "
                                    "(the radius is tiny for the patch)",
                                    kMaxSites, f.s));
    f.na = static_cast<long long>(na);
    f.nb = static_cast<long long>(nb);
    if (f.s > grid.length[f.axis])
      throw ConfigError(key + ".face", "the box is thinner than one insertion site");
    out.push_back(f);
  }
  return out;
}

std::vector<SourceInfo> inspectSources(const Config& cfg, const GlobalGrid& grid, int nMaterials) {
  const auto& sources = cfg.at("particles.sources");
  std::vector<SourceInfo> out;
  for (std::size_t i = 0; i < sources.size(); ++i) {
    const auto& src = sources[i];
    const std::string key = srcPath(i);
    const std::string type = src["type"].get<std::string>();
    SourceInfo info;
    if (src["material"].get<long long>() >= nMaterials)
      throw ConfigError(
          key + ".material",
          fmt::format("no such material ({} declared in particles.materials)", nMaterials));
    if (type == "list") {
      const auto& pos = src["positions"];
      if (pos.size() % 3 != 0)
        throw ConfigError(key + ".positions", "needs 3 numbers per particle");
      info.count = static_cast<long long>(pos.size() / 3);
      const auto& radii = src["radii"];
      if (!radii.empty()) {
        if (static_cast<long long>(radii.size()) != info.count)
          throw ConfigError(key + ".radii", "needs one radius per position");
        info.rmin = radii[0].get<double>();
        for (auto& r : radii) {
          info.rmax = std::max(info.rmax, r.get<double>());
          info.rmin = std::min(info.rmin, r.get<double>());
        }
      } else {
        info.rmax = info.rmin = src["radius"].get<double>();
        if (!(info.rmax > 0) && info.count > 0)
          throw ConfigError(key + ".radius", "must be positive (or give radii)");
      }
      const auto& vel = src["velocities"];
      if (!vel.empty() && static_cast<long long>(vel.size()) != 3 * info.count)
        throw ConfigError(key + ".velocities", "needs 3 numbers per position");
      for (long long k = 0; k < info.count; ++k)
        checkInside(
            grid,
            {pos[3 * k].get<double>(), pos[3 * k + 1].get<double>(), pos[3 * k + 2].get<double>()},
            key + ".positions");
    } else if (type == "lattice") {
      const auto lo = vec(src["lo"]);
      const auto sp = vec(src["spacing"]);
      std::array<double, 3> last{};
      double count = 1;  // in double first: three 32-bit counts overflow a long long
      for (int d = 0; d < 3; ++d) {
        const long long c = src["counts"][d].get<long long>();
        count *= static_cast<double>(c);
        last[d] = lo[d] + static_cast<double>(c - 1) * sp[d];
      }
      if (!(count <= kMaxSites))
        throw ConfigError(key + ".counts",
                          fmt::format("{:.4g} particles: more than a run can hold", count));
      info.count = 1;  // exact now: at most about 2^62, far from a long long's end
      for (int d = 0; d < 3; ++d) info.count *= src["counts"][d].get<long long>();
      const auto sd = sizeDistribution(src, key);
      info.rmax = sd.rmax();
      info.rmin = sd.rmin();
      checkInside(grid, lo, key + ".lo");
      checkInside(grid, last, key + ".counts");
    } else if (type == "random" || type == "layered") {
      info.count = src["count"].get<long long>();
      const auto sd = sizeDistribution(src, key);
      const double r = sd.rmax();
      info.rmax = r;
      info.rmin = sd.rmin();
      if (type == "random") {
        const double rm = src["radius_max"].get<double>();
        if (rm > 0 && !sd.fixed())
          throw ConfigError(key + ".radius_max", "give radius_max or size, not both");
        if (rm > 0 && rm < r) throw ConfigError(key + ".radius_max", "must be >= radius");
        info.rmax = std::max(r, rm);
      }
      checkInside(grid, vec(src["lo"]), key + ".lo");
      checkInside(grid, vec(src["hi"]), key + ".hi");
      const auto sg = siteGrid(src, 2 * info.rmax * (1 + src["gap"].get<double>()), key);
      if (info.count > sg.total())
        throw ConfigError(key + ".count",
                          fmt::format("{} particles do not fit: the region holds {} sites at "
                                      "this radius and gap",
                                      info.count, sg.total()));
    }
    out.push_back(info);
  }
  return out;
}

void generate(const Config& cfg, const std::vector<SourceInfo>& info, const Real3& blockLo,
              const Real3& blockHi, const std::function<bool(const double*)>& owns,
              const std::function<void(const NewParticle&)>& add) {
  const auto& sources = cfg.at("particles.sources");
  const auto seed = static_cast<std::uint64_t>(cfg.integer("particles.seed"));
  std::int64_t base = 0;
  for (std::size_t i = 0; i < sources.size(); ++i) {
    const auto& src = sources[i];
    const std::string type = src["type"].get<std::string>();
    const int mat = static_cast<int>(src["material"].get<long long>());
    const Velocity velocity(src);
    const double temperature = src["temperature"].get<double>();
    const auto put = [&](NewParticle& p) {
      p.temperature = temperature;
      if (owns(p.x)) add(p);
    };
    if (type == "list") {
      const auto& pos = src["positions"];
      const auto& radii = src["radii"];
      const auto& vel = src["velocities"];
      const double radius = radii.empty() ? src["radius"].get<double>() : 0.0;
      for (long long k = 0; k < info[i].count; ++k) {
        NewParticle p;
        p.id = base + k;
        p.material = mat;
        p.radius = radii.empty() ? radius : radii[k].get<double>();
        for (int d = 0; d < 3; ++d) p.x[d] = pos[3 * k + d].get<double>();
        applySpread(p, velocity, seed);
        if (!vel.empty())
          for (int d = 0; d < 3; ++d) p.v[d] = vel[3 * k + d].get<double>();
        put(p);
      }
    } else if (type == "lattice") {
      const auto lo = vec(src["lo"]);
      const auto sp = vec(src["spacing"]);
      const auto sd = sizeDistribution(src, srcPath(i));
      const double jitter = src["jitter"].get<double>();
      std::array<long long, 3> n{}, a{}, b{};
      for (int d = 0; d < 3; ++d) {
        n[d] = src["counts"][d].get<long long>();
        // sites are points lo + i sp: shift by half a spacing to reuse siteRange on cells
        siteRange(lo[d] - 0.5 * sp[d], sp[d], n[d], blockLo[d], blockHi[d], a[d], b[d]);
      }
      for (long long kz = a[2]; kz <= b[2]; ++kz)
        for (long long ky = a[1]; ky <= b[1]; ++ky)
          for (long long kx = a[0]; kx <= b[0]; ++kx) {
            NewParticle p;
            p.id = base + kx + n[0] * (ky + n[1] * kz);
            p.material = mat;
            p.radius = sd.radius(uniform01(seed, static_cast<std::uint64_t>(p.id), 1));
            const double r = p.radius;
            const long long k3[3] = {kx, ky, kz};
            for (int d = 0; d < 3; ++d) {
              const double free = std::max(0.0, 0.5 * sp[d] - r);
              p.x[d] = lo[d] + static_cast<double>(k3[d]) * sp[d];
              if (jitter > 0)
                p.x[d] += jitter * free *
                          (2.0 * uniform01(seed, static_cast<std::uint64_t>(p.id), 2 + d) - 1.0);
            }
            applySpread(p, velocity, seed);
            put(p);
          }
    } else if (type == "random" || type == "layered") {
      const bool random = type == "random";
      const auto sd = sizeDistribution(src, srcPath(i));
      const double r0 = sd.rmax();
      const double rmax = info[i].rmax;
      const auto sg = siteGrid(src, 2 * rmax * (1 + src["gap"].get<double>()), srcPath(i));
      const long long count = info[i].count;
      const double jitter = random ? 1.0 : src["jitter"].get<double>();
      const RandomPermutation perm(static_cast<std::uint64_t>(sg.total()),
                                   hash3(seed, static_cast<std::uint64_t>(i), 0x5eed));
      // layered: layer axis slowest, the two others in x, y, z order, the first fastest
      int ax = 2;
      if (!random) ax = src["axis"].get<std::string>()[0] - 'x';
      int o1 = ax == 0 ? 1 : 0, o2 = ax == 2 ? 1 : 2;
      std::array<long long, 3> a{}, b{};
      double blockSites = 1;
      for (int d = 0; d < 3; ++d) {
        siteRange(sg.lo[d], sg.s, sg.n[d], blockLo[d], blockHi[d], a[d], b[d]);
        blockSites *= static_cast<double>(std::max(0LL, b[d] - a[d] + 1));
      }
      // Particle k on site `site` (k3 its indices): made when k < count and the site is near
      // the block. The same particles either way; the loop is over the fewer of the block's
      // sites and the source's particles, so that the work is bounded by what is produced (a
      // tiny radius gives a huge number of sites, a dense fill as many particles as sites).
      const auto make = [&](long long k, const long long k3[3]) {
        NewParticle p;
        p.id = base + k;
        p.material = mat;
        const auto uid = static_cast<std::uint64_t>(p.id);
        if (!sd.fixed())
          p.radius = sd.radius(uniform01(seed, uid, 1));
        else
          p.radius = random && rmax > r0 ? r0 + (rmax - r0) * uniform01(seed, uid, 1) : r0;
        for (int d = 0; d < 3; ++d) {
          const double free = std::max(0.0, 0.5 * sg.s - p.radius);
          p.x[d] = sg.lo[d] + (static_cast<double>(k3[d]) + 0.5) * sg.s +
                   jitter * free * (2.0 * uniform01(seed, uid, 2 + d) - 1.0);
        }
        applySpread(p, velocity, seed);
        put(p);
      };
      if (blockSites <= static_cast<double>(count)) {
        for (long long kz = a[2]; kz <= b[2]; ++kz)
          for (long long ky = a[1]; ky <= b[1]; ++ky)
            for (long long kx = a[0]; kx <= b[0]; ++kx) {
              const long long k3[3] = {kx, ky, kz};
              long long k;
              if (random) {
                const long long site = kx + sg.n[0] * (ky + sg.n[1] * kz);
                k = static_cast<long long>(perm.inverse(static_cast<std::uint64_t>(site)));
              } else {
                k = k3[o1] + sg.n[o1] * (k3[o2] + sg.n[o2] * k3[ax]);
              }
              if (k < count) make(k, k3);
            }
      } else {
        for (long long k = 0; k < count; ++k) {
          long long k3[3];
          if (random) {
            const auto site = static_cast<long long>(perm(static_cast<std::uint64_t>(k)));
            k3[0] = site % sg.n[0];
            k3[1] = (site / sg.n[0]) % sg.n[1];
            k3[2] = site / sg.n[0] / sg.n[1];
          } else {
            k3[o1] = k % sg.n[o1];
            k3[o2] = (k / sg.n[o1]) % sg.n[o2];
            k3[ax] = k / sg.n[o1] / sg.n[o2];
          }
          bool near = true;
          for (int d = 0; d < 3; ++d) near = near && k3[d] >= a[d] && k3[d] <= b[d];
          if (near) make(k, k3);
        }
      }
    }
    base += info[i].count;
  }
}

SourceTotals sourceTotals(const std::vector<SourceInfo>& info) {
  SourceTotals t;
  for (const auto& s : info) {
    if (s.count > 0) t.rmax = std::max(t.rmax, s.rmax);
    t.count += s.count;
  }
  return t;
}

}  // namespace coloc::dem::detail
