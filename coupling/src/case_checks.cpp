// Whole-case checks and the memory estimate: coupling/include/coloc/coupling/case_checks.hpp.
#include "coloc/coupling/case_checks.hpp"

#include <fmt/format.h>
#include <sys/resource.h>

#include <algorithm>
#include <cmath>
#include <fstream>
#include <sstream>

#include "coloc/core/error.hpp"
#include "coloc/core/run_config.hpp"
#include "coloc/coupling/self_velocity.hpp"
#include "coloc/fv/fluid.hpp"
#include "coloc/io/checkpoint_file.hpp"
#include "coloc/io/h5io.hpp"
#include "coloc/partition/setup.hpp"
#include "coloc/partition/strategy.hpp"

namespace coloc::coupling {

namespace {

constexpr double kPi = 3.14159265358979323846;
const char* const kFaces[6] = {"xlo", "xhi", "ylo", "yhi", "zlo", "zhi"};

std::string num(double v) {
  return fmt::format("{:g}", v);
}

void checkName(const Config& cfg) {
  const std::string name = cfg.string("name");
  const char* why = nullptr;
  if (name.empty())
    why = "is empty";
  else if (name == "." || name == "..")
    why = "is . or ..";
  else if (name.find('/') != std::string::npos || name.find('\\') != std::string::npos)
    why = "contains a path separator";
  else if (std::any_of(name.begin(), name.end(),
                       [](char c) { return static_cast<unsigned char>(c) < 0x20; }))
    why = "contains a control character";
  else if (name.size() > 200)
    why = "is longer than 200 characters";
  if (why)
    throw ConfigError("name", "'" + name + "' " + why +
                                  ": the case name must be a plain name (it names the output "
                                  "folder out/<name>; give --out to write elsewhere)");
}

void checkTimeSteps(const Config& cfg, std::vector<std::string>& notes) {
  const RunMode mode = runMode(cfg);
  if (mode != RunMode::Coupled && mode != RunMode::DummyDem) return;
  const double dtf = cfg.number("fluid.dt"), dtp = cfg.number("particles.dt");
  const long long sub = cfg.integer("coupling.dem_substeps");
  const bool adaptive = cfg.boolean("fluid.adaptive_dt");
  if (sub > 0) {
    const double step = static_cast<double>(sub) * dtp;
    if (adaptive || std::fabs(step - dtf) > 1e-9 * step)
      notes.push_back(fmt::format(
          "coupling.dem_substeps = {0}: every CFD step is {0} x particles.dt = {1} s; fluid.dt = "
          "{2} s{3} not used",
          sub, num(step), num(dtf), adaptive ? " and fluid.adaptive_dt are" : " is"));
    return;
  }
  if (adaptive) {
    notes.push_back(
        "fluid.adaptive_dt: each CFD step is the fluid's step rounded down to a "
        "whole number of particles.dt = " +
        num(dtp) + " s (at least one)");
    return;
  }
  const double ratio = dtf / dtp;
  if (!(ratio <= 1e6))  // a sub-step count is an integer of the time loop
    throw ConfigError("fluid.dt", num(dtf) + " s is " + num(ratio) + " particles.dt = " + num(dtp) +
                                      " s: more than 1e6 DEM steps a CFD step");
  const double n = std::round(ratio);
  if (n >= 1 && std::fabs(ratio - n) <= 1e-9 * ratio) return;
  const double lo = std::max(1.0, std::floor(ratio));
  std::string use = num(lo * dtp) + " s (" + num(lo) + (lo == 1 ? " DEM step)" : " DEM steps)");
  if (ratio > 1) use += " or " + num((lo + 1) * dtp) + " s (" + num(lo + 1) + ")";
  throw ConfigError("fluid.dt", num(dtf) + " s is not a whole multiple of particles.dt = " +
                                    num(dtp) + " s (" + num(ratio) +
                                    " DEM steps): a CFD step is a whole number of DEM steps; "
                                    "use fluid.dt = " +
                                    use + ", or set coupling.dem_substeps");
}

void checkBoundaries(const Config& cfg, std::vector<std::string>& notes) {
  if (runMode(cfg) == RunMode::ParticlesOnly) return;
  fv::checkBoundaryConfig(cfg, gridFromConfig(cfg));  // types and periodicity first
  std::string inlet;
  bool outlet = false;
  const char* const periodicKey[3] = {"domain.periodic.x", "domain.periodic.y",
                                      "domain.periodic.z"};
  for (int i = 0; i < 6; ++i) {
    const char* f = kFaces[i];
    const std::string type =
        cfg.at(std::string("fluid.boundary.") + f).at("type").get<std::string>();
    // (an inlet on a periodic face is refused with its own message when the fluid is built)
    if (type == "inlet" && inlet.empty() && !cfg.boolean(periodicKey[i / 2]))
      inlet = std::string("fluid.boundary.") + f;
    if (type == "outlet") outlet = true;
  }
  // Patches (fluid.patches) are inlets and outlets too, on faces that are not periodic.
  const Json patches = cfg.has("fluid.patches") ? cfg.at("fluid.patches") : Json::array();
  for (std::size_t k = 0; k < patches.size(); ++k) {
    const std::string type = patches[k].at("type").get<std::string>();
    if (type == "inlet" && inlet.empty()) inlet = fmt::format("fluid.patches.{}", k);
    if (type == "outlet") outlet = true;
  }
  if (!inlet.empty() && !outlet)
    throw ConfigError(
        inlet,
        "an inlet but no outlet on any face: the inflow has nowhere to go "
        "(incompressible fluid); make a face an outlet (type outlet) or add an outlet patch");
  if (runMode(cfg) == RunMode::FluidOnly && cfg.at("particles.sources").size() > 0)
    notes.push_back("run.mode = fluid: particles.sources are not used");
}

/// The simulated time the run covers from the initial condition (s): run.steps times the
/// largest step (a coupled step: dem_substeps DEM steps, else fluid.dt, which is also the largest
/// adaptive step), or run.end_time.
double runDuration(const Config& cfg) {
  const long long steps = cfg.integer("run.steps");
  if (steps <= 0) return cfg.number("run.end_time");
  const double dtp = cfg.number("particles.dt");
  const auto sub = static_cast<double>(cfg.integer("coupling.dem_substeps"));
  const double step = runMode(cfg) == RunMode::ParticlesOnly
                          ? std::max(1.0, sub) * dtp
                          : (sub > 0 ? sub * dtp : std::max(cfg.number("fluid.dt"), dtp));
  return static_cast<double>(steps) * step;
}

/// One particles.inflow entry as far as counts go, from the case file alone (the DEM parses and
/// checks the same keys again, with the box, when it is built).
struct InflowCount {
  std::string key;      // particles.inflow[n]
  std::string rateKey;  // its .rate or .mass_rate
  double count = 0;     // particles due over the run (an upper bound for mass_rate)
  double perStep = 0;   // particles due a DEM step (a lower bound for mass_rate)
  double sites = 0;     // insertion sites of the patch
  double rmin = 0;
};

std::vector<InflowCount> inflowCounts(const Config& cfg) {
  std::vector<InflowCount> out;
  if (runMode(cfg) == RunMode::FluidOnly || !cfg.has("particles.inflow")) return out;
  const GlobalGrid g = gridFromConfig(cfg);
  const Json& mats = cfg.at("particles.materials");
  const double T = runDuration(cfg), dtp = cfg.number("particles.dt");
  const Json& list = cfg.at("particles.inflow");
  for (std::size_t i = 0; i < list.size(); ++i) {
    const Json& src = list[i];
    InflowCount c;
    c.key = fmt::format("particles.inflow[{}]", i);
    // radii: fixed (radius), discrete (diameters), uniform and lognormal (min, max)
    const Json& sz = src.at("size");
    const std::string type = sz.at("type").get<std::string>();
    double rmin = 0, rmax = 0;
    if (type == "fixed") {
      rmin = rmax = src.at("radius").get<double>();
    } else if (type == "discrete") {
      for (const auto& d : sz.at("diameters")) {
        rmin = rmin > 0 ? std::min(rmin, 0.5 * d.get<double>()) : 0.5 * d.get<double>();
        rmax = std::max(rmax, 0.5 * d.get<double>());
      }
    } else {
      rmin = 0.5 * sz.at("min").get<double>();
      rmax = 0.5 * sz.at("max").get<double>();
    }
    if (!(rmin > 0) || !(rmax >= rmin)) continue;  // refused with its key by the DEM's checks
    c.rmin = rmin;
    const auto mat = static_cast<std::size_t>(src.at("material").get<long long>());
    const double rho = mat < mats.size() ? mats[mat].at("density").get<double>() : 0.0;
    const double rate = src.at("rate").get<double>(), massRate = src.at("mass_rate").get<double>();
    const double start = src.at("start").get<double>(), end = src.at("end").get<double>();
    const double stop = end > 0 ? std::min(end, T) : T;
    const double span = std::max(0.0, stop - start);
    const double mMin = rho * 4.0 / 3.0 * kPi * rmin * rmin * rmin;
    const double mMax = rho * 4.0 / 3.0 * kPi * rmax * rmax * rmax;
    if (rate > 0) {
      c.rateKey = c.key + ".rate";
      c.count = rate * span;
      c.perStep = rate * dtp;
    } else if (massRate > 0 && mMin > 0) {
      c.rateKey = c.key + ".mass_rate";
      c.count = massRate * span / mMin;
      c.perStep = massRate * dtp / mMax;
    } else {
      continue;
    }
    // the sites of the patch (the whole face by default), as the DEM lays them
    const std::string face = src.at("face").get<std::string>();
    const int axis = face[0] - 'x';
    const int ab[2] = {axis == 0 ? 1 : 0, axis == 2 ? 1 : 2};
    const double s = 2 * rmax * (1 + src.at("gap").get<double>());
    const Json& pmin = src.at("patch").at("min");
    const Json& pmax = src.at("patch").at("max");
    c.sites = 1;
    for (int k = 0; k < 2; ++k) {
      const int d = ab[k];
      const bool whole = pmin.size() != 2 || pmax.size() != 2;
      const double w = whole ? g.length[d] : pmax[k].get<double>() - pmin[k].get<double>();
      c.sites *= std::max(0.0, std::floor(w / s * (1 + 1e-12)));
    }
    out.push_back(c);
  }
  return out;
}

/// At most this many particles enter through all the inflows of one run (counts, ids and the
/// waiting lists stay far inside 64-bit integers and doubles).
constexpr double kMaxInflowParticles = 1e9;

void checkInflow(const Config& cfg) {
  double total = 0;
  for (const InflowCount& c : inflowCounts(cfg)) {
    total += c.count;
    if (!(c.count <= kMaxInflowParticles) || !(total <= kMaxInflowParticles))
      throw ConfigError(c.rateKey, "over the " + num(runDuration(cfg)) +
                                       " s the run covers, the inflows would insert about " +
                                       num(total) +
                                       " particles, more than coloc inserts in one run (" +
                                       num(kMaxInflowParticles) +
                                       "): lower the rate, or set its end or a shorter run");
    if (c.sites >= 1 && c.perStep > c.sites)
      throw ConfigError(c.rateKey, num(c.perStep) + " particles are due every DEM step (" +
                                       (c.rateKey.ends_with(".rate")
                                            ? std::string("rate x particles.dt")
                                            : std::string("mass_rate x particles.dt / the "
                                                          "largest particle's mass")) +
                                       "), but the patch has " + num(c.sites) +
                                       " insertion sites: the waiting list could never be "
                                       "drained; lower the rate or widen the patch");
  }
}

}  // namespace

double inflowParticleCount(const Config& cfg) {
  // Bounded by what the box holds (a random close packing of the smallest spheres).
  const GlobalGrid g = gridFromConfig(cfg);
  const double box = g.length[0] * g.length[1] * g.length[2];
  double n = 0;
  for (const InflowCount& c : inflowCounts(cfg))
    n += std::min(c.count, 0.64 * box / (4.0 / 3.0 * kPi * c.rmin * c.rmin * c.rmin));
  return n;
}

double inflowWaitingCount(const Config& cfg) {
  double n = 0;
  for (const InflowCount& c : inflowCounts(cfg)) n += c.count;
  return n;
}

/// A build without HDF5 (SimGrid SMPI) refuses the keys that would write files, before the run.
void checkFileKeys(const Config& cfg) {
  if (hdf5Available()) return;
  const char* why =
      "HDF5 files are not available in this build of coloc (SimGrid SMPI, COLOC_SMPI=ON): set it "
      "to 0, or run the Open MPI build";
  if (cfg.integer("output.interval_steps") > 0 &&
      (cfg.boolean("output.fields") || cfg.boolean("output.particles")))
    throw ConfigError("output.interval_steps", why);
  if (cfg.integer("output.checkpoint_interval") > 0)
    throw ConfigError("output.checkpoint_interval", why);
}

/// Heat keys a run of this mode (or with heat off) does not use: said, never silently ignored.
void checkHeatKeys(const Config& cfg, std::vector<std::string>& notes) {
  const RunMode mode = runMode(cfg);
  const char* const modeName = runModeName(mode);
  if (mode == RunMode::ParticlesOnly && cfg.boolean("fluid.heat"))
    notes.push_back(fmt::format("run.mode = {}: fluid.heat is not used (no fluid)", modeName));
  if (mode == RunMode::FluidOnly && cfg.boolean("particles.heat"))
    notes.push_back(
        fmt::format("run.mode = {}: particles.heat is not used (no particles)", modeName));
  if ((mode == RunMode::FluidOnly || mode == RunMode::ParticlesOnly) &&
      cfg.string("coupling.heat_transfer") != "none")
    notes.push_back(fmt::format(
        "run.mode = {}: coupling.heat_transfer = {} is not used (no fluid-particle exchange)",
        modeName, cfg.string("coupling.heat_transfer")));
  if (!cfg.boolean("fluid.heat")) {
    std::string unused;
    for (const char* key :
         {"fluid.conductivity", "fluid.heat_capacity", "fluid.initial_temperature"})
      if (cfg.has(key)) unused += (unused.empty() ? "" : ", ") + std::string(key);
    if (!unused.empty()) notes.push_back("fluid.heat = false: " + unused + " not used");
  }
  if (!cfg.boolean("particles.heat") && cfg.has("particles.wall_temperature"))
    notes.push_back("particles.heat = false: particles.wall_temperature not used");
}

std::vector<std::string> checkCase(const Config& cfg) {
  std::vector<std::string> notes;
  checkName(cfg);
  checkFileKeys(cfg);
  // The checkpoint stays inside the output folder and is none of the run's own files.
  if (const std::string why = checkpointFileProblem(cfg.string("output.checkpoint_file"));
      !why.empty())
    throw ConfigError("output.checkpoint_file", why);
  checkTimeSteps(cfg, notes);
  checkBoundaries(cfg, notes);
  checkInflow(cfg);
  checkHeatKeys(cfg, notes);
  const std::string mode = cfg.string("run.mode");
  if (mode == "coupled" || mode == "dummy_dem") selfVelocityFromConfig(cfg);
  if (cfg.integer("run.steps") > 0 && cfg.number("run.end_time") > 0)
    notes.push_back(
        fmt::format("run.steps = {} is given: run.end_time is not used", cfg.integer("run.steps")));
  return notes;
}

double sourceParticleCount(const Config& cfg) {
  double n = 0;
  for (const auto& s : cfg.at("particles.sources")) {
    const std::string type = s.at("type").get<std::string>();
    if (type == "list")
      n += static_cast<double>(s.at("positions").size() / 3);
    else if (type == "lattice")
      n += s.at("counts")[0].get<double>() * s.at("counts")[1].get<double>() *
           s.at("counts")[2].get<double>();
    else if (s.contains("count"))
      n += s.at("count").get<double>();
  }
  return n;
}

// Coefficients: peak RSS of 1-rank runs of tests/robustness/cases/bed.json (fluid only at 16^3,
// 48^3, 80^3 cells; particles only at 1e3, 3e4, 1e5 particles; coupled at 48^3 + 2e4) and of
// bench/cases/case3-small.json on 2 ranks (a dense bed: 400 B a particle). docs/case-files.md.
constexpr double kBaseBytes = 24e6;
constexpr double kFluidBytesPerCell = 434;     // per ghosted cell, hypre included
constexpr double kCouplingBytesPerCell = 118;  // per ghosted cell
constexpr double kParticleBytes = 400;         // per particle
// PFMG options that hold more (fluid-channel.json at 78k, 320k and 625k cells, 2 steps): the
// (weighted) Jacobi smoother on Galerkin levels +118..123, PFMG without PCG +96..104.
constexpr double kJacobiBytesPerCell = 125;    // per ghosted cell
constexpr double kNoKrylovBytesPerCell = 105;  // per ghosted cell
constexpr double kWaitingBytes = 16;           // per particle due from an inflow

MemoryEstimate estimateMemory(const Config& cfg, Int3 blockCells, double particles) {
  MemoryEstimate m;
  const RunMode mode = runMode(cfg);
  m.cells = 1LL * blockCells[0] * blockCells[1] * blockCells[2];
  m.ghostedCells = 1LL * (blockCells[0] + 4) * (blockCells[1] + 4) * (blockCells[2] + 4);
  m.particles = mode == RunMode::FluidOnly ? 0.0 : particles;
  m.baseBytes = kBaseBytes;
  const double g = static_cast<double>(m.ghostedCells);
  if (mode != RunMode::ParticlesOnly) {
    double perCell = kFluidBytesPerCell;
    if (cfg.string("fluid.pressure.solver") == "pfmg") {
      const std::string relax = cfg.string("fluid.pressure.pfmg.relax");
      if ((relax == "jacobi" || relax == "weighted_jacobi") &&
          cfg.string("fluid.pressure.pfmg.rap") == "galerkin")
        perCell += kJacobiBytesPerCell;
      if (cfg.string("fluid.pressure.krylov") == "none") perCell += kNoKrylovBytesPerCell;
    }
    m.fluidBytes = perCell * g;
  }
  if (mode == RunMode::Coupled || mode == RunMode::DummyDem)
    m.couplingBytes = kCouplingBytesPerCell * g;
  m.particleBytes = kParticleBytes * m.particles;
  // A waiting entry is a 64-bit id in a vector that may have doubled: 16 bytes at most.
  if (mode != RunMode::FluidOnly) m.inflowBytes = kWaitingBytes * inflowWaitingCount(cfg);
  return m;
}

Int3 largestUniformBlock(const Config& cfg, int ranks) {
  const GlobalGrid g = gridFromConfig(cfg);
  if (!PartitionStrategy::named(cfg.string("partition.strategy")).gridLayout()) {
    // No process grid: the boxes have about cells / ranks cells; estimated as cubes of that
    // many cells (the bisection cuts the longest axis first), at least one cell thick.
    const double side = std::cbrt(static_cast<double>(g.cellCount()) / std::max(ranks, 1));
    Int3 b{};
    for (int a = 0; a < 3; ++a) b[a] = std::clamp(static_cast<int>(std::ceil(side)), 1, g.cells[a]);
    return b;
  }
  const Int3 dims = processGridFromConfig(cfg, ranks);  // the run's own grid (and its errors)
  Int3 b{};
  for (int a = 0; a < 3; ++a) b[a] = (g.cells[a] + std::max(dims[a], 1) - 1) / std::max(dims[a], 1);
  return b;
}

double memoryLimitPerRank(const Config& cfg, int ranksOnNode, std::string* how) {
  const double gib = 1024.0 * 1024.0 * 1024.0;
  const double key = cfg.number("run.memory_limit");
  if (key > 0) {
    if (how) *how = "run.memory_limit = " + num(key) + " GiB a rank";
    return key * gib;
  }
  std::ifstream in("/proc/meminfo");
  std::string line;
  double kb = 0;
  while (std::getline(in, line))
    if (line.rfind("MemAvailable:", 0) == 0) {
      std::istringstream(line.substr(13)) >> kb;
      break;
    }
  if (!(kb > 0)) {
    if (how) *how = "unknown (no MemAvailable in /proc/meminfo)";
    return 0;
  }
  const double avail = kb * 1024.0;
  if (how)
    *how = fmt::format("MemAvailable {} / {} rank(s) on this node", bytesText(avail), ranksOnNode);
  double limit = avail / std::max(ranksOnNode, 1);
  // An address-space limit (ulimit -v) binds first when it leaves less than that: what it still
  // lets this process map, plus the base the estimate counts (already mapped now).
  rlimit as{};
  if (getrlimit(RLIMIT_AS, &as) == 0 && as.rlim_cur != RLIM_INFINITY) {
    std::ifstream st("/proc/self/status");
    double vmKb = 0;
    while (std::getline(st, line))
      if (line.rfind("VmSize:", 0) == 0) {
        std::istringstream(line.substr(7)) >> vmKb;
        break;
      }
    const double room =
        std::max(0.0, static_cast<double>(as.rlim_cur) - vmKb * 1024.0) + kBaseBytes;
    if (room < limit) {
      limit = room;
      if (how)
        *how = "RLIMIT_AS (ulimit -v) " + bytesText(static_cast<double>(as.rlim_cur)) +
               ", of which " + bytesText(vmKb * 1024.0) + " is mapped already";
    }
  }
  return limit;
}

std::string bytesText(double b) {
  if (b >= 1024.0 * 1024 * 1024 * 1024 * 10)
    return fmt::format("{:.3g} TiB", b / (1024.0 * 1024 * 1024 * 1024));
  if (b >= 1024.0 * 1024 * 1024) return fmt::format("{:.2f} GiB", b / (1024.0 * 1024 * 1024));
  return fmt::format("{:.1f} MiB", b / (1024.0 * 1024));
}

void checkMemory(const Comm& world, const Config& cfg) {
  // Same inputs on every rank except the node's memory: the verdict is made collective below.
  std::string err;
  try {
    const MemoryEstimate m =
        estimateMemory(cfg, largestUniformBlock(cfg, world.size()),
                       (sourceParticleCount(cfg) + inflowParticleCount(cfg)) / world.size());
    MPI_Comm node;
    MPI_Comm_split_type(world.raw(), MPI_COMM_TYPE_SHARED, 0, MPI_INFO_NULL, &node);
    int onNode = 1;
    MPI_Comm_size(node, &onNode);
    MPI_Comm_free(&node);
    std::string how;
    const double limit = memoryLimitPerRank(cfg, onNode, &how);
    if (limit > 0 && m.total() > limit) {
      err = std::string("domain.cells, particles.sources") +
            (m.inflowBytes > 0 ? ", particles.inflow" : "") + ": the case needs about " +
            bytesText(m.total()) + " a rank (" + fmt::format("{} cells", m.cells) +
            " in the largest block: fluid " + bytesText(m.fluidBytes) + ", coupling " +
            bytesText(m.couplingBytes) + "; " + num(m.particles) +
            " particles: " + bytesText(m.particleBytes) +
            (m.inflowBytes > 0 ? "; inflow waiting lists " + bytesText(m.inflowBytes) : "") +
            "; base " + bytesText(m.baseBytes) + "), the machine offers " + bytesText(limit) +
            " (" + how +
            "): use fewer cells or particles, more ranks or nodes, or set run.memory_limit (GiB) "
            "if the estimate is wrong";
    }
  } catch (const Error& e) {
    err = e.what();
  }
  // Every rank reaches this point; a refusal on any node stops all of them.
  const int bad = world.max(err.empty() ? 0 : 1);
  if (!bad) return;
  const int first = world.min(err.empty() ? world.size() : world.rank());
  throw Error(world.broadcast(world.rank() == first ? err : std::string(), first));
}

}  // namespace coloc::coupling
