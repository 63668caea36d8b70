// The "particles.*" keys of the case file (see docs/dem.md for the meaning of each choice).
#include <cmath>

#include "coloc/dem/dem.hpp"

namespace coloc::dem {

namespace {
/// A temperature (K): above absolute zero, and below what the enthalpy sums hold with round-off
/// to spare (1e6 K: hotter than any material stays solid).
const Range kTemperatureRange = Range::openClosed(0.0, 1e6);

Schema commonSource() {
  Schema s;
  s.integer("material", 0, "index into particles.materials", Range::nonNegative());
  s.vec3("velocity", std::array<double, 3>{0, 0, 0}, "initial velocity (m/s)");
  s.number("velocity_spread", 0.0,
           "each velocity component gets a uniform random addition in [-spread, spread] (m/s), "
           "drawn from the particle's id",
           Range::nonNegative());
  s.number("temperature", 293.15,
           "initial temperature of the source's particles (K); used when particles.heat is true",
           kTemperatureRange);
  return s;
}

/// The size distribution of a source (diameters, by number); "fixed" uses the source's radius.
void sizeKey(Schema& s) {
  std::map<std::string, Schema> t;
  t["fixed"] = Schema();
  Schema disc;
  disc.numberList("diameters", std::nullopt, "the diameters (m)", Range::positive());
  disc.numberList("weights", std::vector<double>{},
                  "relative number of particles of each diameter (default: equal)",
                  Range::nonNegative());
  t["discrete"] = disc;
  Schema uni;
  uni.number("min", std::nullopt, "smallest diameter (m)", Range::positive());
  uni.number("max", std::nullopt, "largest diameter (m)", Range::positive());
  t["uniform"] = uni;
  Schema ln;
  ln.number("median", std::nullopt, "median diameter exp(mu) of the untruncated distribution (m)",
            Range::positive());
  ln.number("sigma", std::nullopt, "standard deviation of ln(d)", Range::positive());
  ln.number("min", std::nullopt, "lower cut-off diameter (m)", Range::positive());
  ln.number("max", std::nullopt, "upper cut-off diameter (m)", Range::positive());
  t["lognormal"] = ln;
  s.variant("size", t, "fixed",
            "diameter distribution by number, drawn per particle from its id: fixed (the radius "
            "key), discrete{diameters, weights}, uniform{min, max} (uniform in d), "
            "lognormal{median, sigma, min, max} (ln d normal, truncated to [min, max])");
}
}  // namespace

void declareConfig(Schema& s) {
  s.number("particles.dt", 1e-5,
           "DEM time step (s); refused above particles.dt_fraction of the "
           "Rayleigh time (Hertz) or of the collision time (linear)",
           Range::positive());
  s.number("particles.dt_fraction", 0.2,
           "largest allowed dt as a fraction of the Rayleigh time (hertz_mindlin) or of the "
           "linear collision time pi sqrt(m*/k_n) (linear)",
           Range::openClosed(0, 1));
  s.number("particles.skin", 0.2,
           "Verlet skin as a fraction of the largest particle diameter; lists are rebuilt when a "
           "particle moved more than skin/2; at most 10",
           Range::openClosed(0.0, 10.0));
  s.number("particles.prune_margin", 0.05,
           "gap below which a Verlet-list entry stays in the pruned inner list, as a fraction of "
           "the largest particle diameter: the force passes visit only those entries until any "
           "two particles may have closed it (bit for bit the same results); 0: no inner list",
           Range::between(0.0, 10.0));
  s.string("particles.force_isa", "scalar",
           "how the force pass tests the list entries: scalar (entry by entry, the build's "
           "target), avx512 (eight entries of a row at a time; refused on a CPU without AVX-512), "
           "widest (avx512 where the CPU has it, else scalar); the same results, bit for bit. "
           "avx512 pays where rows hold many entries that do not touch (a settled bed: ~5 %), "
           "scalar where most touch (case3-small in contact: avx512 is ~15 % slower there)",
           {"scalar", "avx512", "widest"});
  s.string("particles.contact_model", "hertz_mindlin",
           "hertz_mindlin: Hertz normal + Mindlin no-slip tangential with history (LIGGGHTS "
           "formulas); linear: spring-dashpot with history",
           {"hertz_mindlin", "linear"});
  s.number("particles.linear.kn", 1e3, "normal stiffness of the linear model (N/m)",
           Range::positive());
  s.number("particles.linear.kt_ratio", 2.0 / 7.0, "k_t / k_n of the linear model",
           Range::nonNegative());
  {
    Schema m;
    m.number("density", 2500.0, "particle density (kg/m^3)", Range::positive());
    m.number("young", 1e7, "Young's modulus E (Pa)", Range::positive());
    m.number("poisson", 0.3, "Poisson ratio", Range::between(0.0, 0.5));
    m.number("restitution", 0.9, "coefficient of restitution e", Range::openClosed(0.0, 1.0));
    m.number("friction", 0.5, "Coulomb friction coefficient", Range::nonNegative());
    m.number("rolling_friction", 0.0,
             "rolling resistance coefficient (constant directional torque); 0: off",
             Range::nonNegative());
    // Optional (no default, no sentinel): required when particles.heat is true. Bounded far
    // above any real material, so that no value makes the enthalpies or conductances overflow.
    m.optionalNumber("heat_capacity",
                     "specific heat capacity c_p (J/(kg K)); required when particles.heat is true",
                     Range::openClosed(0.0, 1e8));
    m.optionalNumber("conductivity",
                     "thermal conductivity k (W/(m K)) for contact conduction and the Biot "
                     "number; required when particles.heat is true",
                     Range::openClosed(0.0, 1e6));
    s.list("particles.materials", {{"", m}},
           "materials: [{density, young, poisson, restitution, friction, rolling_friction}]");
  }
  s.boolean("particles.heat", false,
            "particle temperature (lumped capacitance, per-material heat_capacity and "
            "conductivity, per-source temperature) and conduction through contacts; false: no "
            "temperature at all (nothing computed, stored or sent)");
  s.boolean("particles.contact_conduction", true,
            "with particles.heat: heat conducted through particle-particle and particle-wall "
            "contacts (Batchelor & O'Brien: H = 2 k_eff a, a the Hertz contact radius)");
  // (above 0 K: a 0 once meant "adiabatic"; such a case file is refused rather than read as a
  // wall at absolute zero)
  s.optionalNumber("particles.wall_temperature",
                   "with particles.heat: temperature of every wall (K), which conducts through its "
                   "contacts with the wall_material's conductivity; absent: adiabatic walls",
                   kTemperatureRange);
  s.integer("particles.wall_material", 0, "material of the box walls", Range::nonNegative());
  s.boolean("particles.walls", true,
            "planar walls on every non-periodic face of the box whose particles.boundary is auto");
  {
    const char* faces[6] = {"xlo", "xhi", "ylo", "yhi", "zlo", "zhi"};
    for (const char* f : faces)
      s.string(std::string("particles.boundary.") + f, "auto",
               std::string("particle condition at the ") + f +
                   " face: auto (periodic on a periodic axis, else a wall when particles.walls), "
                   "wall, outflow (a particle whose centre leaves is removed, counted, its mass "
                   "reported), periodic (only on a periodic axis)",
               {"auto", "wall", "outflow", "periodic"});
  }
  s.integer("particles.bin_cells", 0,
            "bin edge = this many CFD cells (0: automatic, the smallest bin that coincides with "
            "the cells and holds the interaction range)",
            Range::between(0, 1e6));
  s.integer("particles.bin_split", 0,
            "bin edge = CFD cell / this number (0: automatic); exclusive with bin_cells",
            Range::between(0, 1024));
  s.number("particles.overlap_limit", 0.2,
           "largest overlap allowed, as a fraction of the smaller radius; beyond it the run stops",
           Range::positive());
  s.integer("particles.seed", 12345, "seed of the particle generation streams",
            Range::nonNegative());
  {
    std::map<std::string, Schema> src;
    Schema list = commonSource();
    list.numberList("positions", std::nullopt, "x0 y0 z0 x1 y1 z1 ... (m)");
    list.number("radius", 0.0, "radius of every particle (m), unless radii is given",
                Range::nonNegative());
    list.numberList("radii", std::vector<double>{}, "one radius per particle (m)",
                    Range::positive());
    list.numberList("velocities", std::vector<double>{},
                    "vx0 vy0 vz0 ... (m/s), overrides velocity", Range::any());
    src["list"] = list;

    Schema lat = commonSource();
    lat.vec3("lo", std::nullopt, "centre of the first particle (m)");
    lat.intVec3("counts", std::nullopt, "particles along x, y, z", Range::atLeast(1));
    lat.vec3("spacing", std::nullopt, "centre distance along x, y, z (m)", Range::positive());
    lat.number("radius", 0.0, "radius (m); required unless size is given", Range::nonNegative());
    sizeKey(lat);
    lat.number("jitter", 0.0,
               "random displacement per axis as a fraction of the free gap (spacing/2 - radius)",
               Range::between(0.0, 1.0));
    src["lattice"] = lat;

    Schema rnd = commonSource();
    rnd.vec3("lo", std::nullopt, "region lower corner (m)");
    rnd.vec3("hi", std::nullopt, "region upper corner (m)");
    rnd.integer("count", std::nullopt, "number of particles", Range::nonNegative());
    rnd.number("radius", 0.0,
               "radius, or smallest radius with radius_max (m); required unless size is given",
               Range::nonNegative());
    sizeKey(rnd);
    rnd.number("radius_max", 0.0, "largest radius for a uniform radius distribution (0: mono)",
               Range::nonNegative());
    rnd.number("gap", 0.05,
               "sites are cubes of edge 2 r_max (1 + gap); each particle sits at a random free "
               "position inside its own randomly chosen site (non-overlapping by construction)",
               Range::nonNegative());
    src["random"] = rnd;

    Schema lay = commonSource();
    lay.vec3("lo", std::nullopt, "region lower corner (m)");
    lay.vec3("hi", std::nullopt, "region upper corner (m)");
    lay.integer("count", std::nullopt, "number of particles", Range::nonNegative());
    lay.number("radius", 0.0, "radius (m); required unless size is given", Range::nonNegative());
    sizeKey(lay);
    lay.string("axis", "z", "layers are stacked along this axis, from lo upwards", {"x", "y", "z"});
    lay.number("gap", 0.05, "site edge = 2 r (1 + gap)", Range::nonNegative());
    lay.number("jitter", 0.5, "random displacement per axis as a fraction of the free gap",
               Range::between(0.0, 1.0));
    src["layered"] = lay;
    s.list("particles.sources", src,
           "particle sources: {type: list|lattice|random|layered, ...}; global ids follow the "
           "order of the sources");
  }
  {
    Schema in = commonSource();
    in.string("face", std::nullopt, "the face the particles enter through",
              {"xlo", "xhi", "ylo", "yhi", "zlo", "zhi"});
    in.numberList("patch.min", std::vector<double>{},
                  "lower corner of the inlet rectangle in the face's two other coordinates, in "
                  "axis order (xlo/xhi: y, z; ylo/yhi: x, z; zlo/zhi: x, y) (m); default: the "
                  "whole face",
                  Range::any());
    in.numberList("patch.max", std::vector<double>{}, "upper corner of the rectangle (m)",
                  Range::any());
    in.number("rate", 0.0, "particles per second (exclusive with mass_rate)", Range::nonNegative());
    in.number("mass_rate", 0.0,
              "kilograms per second: a particle is due when the mass of the particles due so far "
              "is below mass_rate (t - start) (exclusive with rate)",
              Range::nonNegative());
    in.number("start", 0.0, "time the inflow starts (s)", Range::nonNegative());
    in.number("end", 0.0, "time the inflow stops (s; 0: never)", Range::nonNegative());
    in.number("radius", 0.0, "radius (m); required unless size is given", Range::nonNegative());
    in.number("gap", 0.05,
              "insertion sites are squares of edge 2 r_max (1 + gap) in the layer of that "
              "thickness along the face; a due particle enters on its own site at a random "
              "offset, or waits (in id order) while a particle already there would overlap it",
              Range::nonNegative());
    sizeKey(in);
    s.list("particles.inflow", {{"", in}},
           "particle inflow sources: [{face, patch{min, max}, rate|mass_rate, velocity, radius|"
           "size, start, end, ...}]; ids follow those of particles.sources");
  }
}

}  // namespace coloc::dem
