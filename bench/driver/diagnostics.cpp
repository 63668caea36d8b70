#include "diagnostics.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>
#include <span>

namespace coloc {
namespace {

/// The k-th smallest (1-based) of the values held by all ranks together, exactly (a value of the
/// set, the same on any decomposition): bisection on the value with global counts. Collective.
double kthSmallest(const Comm& comm, std::span<const double> h, long long k, double lo0,
                   double hi0) {
  auto countAtMost = [&](double t) {
    long long c = 0;
    for (double v : h) c += v <= t ? 1 : 0;
    return comm.sum(c);
  };
  // Invariant: count(<= lo) < k <= count(<= hi).
  double lo = std::nextafter(lo0, -std::numeric_limits<double>::infinity()), hi = hi0;
  for (int it = 0; it < 200; ++it) {
    const double mid = lo + 0.5 * (hi - lo);
    if (!(mid > lo && mid < hi)) break;
    const long long c = countAtMost(mid);
    if (c >= k)
      hi = mid;
    else
      lo = mid;
    if (c == k) break;
  }
  // The largest value <= hi is the k-th smallest.
  double best = -std::numeric_limits<double>::infinity();
  for (double v : h)
    if (v <= hi) best = std::max(best, v);
  return comm.max(best);
}

}  // namespace

VerticalAxis verticalAxis(const std::array<double, 3>& grav, const GlobalGrid& g) {
  int axis = 0;
  for (int a = 1; a < 3; ++a)
    if (std::abs(grav[a]) > std::abs(grav[axis])) axis = a;
  if (grav[axis] == 0)
    for (int a = 0; a < 3; ++a)
      if (g.length[a] > g.length[axis]) axis = a;
  return {axis, grav[axis] <= 0};
}

BedDiagnostics bedDiagnostics(coupling::Simulation& sim, const Config& cfg) {
  BedDiagnostics d;
  const Decomposition& dec = sim.decomposition();
  const Comm& comm = dec.comm();
  const GlobalGrid& g = dec.grid();
  const auto grav = cfg.vec3("gravity");
  const VerticalAxis vertical = verticalAxis(grav, g);
  const int axis = vertical.axis;
  const bool up = vertical.up;  // heights grow along +axis
  d.axis = axis;
  const int layers = g.cells[axis];
  const double h = g.spacing(axis);
  auto height = [&](double x) {
    return up ? x - g.origin[axis] : g.origin[axis] + g.length[axis] - x;
  };
  auto layerOf = [&](double z) {
    return std::clamp(static_cast<int>(std::floor(z / h)), 0, layers - 1);
  };
  double area = 1;
  for (int a = 0; a < 3; ++a)
    if (a != axis) area *= g.length[a];
  const double rhoF = cfg.number("fluid.rho");
  const double gAbs = std::sqrt(grav[0] * grav[0] + grav[1] * grav[1] + grav[2] * grav[2]);

  d.solidProfile.assign(static_cast<std::size_t>(layers), 0.0);
  if (auto* dem = sim.particles()) {
    d.dem = true;
    const auto& p = dem->particles();
    const std::size_t n = p.nOwned;
    std::vector<double> z(n);
    double speedSum = 0, speedMax = 0, weight = 0, zmin = std::numeric_limits<double>::infinity(),
           zmax = -zmin;
    for (std::size_t i = 0; i < n; ++i) {
      z[i] = height(p.x[axis][i]);
      zmin = std::min(zmin, z[i]);
      zmax = std::max(zmax, z[i]);
      const double s =
          std::sqrt(p.v[0][i] * p.v[0][i] + p.v[1][i] * p.v[1][i] + p.v[2][i] * p.v[2][i]);
      speedSum += s;
      speedMax = std::max(speedMax, s);
      const double vol = 4.0 / 3.0 * std::numbers::pi * p.radius[i] * p.radius[i] * p.radius[i];
      weight += p.mass[i] - (sim.fluid() ? rhoF * vol : 0.0);
      d.solidProfile[static_cast<std::size_t>(layerOf(z[i]))] += vol;
    }
    double sums[3] = {static_cast<double>(n), speedSum, weight};
    comm.sumInPlace(std::span<double>(sums, 3));
    comm.sumInPlace(std::span<double>(d.solidProfile));
    d.particles = static_cast<long long>(sums[0]);
    d.maxSpeed = comm.max(speedMax);
    zmin = comm.min(zmin);
    zmax = comm.max(zmax);
    d.contactsPerParticle =
        static_cast<double>(comm.sum(dem->localContacts())) / std::max(1.0, sums[0]);
    if (d.particles > 0) {
      d.meanSpeed = sums[1] / sums[0];
      d.lowestParticle = zmin;
      const long long k = static_cast<long long>(std::ceil(0.95 * sums[0]));
      d.bedHeight = kthSmallest(comm, z, std::max(1LL, k), zmin, zmax);
    }
    d.bedWeight = sums[2] * gAbs / area;
    const double layerVolume = area * h;
    for (double& s : d.solidProfile) s /= layerVolume;
    d.solidMax = *std::max_element(d.solidProfile.begin(), d.solidProfile.end());
    const int top = d.particles > 0 ? layerOf(d.bedHeight) : -1;
    double s = 0;
    for (int l = 0; l <= top; ++l) s += d.solidProfile[static_cast<std::size_t>(l)];
    d.solidBedMean = top >= 0 ? s / (top + 1) : 0.0;
  }
  if (auto* fluid = sim.fluid()) {
    d.fluid = true;
    const CellField& pf = fluid->fields().p;
    std::vector<double> plane(static_cast<std::size_t>(layers), 0.0);
    const auto lo = dec.lo();
    forEach(pf.interior(), [&](int i, int j, int k) {
      const int idx[3] = {i, j, k};
      const int gk = lo[axis] + idx[axis];
      plane[static_cast<std::size_t>(up ? gk : layers - 1 - gk)] += pf(i, j, k);
    });
    comm.sumInPlace(std::span<double>(plane));
    const double perLayer = static_cast<double>(g.cellCount()) / layers;
    for (double& v : plane) v /= perLayer;
    // Body acceleration of the fluid against the height direction (9.81 for gravity -z, up +z).
    const double down = (up ? -1.0 : 1.0) * (grav[axis] + cfg.vec3("fluid.body_force")[axis]);
    d.dpBox = rhoF * (plane.front() - plane.back());
    d.dpBoxExcess = d.dpBox - rhoF * down * (layers - 1) * h;
    if (d.particles > 0) {
      const int l0 = layerOf(d.lowestParticle), l1 = layerOf(d.bedHeight);
      d.dpBed = rhoF * (plane[static_cast<std::size_t>(l0)] - plane[static_cast<std::size_t>(l1)]);
      d.dpBedExcess = d.dpBed - rhoF * down * (l1 - l0) * h;
    }
  }
  return d;
}

std::vector<std::string> bedDiagnosticsColumns() {
  return {"bed_height",
          "mean_speed",
          "max_speed",
          "contacts_per_particle",
          "dp_bed_pa",
          "dp_box_pa",
          "dp_bed_excess_pa",
          "dp_box_excess_pa",
          "bed_weight_pa",
          "solid_fraction_max",
          "solid_fraction_bed_mean"};
}

std::vector<double> bedDiagnosticsRow(const BedDiagnostics& d) {
  return {d.bedHeight, d.meanSpeed, d.maxSpeed,    d.contactsPerParticle,
          d.dpBed,     d.dpBox,     d.dpBedExcess, d.dpBoxExcess,
          d.bedWeight, d.solidMax,  d.solidBedMean};
}

Json bedDiagnosticsJson(const BedDiagnostics& d) {
  Json j;
  j["axis"] = std::string(1, "xyz"[d.axis]);
  j["particles"] = d.particles;
  if (d.dem) {
    j["bed_height_m"] = d.bedHeight;
    j["lowest_particle_m"] = d.lowestParticle;
    j["mean_speed_m_per_s"] = d.meanSpeed;
    j["max_speed_m_per_s"] = d.maxSpeed;
    j["contacts_per_particle"] = d.contactsPerParticle;
    j["bed_weight_pa"] = d.bedWeight;
    j["solid_fraction_max"] = d.solidMax;
    j["solid_fraction_bed_mean"] = d.solidBedMean;
    j["solid_fraction_profile"] = d.solidProfile;
  }
  if (d.fluid) {
    j["dp_box_pa"] = d.dpBox;
    j["dp_box_excess_pa"] = d.dpBoxExcess;
    if (d.dem) {
      j["dp_bed_pa"] = d.dpBed;
      j["dp_bed_excess_pa"] = d.dpBedExcess;
    }
  }
  return j;
}

}  // namespace coloc
