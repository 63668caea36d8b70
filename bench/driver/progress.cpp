// The progress table of `coloc run` (progress.hpp).
#include "progress.hpp"

#include <mpi.h>

#include <algorithm>
#include <iterator>
#include <span>
#include <string>

#include "coloc/core/error.hpp"
#include "coloc/core/run_config.hpp"
#include "diagnostics.hpp"

namespace coloc {
namespace {

/// Each column's width (at least its name's) and how its values are written.
struct ColumnFormat {
  int width;
  enum Kind { kInteger, kGeneral, kFixed } kind;
  int precision;  // significant digits (kGeneral), digits after the point (kFixed)
};
// In the order of progressColumnNames() (run_config.cpp) and Progress::Column.
constexpr std::array<ColumnFormat, 13> kFormat = {{
    {10, ColumnFormat::kInteger, 0},  // step
    {13, ColumnFormat::kGeneral, 7},  // time
    {10, ColumnFormat::kGeneral, 4},  // dt
    {10, ColumnFormat::kInteger, 0},  // particles
    {13, ColumnFormat::kGeneral, 7},  // ke
    {9, ColumnFormat::kGeneral, 5},   // contacts
    {9, ColumnFormat::kGeneral, 4},   // cfl
    {7, ColumnFormat::kInteger, 0},   // p_iter
    {10, ColumnFormat::kGeneral, 4},  // p_iter_avg
    {13, ColumnFormat::kGeneral, 7},  // dp
    {13, ColumnFormat::kGeneral, 4},  // wall_per_step
    {11, ColumnFormat::kGeneral, 4},  // steps_per_s
    {9, ColumnFormat::kFixed, 1},     // left
}};

}  // namespace

Progress::Progress(const Comm& comm, const Config& cfg, double interval, RunLog& log)
    : comm_(comm), log_(log), root_(comm.isRoot()), interval_(interval) {
  static_assert(kFormat.size() == static_cast<std::size_t>(kColumns));
  const auto& names = progressColumnNames();
  if (names.size() != static_cast<std::size_t>(kColumns))
    throw Error("internal: the progress columns of run_config.cpp and progress.cpp differ");
  for (const std::string& n : cfg.names("run.progress_columns")) {
    const auto c = static_cast<Column>(std::find(names.begin(), names.end(), n) - names.begin());
    if (c == kColumns)  // the schema has refused it already
      throw ConfigError("run.progress_columns", "unknown name '" + n + "'");
    columns_.push_back(c);
    global_ = global_ || c == kParticles || c == kKe || c == kContacts || c == kDp;
  }
  maxSteps_ = cfg.integer("run.steps");
  endTime_ = cfg.number("run.end_time");
  rhoF_ = cfg.number("fluid.rho");
  gravity_ = cfg.vec3("gravity");
  if (root_) line_.reserve(16 * columns_.size() + 64);
}

void Progress::start(coupling::Simulation& sim) {
  if (!on()) return;
  t0_ = lastWall_ = MPI_Wtime();
  steps0_ = lastSteps_ = sim.steps();
  time0_ = sim.time();
  if (root_) {
    line_.clear();
    for (const Column c : columns_)
      fmt::format_to(std::back_inserter(line_), " {:>{}}", progressColumnNames()[c],
                     kFormat[c].width);
    log_.out("{}\n", fmt::string_view(line_.data(), line_.size()));
  }
  row(sim, true);
}

int Progress::request() const {
  if (!root_ || !on()) return 0;
  return MPI_Wtime() - lastWall_ >= interval_ ? 1 : 0;
}

void Progress::row(coupling::Simulation& sim, bool due) {
  if (!on() || !due) return;
  std::array<double, kSums> sums{};
  if (global_) {
    if (const auto* dem = sim.particles()) {
      const auto& p = dem->particles();
      double ke = 0;
      for (std::size_t i = 0; i < p.nOwned; ++i)
        ke += 0.5 * p.mass[i] *
              (p.v[0][i] * p.v[0][i] + p.v[1][i] * p.v[1][i] + p.v[2][i] * p.v[2][i]);
      sums[kSumParticles] = static_cast<double>(p.nOwned);
      sums[kSumKe] = ke;
      sums[kSumContacts] = static_cast<double>(dem->localContacts());
    }
    if (auto* fluid = sim.fluid()) {
      // The owned cells of the lowest and the highest layer along the vertical axis.
      const Decomposition& dec = sim.decomposition();
      const VerticalAxis v = verticalAxis(gravity_, dec.grid());
      const int layers = dec.grid().cells[v.axis];
      const CellField& pf = fluid->fields().p;
      const int bottom = v.up ? 0 : layers - 1;
      const int layer[2] = {bottom, layers - 1 - bottom};  // bottom, top
      for (int w = 0; w < 2; ++w) {
        IndexBox plane = pf.interior();
        const int local = layer[w] - dec.lo()[v.axis];
        if (local < plane.lo[v.axis] || local >= plane.hi[v.axis]) continue;
        plane.lo[v.axis] = local;
        plane.hi[v.axis] = local + 1;
        double s = 0;
        forEach(plane, [&](int i, int j, int k) { s += pf(i, j, k); });
        sums[w == 0 ? kSumPBottom : kSumPTop] = s;
      }
    }
    comm_.sumInPlace(std::span<double>(sums));
  }
  const double now = MPI_Wtime();
  if (root_) print(sim, sums, now);
  lastWall_ = now;
  lastSteps_ = sim.steps();
}

void Progress::print(coupling::Simulation& sim, const std::array<double, kSums>& sums, double now) {
  const auto* dem = sim.particles();
  const auto* fluid = sim.fluid();
  const fv::FluidCounters fc = fluid ? fluid->counters() : fv::FluidCounters{};
  const long long steps = sim.steps();
  const long long done = steps - steps0_;  // steps of this run (this process)
  const double elapsed = now - t0_;
  const double rate = done > 0 && elapsed > 0 ? static_cast<double>(done) / elapsed : 0.0;
  line_.clear();
  auto out = std::back_inserter(line_);
  for (const Column c : columns_) {
    const ColumnFormat& f = kFormat[c];
    bool have = true;
    double x = 0;
    long long n = 0;
    switch (c) {
      case kStep:
        n = steps;
        break;
      case kTime:
        x = sim.time();
        break;
      case kDt:
        have = steps > 0;
        x = sim.lastDt();
        break;
      case kParticles:
        have = dem != nullptr;
        n = static_cast<long long>(sums[kSumParticles]);
        break;
      case kKe:
        have = dem != nullptr;
        x = sums[kSumKe];
        break;
      case kContacts:
        have = dem != nullptr;
        x = sums[kSumContacts] / std::max(1.0, sums[kSumParticles]);
        break;
      case kCfl:
        have = fluid && fc.steps > 0;
        x = fc.cflLast;
        break;
      case kPIter:
        have = fluid && fc.solves > 0;
        n = fc.itLast;
        break;
      case kPIterAvg:
        have = fluid && fc.solves > 0;
        x = static_cast<double>(fc.itSum) / static_cast<double>(std::max(1LL, fc.solves));
        break;
      case kDp: {
        have = fluid != nullptr;
        const GlobalGrid& g = sim.decomposition().grid();
        const double perLayer =
            static_cast<double>(g.cellCount()) / g.cells[verticalAxis(gravity_, g).axis];
        x = rhoF_ * (sums[kSumPBottom] - sums[kSumPTop]) / perLayer;
        break;
      }
      case kWallPerStep:
        have = steps > lastSteps_;
        x = have ? (now - lastWall_) / static_cast<double>(steps - lastSteps_) : 0.0;
        break;
      case kStepsPerS:
        have = done > 0;
        x = rate;
        break;
      case kLeft:
        have = done > 0;
        if (maxSteps_ > 0)
          x = static_cast<double>(maxSteps_ - steps) / std::max(rate, 1e-300);
        else if (sim.time() > time0_)
          x = (endTime_ - sim.time()) / (sim.time() - time0_) * elapsed;
        x = std::max(x, 0.0);
        break;
      case kColumns:
        break;
    }
    if (!have)
      fmt::format_to(out, " {:>{}}", "-", f.width);
    else if (f.kind == ColumnFormat::kInteger)
      fmt::format_to(out, " {:>{}}", n, f.width);
    else if (f.kind == ColumnFormat::kFixed)
      fmt::format_to(out, " {:>{}.{}f}", x, f.width, f.precision);
    else
      fmt::format_to(out, " {:>{}.{}g}", x, f.width, f.precision);
  }
  log_.out("{}\n", fmt::string_view(line_.data(), line_.size()));
}

}  // namespace coloc
