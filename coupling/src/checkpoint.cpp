// Restart checkpoints: layout in coupling/include/coloc/coupling/checkpoint.hpp, docs/output.md.
#include "coloc/coupling/checkpoint.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <optional>
#include <sstream>
#include <stdexcept>
#include <type_traits>
#include <utility>

#include "coloc/core/error.hpp"
#include "coloc/core/fault.hpp"
#include "coloc/partition/setup.hpp"

namespace coloc::coupling {

namespace {

std::vector<double> asDoubles(const std::vector<int>& v) {
  return std::vector<double>(v.begin(), v.end());
}
std::vector<int> asInts(const std::vector<double>& v) {
  std::vector<int> out;
  for (double x : v) out.push_back(static_cast<int>(std::lround(x)));
  return out;
}
std::vector<double> three(const Real3& v) {
  return {v[0], v[1], v[2]};
}
const char* const kAxis[3] = {"x", "y", "z"};

std::string g9(double v) {
  return fmt::format("{:.9g}", v);
}

/// "(x, y, z)", every digit (a box that differs in the last bit shows it).
std::string g17(const std::array<double, 3>& v) {
  return fmt::format("({:.17g}, {:.17g}, {:.17g})", v[0], v[1], v[2]);
}

/// Rows of a [N][3] dataset as an array-of-structs.
std::vector<std::array<double, 3>> readRows3(H5File& f, const std::string& path,
                                             const RowRange& r) {
  const auto soa = readParticleVec3(f, path, r);
  std::vector<std::array<double, 3>> out(static_cast<std::size_t>(r.count));
  for (std::size_t i = 0; i < out.size(); ++i)
    for (int d = 0; d < 3; ++d) out[i][static_cast<std::size_t>(d)] = soa[d][i];
  return out;
}

}  // namespace

void writeGrid(H5File& file, const GlobalGrid& g) {
  file.createGroup("/grid");
  file.setAttribute("/grid", "origin", std::span<const double>(three(g.origin)));
  file.setAttribute("/grid", "length", std::span<const double>(three(g.length)));
  const std::vector<double> cells{double(g.cells[0]), double(g.cells[1]), double(g.cells[2])};
  file.setAttribute("/grid", "cells", std::span<const double>(cells));
  const std::vector<double> per{g.periodic[0] ? 1.0 : 0.0, g.periodic[1] ? 1.0 : 0.0,
                                g.periodic[2] ? 1.0 : 0.0};
  file.setAttribute("/grid", "periodic", std::span<const double>(per));
}

void writeCuts(H5File& file, const std::string& group, const Decomposition& dec) {
  file.createGroup(group);
  if (dec.isTiled()) {  // attributes: ~48 KB at 1024 ranks, within HDF5's 64 KB limit
    std::vector<Int3> lo, hi;
    dec.boxes(lo, hi);
    std::vector<double> flo, fhi;
    for (std::size_t r = 0; r < lo.size(); ++r)
      for (int d = 0; d < 3; ++d) {
        flo.push_back(lo[r][d]);
        fhi.push_back(hi[r][d]);
      }
    file.setAttribute(group, "boxes_lo", std::span<const double>(flo));
    file.setAttribute(group, "boxes_hi", std::span<const double>(fhi));
    return;
  }
  const std::vector<double> dims{double(dec.dims()[0]), double(dec.dims()[1]),
                                 double(dec.dims()[2])};
  file.setAttribute(group, "dims", std::span<const double>(dims));
  for (int d = 0; d < 3; ++d)
    file.setAttribute(group, std::string("cuts_") + kAxis[d],
                      std::span<const double>(asDoubles(dec.cuts()[d])));
}

namespace {

/// A damaged checkpoint (exit status 2, like a damaged dataset): the attribute and what it holds.
[[noreturn]] void damaged(const std::string& what) {
  throw Error("damaged: " + what);
}

/// The attributes of the root and /grid hold what a checkpoint can hold; the config attribute is
/// the JSON object of a case (at most kMaxJsonDepth levels deep: parsed with that bound).
void validateInfo(const CheckpointInfo& info) {
  if (info.steps < 0)
    damaged(fmt::format("attribute step = {} (a step count is >= 0)", info.steps));
  if (!std::isfinite(info.time) || info.time < 0)
    damaged(fmt::format("attribute time = {:g} (a time is finite and >= 0)", info.time));
  if (info.ranks < 1 || info.ranks > (1 << 24))
    damaged(fmt::format("attribute ranks = {} (1 .. {})", info.ranks, 1 << 24));
  for (int d = 0; d < 3; ++d) {
    if (!std::isfinite(info.grid.origin[d]) || !std::isfinite(info.grid.length[d]) ||
        !(info.grid.length[d] > 0))
      damaged(
          fmt::format("/grid: attributes origin, length along {} ({:g}, {:g}): a box is "
                      "finite, of positive length",
                      kAxis[d], info.grid.origin[d], info.grid.length[d]));
    if (info.grid.cells[d] < 1)
      damaged(
          fmt::format("/grid: attribute cells along {} = {} (>= 1)", kAxis[d], info.grid.cells[d]));
  }
  Json config;
  try {
    config = Json::parse(info.config, [](int depth, Json::parse_event_t ev, Json&) {
      using E = Json::parse_event_t;
      if ((ev == E::object_start || ev == E::array_start) && depth >= kMaxJsonDepth)
        throw std::length_error("nested deeper than the depth a case has");
      return true;
    });
  } catch (const std::exception& e) {
    damaged(fmt::format("attribute config is not the JSON of a case ({})", e.what()));
  }
  if (!config.is_object()) damaged("attribute config is not the JSON object of a case");
}

/// The attributes of `path`, read on the ranks of `comm` (collective).
CheckpointInfo readInfo(const Comm& comm, const std::string& path) {
  CheckpointInfo info;
  info.path = path;
  try {
    H5File f = H5File::openRead(comm, path);
    std::string format;
    // A file without the format attribute is not a checkpoint: say so rather than
    // "no such attribute".
    try {
      format = f.attributeString("/", "format");
    } catch (const Error&) {
      format.clear();
    }
    if (format != kCheckpointFormat)
      throw Error("not a coloc checkpoint (no attribute format = \"" +
                  std::string(kCheckpointFormat) + "\")");
    info.version = f.attributeInt("/", "version");
    if (info.version != kCheckpointVersion)
      throw Error(fmt::format("checkpoint format version {}, this coloc reads version {}",
                              info.version, kCheckpointVersion));
    info.status = f.attributeString("/", "status");
    info.caseName = f.attributeString("/", "case");
    info.mode = f.attributeString("/", "mode");
    info.config = f.attributeString("/", "config");
    info.steps = f.attributeInt("/", "step");
    info.ranks = f.attributeInt("/", "ranks");
    info.time = f.attributeDouble("/", "time");
    const auto o = f.attributeDoubles("/grid", "origin");
    const auto l = f.attributeDoubles("/grid", "length");
    const auto c = f.attributeDoubles("/grid", "cells");
    const auto p = f.attributeDoubles("/grid", "periodic");
    if (o.size() != 3 || l.size() != 3 || c.size() != 3 || p.size() != 3)
      damaged("/grid: attributes origin, length, cells, periodic must have 3 entries");
    for (int d = 0; d < 3; ++d) {
      info.grid.origin[d] = o[d];
      info.grid.length[d] = l[d];
      // (a cell count beyond an int is damage: validateInfo says so)
      info.grid.cells[d] =
          c[d] >= 1 && c[d] < 2147483647.0 ? static_cast<int>(std::lround(c[d])) : 0;
      info.grid.periodic[d] = p[d] != 0.0;
    }
    validateInfo(info);
    info.strategy = f.attributeString("/partition", "strategy");
    if (!PartitionStrategy::named(info.strategy)
             .gridLayout()) {  // boxes, not a process grid's cuts
      const auto lo = asInts(f.attributeDoubles("/partition/fluid", "boxes_lo"));
      const auto hi = asInts(f.attributeDoubles("/partition/fluid", "boxes_hi"));
      if (lo.size() != hi.size() || lo.size() != static_cast<std::size_t>(3 * info.ranks))
        throw Error("/partition/fluid: boxes_lo and boxes_hi must have 3 entries a rank");
      for (std::size_t r = 0; r < lo.size() / 3; ++r) {
        info.fluidBoxLo.push_back({lo[3 * r], lo[3 * r + 1], lo[3 * r + 2]});
        info.fluidBoxHi.push_back({hi[3 * r], hi[3 * r + 1], hi[3 * r + 2]});
      }
    } else
      for (int d = 0; d < 3; ++d)
        info.fluidCuts[d] =
            asInts(f.attributeDoubles("/partition/fluid", std::string("cuts_") + kAxis[d]));
    if (f.exists("/partition/particles"))
      for (int d = 0; d < 3; ++d)
        info.particleCuts[d] =
            asInts(f.attributeDoubles("/partition/particles", std::string("cuts_") + kAxis[d]));
    f.close();
  } catch (const Error& e) {
    throw Error("checkpoint '" + path + "': " + e.what());
  }
  return info;
}

}  // namespace

CheckpointInfo readCheckpointInfo(const Comm& comm, const std::string& path) {
  // Rank 0 reads and checks the file alone first (its own communicator: nothing another rank
  // does can meet its collectives), and every rank learns the verdict before any open on all
  // ranks: a file that is no checkpoint, or a damaged one, is refused by name, never a hang.
  std::string err;
  if (comm.isRoot()) {
    try {
      (void)readInfo(Comm(MPI_COMM_SELF), path);
    } catch (const std::exception& e) {  // (anything: the other ranks wait for the verdict)
      err = fmt::format("checkpoint '{}': {}", path, e.what());
      if (dynamic_cast<const Error*>(&e)) err = e.what();
    }
  }
  err = comm.broadcast(err);
  if (!err.empty()) throw Error(err);
  return readInfo(comm, path);
}

CheckpointInfo checkRestartable(const Comm& comm, const std::string& path, const GlobalGrid& g,
                                RunMode mode) {
  CheckpointInfo info = readCheckpointInfo(comm, path);
  const std::string where = "cannot restart from '" + path + "': ";
  if (!info.ok())
    throw Error(where + "its status is '" + info.status +
                "' (the state at a failure, for inspection); restart from the last good "
                "checkpoint");
  if (info.grid.cells != g.cells)
    throw Error(fmt::format("{}its grid has {}x{}x{} cells, the case {}x{}x{} (domain.cells)",
                            where, info.grid.cells[0], info.grid.cells[1], info.grid.cells[2],
                            g.cells[0], g.cells[1], g.cells[2]));
  for (int d = 0; d < 3; ++d) {
    const double tol = 1e-12 * std::max(1.0, std::fabs(g.length[d]));
    if (std::fabs(info.grid.origin[d] - g.origin[d]) > tol ||
        std::fabs(info.grid.length[d] - g.length[d]) > tol)
      throw Error(where + "its box is origin " + g17(info.grid.origin) + ", length " +
                  g17(info.grid.length) + "; the case's origin " + g17(g.origin) + ", length " +
                  g17(g.length));
    if (info.grid.periodic[d] != g.periodic[d])
      throw Error(where + "its periodicity along " + kAxis[d] + " differs from the case's");
  }
  if (info.mode != runModeName(mode))
    throw Error(where + "it was written in run.mode " + info.mode + ", the case runs " +
                runModeName(mode));
  return info;
}

// ---- the run's counters ---------------------------------------------------------------------

namespace {
/// One counter as an attribute: a double, an integer, a flag (an integer 0 or 1) or a 3-vector.
template <class T>
void writeCounter(H5File& file, const std::string& group, const char* name, const T& v) {
  if constexpr (std::is_same_v<T, std::array<double, 3>>)
    file.setAttribute(group, name, std::span<const double>(v));
  else if constexpr (std::is_same_v<T, bool>)
    file.setAttribute(group, name, static_cast<long long>(v ? 1 : 0));
  else
    file.setAttribute(group, name, v);
}
template <class T>
void readCounter(H5File& file, const std::string& group, const char* name, T& v) {
  if constexpr (std::is_same_v<T, std::array<double, 3>>) {
    const auto a = file.attributeDoubles(group, name);
    for (std::size_t d = 0; d < 3 && d < a.size(); ++d) v[d] = a[d];
  } else if constexpr (std::is_same_v<T, bool>) {
    v = file.attributeInt(group, name) != 0;
  } else if constexpr (std::is_same_v<T, long long>) {
    v = file.attributeInt(group, name);
  } else {
    v = file.attributeDouble(group, name);
  }
}

/// A step count and a time (or step) of a counter table: what a run can have written, else
/// damage (exit status 2) naming the group.
void checkCounters(const H5File& file, const std::string& group, double time, long long steps) {
  if (!std::isfinite(time) || time < 0 || steps < 0)
    throw Error(
        fmt::format("checkpoint '{}' is damaged: {}: a time of {:g} s or a count of {} "
                    "(times are finite and >= 0, counts >= 0)",
                    file.path(), group, time, steps));
}

/// Which counters a checkpoint holds: every one; one that older files lack (read as the default
/// when absent); one of fluid.heat (written and read only with it).
enum class Held { Always, Since, Heat };

/// The attribute name of each counter, in one order: fn(name, member, held).
template <class C, class Fn>
void forEachRunCounter(C& c, Fn&& fn) {
  fn("time", c.time, Held::Always);
  fn("last_dt", c.lastDt, Held::Always);
  fn("last_step_dt", c.lastStepDt, Held::Always);
  fn("steps", c.steps, Held::Always);
  fn("dem_substeps", c.substeps, Held::Always);
  fn("momentum_residual", c.momentumResidual, Held::Always);
  fn("solid_volume", c.solidVolume, Held::Always);
  fn("fluid_accel_l1", c.accelL1, Held::Always);
  fn("particle_drag_impulse", c.particleImpulse, Held::Always);
  fn("fluid_drag_impulse", c.fluidImpulse, Held::Always);
  fn("heat_exchange_residual", c.heatResidual, Held::Since);
  fn("heat_exchanged", c.heatExchanged, Held::Since);
}

/// The fluid's counters (fv::FluidCounters), one attribute each, in one order:
/// fn(name, member, held).
template <class C, class Fn>
void forEachFluidCounter(C& c, Fn&& fn) {
  fn("time", c.time, Held::Always);
  fn("dt_old", c.dtOld, Held::Always);
  fn("dt_last", c.dtLast, Held::Always);
  fn("cfl_last", c.cflLast, Held::Always);
  fn("max_rate", c.maxRate, Held::Always);
  fn("steady_residual", c.steadyResidual, Held::Always);
  fn("residual_last", c.resLast, Held::Always);
  fn("rhs_scale_last", c.rhsScaleLast, Held::Always);
  fn("steps", c.steps, Held::Always);
  fn("iterations_sum", c.itSum, Held::Always);
  fn("solves", c.solves, Held::Always);
  fn("setups", c.setups, Held::Always);
  fn("iterations_max", c.itMax, Held::Always);
  fn("iterations_last", c.itLast, Held::Always);
  fn("unconverged_solves", c.unconverged, Held::Since);
  // the pressure set-up reuse (absent: no hierarchy kept, the next step sets one up)
  fn("pressure_setup_dt", c.setupDt, Held::Since);
  fn("pressure_matrix_dt", c.matrixDt, Held::Since);
  fn("pressure_setup_reuses", c.setupReuses, Held::Since);
  fn("pressure_setup_iterations", c.setupIterations, Held::Since);
  fn("pressure_setup_due", c.setupDue, Held::Since);
  fn("have_old", c.haveOld, Held::Always);
  fn("rates_stale", c.ratesStale, Held::Always);
  // fluid.heat: the energy accounting
  fn("heat_enthalpy_initial", c.heatEnthalpy0, Held::Heat);
  fn("heat_source", c.heatSource, Held::Heat);
  static constexpr const char* kFace[6] = {"heat_face_0", "heat_face_1", "heat_face_2",
                                           "heat_face_3", "heat_face_4", "heat_face_5"};
  for (std::size_t b = 0; b < 6; ++b) fn(kFace[b], c.heatFace[b], Held::Heat);
  fn("heat_started", c.heatStarted, Held::Heat);
}
}  // namespace

void writeRunCounters(H5File& file, const std::string& group, const RunCounters& c) {
  file.createGroup(group);
  forEachRunCounter(
      c, [&](const char* name, const auto& v, Held) { writeCounter(file, group, name, v); });
}

RunCounters readRunCounters(H5File& file, const std::string& group) {
  RunCounters c;
  forEachRunCounter(c, [&](const char* name, auto& v, Held held) {
    if (held != Held::Since) return readCounter(file, group, name, v);
    try {  // absent from checkpoints written before it was counted: the default
      readCounter(file, group, name, v);
    } catch (const Error&) {
    }
  });
  checkCounters(file, group, c.time, c.steps);
  checkCounters(file, group, c.lastDt, c.substeps);
  checkCounters(file, group, c.lastStepDt, c.steps);
  return c;
}

// ---- fluid --------------------------------------------------------------------------------------

void writeFluidState(H5File& file, const std::string& group, const Decomposition& dec,
                     const fv::FluidSolver& fluid) {
  file.createGroup(group);
  fv::forEachStateField(fluid,
                        [&](const fv::FluidSolver::StateField& sf, const Field3<double>* const* a) {
                          const std::string path = group + "/" + sf.name;
                          if (sf.stagger >= 0)
                            writeFaceComponent(file, path, dec, sf.stagger, *a[0]);
                          else if (sf.components == 1)
                            writeCellField(file, path, dec, *a[0]);
                          else
                            writeCellVector(file, path, dec, *a[0], *a[1], *a[2]);
                        });
  const fv::FluidCounters c = fluid.counters();
  forEachFluidCounter(c, [&](const char* name, const auto& v, Held held) {
    if (held != Held::Heat || fluid.hasHeat()) writeCounter(file, group, name, v);
  });
}

void readFluidState(H5File& file, const std::string& group, const Decomposition& dec,
                    fv::FluidSolver& fluid) {
  if (fluid.hasHeat() && !file.exists(group + "/T"))
    throw ConfigError("fluid.heat",
                      "true, but the checkpoint '" + file.path() +
                          "' holds no fluid temperature (" + group +
                          "/T: it was written with fluid.heat = false): a restart cannot "
                          "turn the fluid's heat on; start from the case, or restart with "
                          "fluid.heat = false");
  // the table's non-const walk marks the solver's ghosts and rates stale; restoreState sets them
  std::string err;  // a restart must not start from NaN or from an impossible fluid fraction
  bool lacksOptional = false;
  fv::forEachStateField(
      fluid, [&](const fv::FluidSolver::StateField& sf, Field3<double>* const* a) {
        const std::string path = group + "/" + sf.name;
        if (sf.optional && !file.exists(path)) {
          lacksOptional = true;
          return;
        }
        if (sf.stagger >= 0)
          readFaceComponent(file, path, dec, sf.stagger, *a[0]);
        else if (sf.components == 1)
          readCellField(file, path, dec, *a[0]);
        else
          readCellVector(file, path, dec, *a[0], *a[1], *a[2]);
        for (int c = 0; c < sf.components && err.empty(); ++c)
          for (double v : a[c]->data())
            if (!std::isfinite(v) || (sf.fraction && !(v > 0.0 && v <= 1.0))) {
              err = group + "/" + sf.name + ": value " + g9(v) +
                    (sf.fraction ? " (a fluid fraction must lie in (0, 1])" : " (not finite)");
              break;
            }
      });
  file.comm().raiseIfAny(err.empty() ? err : "checkpoint '" + file.path() + "': " + err);
  fv::FluidCounters c;
  forEachFluidCounter(c, [&](const char* name, auto& v, Held held) {
    if (held == Held::Heat && !fluid.hasHeat()) return;  // (the table above read T with it)
    if (held != Held::Since) return readCounter(file, group, name, v);
    try {  // absent from checkpoints written before it was counted: the default
      readCounter(file, group, name, v);
    } catch (const Error&) {
    }
  });
  // The optional arrays are the pressure set-up's operator: without them the next step sets up.
  if (lacksOptional) c.setupDt = -1;
  if (!std::isfinite(c.setupDt) || !std::isfinite(c.matrixDt) || c.setupReuses < 0 ||
      c.setupIterations < -1)
    throw Error(fmt::format(
        "checkpoint '{}' is damaged: {}: the pressure set-up's counters (pressure_setup_dt {:g}, "
        "pressure_matrix_dt {:g}, pressure_setup_reuses {}, pressure_setup_iterations {})",
        file.path(), group, c.setupDt, c.matrixDt, c.setupReuses, c.setupIterations));
  checkCounters(file, group, c.time, c.steps);
  checkCounters(file, group, c.dtOld, c.solves);
  checkCounters(file, group, c.dtLast, c.itSum);
  for (const double h : {c.heatEnthalpy0, c.heatSource, c.heatFace[0], c.heatFace[1], c.heatFace[2],
                         c.heatFace[3], c.heatFace[4], c.heatFace[5]})
    if (!std::isfinite(h)) checkCounters(file, group + " (heat accounts)", h, 0);
  fluid.restoreState(c);
}

// ---- particles ----------------------------------------------------------------------------------

namespace {
/// The energy accounts (particles.heat; dem::DemHeat), when every rank's state has them: the
/// attribute "heat" holds the run's values (enthalpy_initial, wall_heat_in, ext_heat_in,
/// inflow_enthalpy_in, outflow_enthalpy_out: the report's), the dataset "heat_shares" one row
/// per writing rank, its shares (wall_heat_in, ext_heat_in, outflow_enthalpy_out).
void writeDemHeat(H5File& file, const std::string& group, const dem::DemHeat& h) {
  const Comm& comm = file.comm();
  if (comm.min(h.known ? 1LL : 0LL) == 0) return;
  double sum[3] = {h.wallIn, h.extIn, h.outflowOut};
  comm.sumInPlace(std::span<double>(sum, 3));
  const std::vector<double> run = {h.enthalpyInitial, sum[0], sum[1], h.inflowIn, sum[2]};
  file.setAttribute(group, "heat", std::span<const double>(run));
  writeParticleVec3(file, group + "/heat_shares",
                    {std::span<const double>(&h.wallIn, 1), std::span<const double>(&h.extIn, 1),
                     std::span<const double>(&h.outflowOut, 1)});
}

/// The accounts of writeDemHeat: the shares' rows split evenly over the reading ranks (on the
/// writer's rank count, each rank its own row), each rank the sum of its rows; without the
/// shares, rank 0 holds the run's values. A file without them: none (not known).
dem::DemHeat readDemHeat(H5File& file, const std::string& group) {
  dem::DemHeat h;
  std::vector<double> run;
  try {  // absent from files written without particles.heat or before the accounts
    run = file.attributeDoubles(group, "heat");
  } catch (const Error&) {
    return h;
  }
  if (run.size() != 5)
    throw Error(fmt::format("checkpoint '{}': {}: attribute heat must have 5 entries, not {}",
                            file.path(), group, run.size()));
  h.known = true;
  h.enthalpyInitial = run[0];
  h.inflowIn = run[3];
  const std::string shares = group + "/heat_shares";
  if (!file.exists(shares)) {
    if (file.comm().isRoot()) {
      h.wallIn = run[1];
      h.extIn = run[2];
      h.outflowOut = run[4];
    }
    return h;
  }
  const auto rows = readParticleVec3(file, shares, evenRows(file.comm(), file.shape(shares)[0]));
  for (std::size_t k = 0; k < rows[0].size(); ++k) {
    h.wallIn += rows[0][k];
    h.extIn += rows[1][k];
    h.outflowOut += rows[2][k];
  }
  return h;
}
}  // namespace

void writeDemState(H5File& file, const std::string& group, const dem::DemState& s) {
  const auto& p = s.particles;
  const std::size_t n = p.nOwned;
  file.createGroup(group);
  // every field of the DEM's table in its state (dem/fields.hpp): the built-in ones under the
  // group, the extra ones under group/extra, listed in its attribute "fields"
  std::string extras;
  for (const auto& e : p.extra)
    if (e.ops & dem::kOpState) extras += fmt::format("{} {} {};", e.name, e.components, e.ops);
  if (!extras.empty()) {
    file.createGroup(group + "/extra");
    file.setAttribute(group + "/extra", "fields", extras);
  }
  dem::forEachField(p, [&]<class T>(const dem::FieldInfo& fi, const std::vector<T>* c) {
    if (!(fi.ops & dem::kOpState)) return;
    const std::string path = group + (fi.extra ? "/extra/" : "/") + std::string(fi.name);
    if (fi.components == 1)
      writeParticleArray(file, path, std::span<const T>(c[0].data(), n));
    else if constexpr (std::is_same_v<T, double>)
      writeParticleVec3(
          file, path,
          {std::span<const double>(c[0].data(), n), std::span<const double>(c[1].data(), n),
           std::span<const double>(c[2].data(), n)});
  });
  // the positions of the last neighbour rebuild (the restore redoes it there); a raw state (at a
  // failure) has none, and a restore then rebuilds at x
  const bool x0 = std::all_of(s.xRebuild.begin(), s.xRebuild.end(),
                              [&](const auto& c) { return c.size() == n; });
  if (file.comm().min(x0 ? 1LL : 0LL) == 1)
    writeParticleVec3(file, group + "/x_rebuild", firstRows(s.xRebuild, n));
  const RowRange rows = rowsOf(file.comm(), static_cast<long long>(n));
  file.setAttribute(group, "count", rows.total);
  file.setAttribute(group, "time", s.time);
  file.setAttribute(group, "steps", s.steps);
  file.setAttribute(group, "rebuilds", s.rebuilds);
  {
    const std::vector<double> flow = s.flow.pack();  // particle inflow/outflow tallies
    file.setAttribute(group, "flow", std::span<const double>(flow));
  }
  writeDemHeat(file, group, s.heat);
  const std::string cg = group + "/contacts";
  file.createGroup(cg);
  const std::size_t m = s.contacts.size();
  std::vector<std::int64_t> holder(m), partner(m);
  std::array<std::vector<double>, 3> shear, roll;
  for (int d = 0; d < 3; ++d) shear[d].resize(m), roll[d].resize(m);
  for (std::size_t i = 0; i < m; ++i) {
    holder[i] = s.contacts[i].holder;
    partner[i] = s.contacts[i].partner;
    for (int d = 0; d < 3; ++d) {
      shear[d][i] = s.contacts[i].shear[static_cast<std::size_t>(d)];
      roll[d][i] = s.contacts[i].roll[static_cast<std::size_t>(d)];
    }
  }
  writeParticleArray(file, cg + "/holder", std::span<const std::int64_t>(holder));
  writeParticleArray(file, cg + "/partner", std::span<const std::int64_t>(partner));
  writeParticleVec3(file, cg + "/shear", firstRows(shear, m));
  writeParticleVec3(file, cg + "/roll", firstRows(roll, m));
  file.setAttribute(cg, "count", rowsOf(file.comm(), static_cast<long long>(m)).total);
}

dem::DemState readDemState(H5File& file, const std::string& group) {
  dem::DemState s;
  const Comm& comm = file.comm();
  // The counts as the datasets hold them, checked before anything is sized by them: a damaged
  // count is damage (exit status 2), not an allocation of its size.
  const auto rowsHeld = [&](const std::string& dataset, const char* countName) {
    const long long count = file.attributeInt(dataset.substr(0, dataset.rfind('/')), countName);
    const auto shape = file.shape(dataset);
    if (shape.empty() || count < 0 || count != shape[0])
      throw Error(
          fmt::format("checkpoint '{}' is damaged: {}: attribute {} = {}, but {} holds {} "
                      "rows",
                      file.path(), dataset.substr(0, dataset.rfind('/')), countName, count, dataset,
                      shape.empty() ? 0 : shape[0]));
    return count;
  };
  const long long total = rowsHeld(group + "/id", "count");
  const RowRange r = evenRows(comm, total);
  auto& p = s.particles;
  p.nOwned = static_cast<std::size_t>(r.count);
  p.nGhost = 0;
  if (file.exists(group + "/extra")) {  // "name components ops;" per extra field
    const std::string fields = file.attributeString(group + "/extra", "fields");
    std::istringstream in(fields);
    std::string name;
    int comps = 0;
    unsigned ops = 0;
    char sep = 0;
    while (in >> name >> comps >> ops >> sep) {
      try {
        if (ops > 0xff) throw Error(fmt::format("unknown operations {}", ops));
        p.addField(name, comps, ops);
      } catch (const Error& e) {
        throw Error(fmt::format("checkpoint '{}' is damaged: {}/extra: attribute fields: {}",
                                file.path(), group, e.what()));
      }
    }
  }
  dem::forEachField(p, [&]<class T>(const dem::FieldInfo& fi, std::vector<T>* c) {
    if (!(fi.ops & dem::kOpState)) return;
    const std::string path = group + (fi.extra ? "/extra/" : "/") + std::string(fi.name);
    if (fi.components == 1) {
      c[0] = readParticleArray<T>(file, path, r);
    } else if constexpr (std::is_same_v<T, double>) {
      auto v = readParticleVec3(file, path, r);
      for (int k = 0; k < 3; ++k) c[k] = std::move(v[static_cast<std::size_t>(k)]);
    }
  });
  if (file.exists(group + "/x_rebuild")) {
    auto v = readParticleVec3(file, group + "/x_rebuild", r);
    for (int k = 0; k < 3; ++k)
      s.xRebuild[static_cast<std::size_t>(k)] = std::move(v[static_cast<std::size_t>(k)]);
  }
  s.time = file.attributeDouble(group, "time");
  s.steps = file.attributeInt(group, "steps");
  s.rebuilds = file.attributeInt(group, "rebuilds");
  checkCounters(file, group, s.time, s.steps);
  checkCounters(file, group, 0.0, s.rebuilds);
  s.flow = dem::DemFlow::unpack(file.attributeDoubles(group, "flow"));
  s.heat = readDemHeat(file, group);
  const std::string cg = group + "/contacts";
  const RowRange rc = evenRows(comm, rowsHeld(cg + "/holder", "count"));
  const auto holder = readParticleArray<std::int64_t>(file, cg + "/holder", rc);
  const auto partner = readParticleArray<std::int64_t>(file, cg + "/partner", rc);
  const auto shear = readRows3(file, cg + "/shear", rc);
  const auto roll = readRows3(file, cg + "/roll", rc);
  s.contacts.resize(static_cast<std::size_t>(rc.count));
  for (std::size_t i = 0; i < s.contacts.size(); ++i)
    s.contacts[i] = dem::ContactHistory{holder[i], partner[i], shear[i], roll[i]};
  return s;
}

void validateDemState(const Comm& comm, const dem::DemState& s, const GlobalGrid& grid,
                      std::size_t materials, const std::string& path, const std::string& group) {
  const auto& p = s.particles;
  const std::size_t n = p.nOwned;
  std::string err;
  auto bad = [&](const std::string& dataset, std::size_t i, const std::string& what) {
    if (err.empty())
      err = fmt::format("{}/{}: particle id {} (row {} of this rank's share) {}", group, dataset,
                        p.id[i], i, what);
  };
  for (std::size_t i = 0; i < n && err.empty(); ++i) {
    if (p.id[i] < 0) bad("id", i, "has a negative id");
    if (!(std::isfinite(p.mass[i]) && p.mass[i] > 0))
      bad("mass", i, "has mass " + g9(p.mass[i]) + " (must be positive and finite)");
    if (!(std::isfinite(p.radius[i]) && p.radius[i] > 0))
      bad("radius", i, "has radius " + g9(p.radius[i]) + " (must be positive and finite)");
    if (p.material[i] < 0) bad("material", i, fmt::format("has material {}", p.material[i]));
    if (err.empty() && p.radius[i] > 0 && p.mass[i] > 0) {
      const double rho = p.mass[i] / (4.0 / 3.0 * M_PI * p.radius[i] * p.radius[i] * p.radius[i]);
      if (!std::isfinite(rho)) bad("mass", i, "has a density that is not finite");
    }
    for (int d = 0; d < 3 && err.empty(); ++d) {
      const double x = p.x[d][i];
      const double lo = grid.origin[d], hi = grid.origin[d] + grid.length[d];
      const double tol = 1e-9 * grid.length[d];
      if (!std::isfinite(x))
        bad("x", i, "has a position that is not finite");
      else if (!grid.periodic[d] && (x < lo - tol || x > hi + tol))
        bad("x", i,
            std::string("is outside the box along ") + kAxis[d] + " (" + g9(x) + " m, box [" +
                g9(lo) + ", " + g9(hi) + "])");
      for (const auto* a : {&p.v, &p.omega, &p.f, &p.torque, &p.fExt})
        if (!std::isfinite((*a)[d][i]))
          bad("v, omega, f, torque, f_ext", i, "has a value that is not finite");
      const auto& x0 = s.xRebuild[static_cast<std::size_t>(d)];
      if (i < x0.size() && !std::isfinite(x0[i]))
        bad("x_rebuild", i, "has a rebuild position that is not finite");
    }
  }
  {
    const auto& h = s.heat;
    for (const double v : {h.enthalpyInitial, h.inflowIn, h.wallIn, h.extIn, h.outflowOut})
      if (err.empty() && !std::isfinite(v))
        err = fmt::format(
            "{}: the energy accounts (heat, heat_shares) hold a value that is not "
            "finite",
            group);
  }
  // The materials the particles use must be the case's: fewer declared is the case's error (the
  // particles keep their materials), named by its key.
  {
    long long top = -1;
    for (std::size_t i = 0; i < n; ++i) top = std::max<long long>(top, p.material[i]);
    top = comm.max(top);
    if (top >= static_cast<long long>(materials))
      throw ConfigError("particles.materials",
                        fmt::format("the checkpoint's particles use material {}, the case declares "
                                    "{} material(s): a restart keeps the particles and their "
                                    "materials; declare them all",
                                    top, materials));
  }
  // Ids unique over all ranks, and every contact history held by (and pointing at) an existing
  // particle: every rank gathers the sorted ids (8 bytes a particle, once at a restart).
  std::vector<std::int64_t> all;
  {
    const int size = comm.size();
    const int mine = static_cast<int>(n);
    std::vector<int> counts(static_cast<std::size_t>(size)), displ;
    MPI_Allgather(&mine, 1, MPI_INT, counts.data(), 1, MPI_INT, comm.raw());
    all.resize(static_cast<std::size_t>(Comm::displacements(counts, displ)));
    MPI_Allgatherv(p.id.data(), mine, MPI_INT64_T, all.data(), counts.data(), displ.data(),
                   MPI_INT64_T, comm.raw());
    std::sort(all.begin(), all.end());
  }
  if (err.empty() && comm.isRoot()) {
    const auto dup = std::adjacent_find(all.begin(), all.end());
    if (dup != all.end()) err = fmt::format("{}/id: id {} appears more than once", group, *dup);
  }
  auto known = [&](std::int64_t id) { return std::binary_search(all.begin(), all.end(), id); };
  for (std::size_t c = 0; c < s.contacts.size() && err.empty(); ++c) {
    const auto& h = s.contacts[c];
    if (!known(h.holder))
      err = fmt::format(
          "{}/contacts/holder: row {} of this rank's share names id {}, which no "
          "particle has",
          group, c, h.holder);
    else if (h.partner < -6 || (h.partner >= 0 && !known(h.partner)))  // walls: -1..-6
      err = fmt::format(
          "{}/contacts/partner: row {} of this rank's share names id {}, which no "
          "particle has",
          group, c, h.partner);
    for (int d = 0; d < 3 && err.empty(); ++d)
      if (!std::isfinite(h.shear[static_cast<std::size_t>(d)]) ||
          !std::isfinite(h.roll[static_cast<std::size_t>(d)]))
        err = fmt::format("{}/contacts/shear, roll: row {} is not finite", group, c);
  }
  comm.raiseIfAny(err.empty() ? err : "checkpoint '" + path + "' is damaged: " + err);
}

dem::DemState rawDemState(const dem::ParticleStore& p, double time, long long steps) {
  dem::DemState s;
  s.particles = dem::ownedRows(p);
  s.time = time;
  s.steps = steps;
  return s;
}

// ---- the blocks --------------------------------------------------------------------------------

void writeLayouts(H5File& f, const Layouts& L, const Decomposition& fluid,
                  const std::optional<Decomposition>& particles) {
  f.createGroup("/partition");
  f.setAttribute("/partition", "strategy", L.strategy);
  f.setAttribute("/partition", "cost_per_cell", L.model.perCell);
  f.setAttribute("/partition", "cost_per_particle", L.model.perParticle);
  f.setAttribute("/partition", "modelled_imbalance", L.modelledImbalance);
  f.setAttribute("/partition", "uniform_modelled_imbalance", L.uniformImbalance);
  writeCuts(f, "/partition/fluid", fluid);
  if (particles) writeCuts(f, "/partition/particles", *particles);
}

void readLayoutCosts(H5File& f, Layouts& L) {
  L.model.perCell = f.attributeDouble("/partition", "cost_per_cell");
  L.model.perParticle = f.attributeDouble("/partition", "cost_per_particle");
  L.modelledImbalance = f.attributeDouble("/partition", "modelled_imbalance");
  L.uniformImbalance = f.attributeDouble("/partition", "uniform_modelled_imbalance");
}

}  // namespace coloc::coupling
