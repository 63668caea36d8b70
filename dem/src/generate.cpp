#include "generate.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <string>

#include "rng.hpp"

namespace coloc::dem::detail {
namespace {

std::string srcPath(std::size_t i) {
  return "particles.sources[" + std::to_string(i) + "]";
}

std::array<double, 3> vec(const Json& j) {
  return {j[0].get<double>(), j[1].get<double>(), j[2].get<double>()};
}

void checkInside(const GlobalGrid& g, const std::array<double, 3>& p, const std::string& key) {
  for (int d = 0; d < 3; ++d) {
    const double lo = g.origin[d], hi = g.origin[d] + g.length[d];
    if (!(p[d] >= lo && p[d] <= hi))
      throw ConfigError(key, "point (" + std::to_string(p[0]) + ", " + std::to_string(p[1]) + ", " +
                                 std::to_string(p[2]) + ") lies outside the box");
  }
}

struct SiteGrid {
  std::array<double, 3> lo{};
  double s = 1;
  std::array<long long, 3> n{1, 1, 1};
  long long total() const { return n[0] * n[1] * n[2]; }
};

SiteGrid siteGrid(const Json& src, double edge, const std::string& key) {
  SiteGrid g;
  g.lo = vec(src["lo"]);
  const auto hi = vec(src["hi"]);
  g.s = edge;
  for (int d = 0; d < 3; ++d) {
    const double len = hi[d] - g.lo[d];
    if (!(len > 0)) throw ConfigError(key + ".hi", "must be above lo along every axis");
    g.n[d] = static_cast<long long>(std::floor(len / edge * (1 + 1e-12)));
    if (g.n[d] < 1)
      throw ConfigError(key, "the region is thinner than one particle site (" +
                                 std::to_string(edge) + " m) along an axis");
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
  a = std::max(0LL, static_cast<long long>(std::floor((bLo - lo) / s)) - 1);
  b = std::min(n - 1, static_cast<long long>(std::floor((bHi - lo) / s)) + 1);
}

}  // namespace

std::vector<SourceInfo> inspectSources(const Config& cfg, const GlobalGrid& grid, int nMaterials) {
  const auto& sources = cfg.at("particles.sources");
  std::vector<SourceInfo> out;
  for (std::size_t i = 0; i < sources.size(); ++i) {
    const auto& src = sources[i];
    const std::string key = srcPath(i);
    const std::string type = src["type"].get<std::string>();
    SourceInfo info;
    if (src["material"].get<long long>() >= nMaterials)
      throw ConfigError(key + ".material", "no such material (" + std::to_string(nMaterials) +
                                               " declared in particles.materials)");
    if (type == "list") {
      const auto& pos = src["positions"];
      if (pos.size() % 3 != 0)
        throw ConfigError(key + ".positions", "needs 3 numbers per particle");
      info.count = static_cast<long long>(pos.size() / 3);
      const auto& radii = src["radii"];
      if (!radii.empty()) {
        if (static_cast<long long>(radii.size()) != info.count)
          throw ConfigError(key + ".radii", "needs one radius per position");
        for (auto& r : radii) info.rmax = std::max(info.rmax, r.get<double>());
      } else {
        info.rmax = src["radius"].get<double>();
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
      info.count = 1;
      for (int d = 0; d < 3; ++d) {
        const long long c = src["counts"][d].get<long long>();
        info.count *= c;
        last[d] = lo[d] + static_cast<double>(c - 1) * sp[d];
      }
      info.rmax = src["radius"].get<double>();
      checkInside(grid, lo, key + ".lo");
      checkInside(grid, last, key + ".counts");
    } else if (type == "random" || type == "layered") {
      info.count = src["count"].get<long long>();
      const double r = src["radius"].get<double>();
      info.rmax = r;
      if (type == "random") {
        const double rm = src["radius_max"].get<double>();
        if (rm > 0 && rm < r) throw ConfigError(key + ".radius_max", "must be >= radius");
        info.rmax = std::max(r, rm);
      }
      checkInside(grid, vec(src["lo"]), key + ".lo");
      checkInside(grid, vec(src["hi"]), key + ".hi");
      const auto sg = siteGrid(src, 2 * info.rmax * (1 + src["gap"].get<double>()), key);
      if (info.count > sg.total())
        throw ConfigError(key + ".count", std::to_string(info.count) +
                                              " particles do not fit: "
                                              "the region holds " +
                                              std::to_string(sg.total()) +
                                              " sites at this radius and gap");
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
    const auto put = [&](NewParticle& p) {
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
      const double r = src["radius"].get<double>();
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
            p.radius = r;
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
      const double r0 = src["radius"].get<double>();
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
      for (int d = 0; d < 3; ++d)
        siteRange(sg.lo[d], sg.s, sg.n[d], blockLo[d], blockHi[d], a[d], b[d]);
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
            if (k >= count) continue;
            NewParticle p;
            p.id = base + k;
            p.material = mat;
            const auto uid = static_cast<std::uint64_t>(p.id);
            p.radius = random && rmax > r0 ? r0 + (rmax - r0) * uniform01(seed, uid, 1) : r0;
            for (int d = 0; d < 3; ++d) {
              const double free = std::max(0.0, 0.5 * sg.s - p.radius);
              p.x[d] = sg.lo[d] + (static_cast<double>(k3[d]) + 0.5) * sg.s +
                       jitter * free * (2.0 * uniform01(seed, uid, 2 + d) - 1.0);
            }
            applySpread(p, velocity, seed);
            put(p);
          }
    }
    base += info[i].count;
  }
}

}  // namespace coloc::dem::detail
