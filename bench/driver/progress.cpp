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
// In the order of progressColumnNames() (run_config.cpp) and Progress::Column; the last entry
// is a report column's (at least as wide as its key).
constexpr std::array<ColumnFormat, 16> kFormat = {{
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
    {11, ColumnFormat::kGeneral, 7},  // t_fluid
    {11, ColumnFormat::kGeneral, 7},  // t_particles
    {13, ColumnFormat::kGeneral, 7},  // a report key
}};

/// The numbers of a report under `prefix` (a key path, "" for all), as key paths: what a
/// refused report column could have been.
void numberKeys(const Json& j, const std::string& path, std::vector<std::string>& out) {
  if (j.is_object()) {
    for (const auto& [k, v] : j.items()) numberKeys(v, path.empty() ? k : path + "." + k, out);
  } else if (j.is_array()) {
    for (std::size_t i = 0; i < j.size() && i < 3; ++i)
      numberKeys(j[i], path + "." + std::to_string(i), out);
  } else if (j.is_number() || j.is_boolean()) {
    out.push_back(path);
  }
}

/// "a.b.0" -> the JSON pointer "/a/b/0".
Json::json_pointer pointerOf(const std::string& key) {
  std::string p;
  std::size_t start = 0;
  while (start <= key.size()) {
    const std::size_t dot = std::min(key.find('.', start), key.size());
    std::string part = key.substr(start, dot - start);
    std::string escaped;
    for (char c : part) escaped += c == '~' ? "~0" : c == '/' ? "~1" : std::string(1, c);
    p += "/" + escaped;
    start = dot + 1;
  }
  return Json::json_pointer(p);
}

}  // namespace

Progress::Progress(const Comm& comm, const Config& cfg, double interval, RunLog& log)
    : comm_(comm), cfg_(cfg), log_(log), root_(comm.isRoot()), interval_(interval) {
  static_assert(kFormat.size() == static_cast<std::size_t>(kColumns) + 1);
  const auto& names = progressColumnNames();
  if (names.size() != static_cast<std::size_t>(kColumns))
    throw Error("internal: the progress columns of run_config.cpp and progress.cpp differ");
  for (const std::string& n : cfg.names("run.progress_columns")) {
    auto c = static_cast<Column>(std::find(names.begin(), names.end(), n) - names.begin());
    if (c == kColumns) {
      if (n.find('.') == std::string::npos)  // the schema has refused it already
        throw ConfigError("run.progress_columns", "unknown name '" + n + "'");
      if (n.front() == '.' || n.back() == '.' || n.find("..") != std::string::npos)
        throw ConfigError("run.progress_columns",
                          "'" + n + "' is not a key path of report.json (an empty part)");
      c = kReport;
      reportKeys_.push_back(n);
      reportPointers_.push_back(pointerOf(n));
      bed_ = bed_ || n.starts_with("bed.");
    }
    columns_.push_back(c);
    global_ = global_ || c == kParticles || c == kKe || c == kContacts || c == kDp ||
              c == kTFluid || c == kTParticles;
  }
  maxSteps_ = cfg.integer("run.steps");
  endTime_ = cfg.number("run.end_time");
  rhoF_ = cfg.number("fluid.rho");
  gravity_ = cfg.vec3("gravity");
  if (root_) line_.reserve(16 * columns_.size() + 64);
}

Json Progress::rowReport(coupling::Simulation& sim, double now) {
  Json r = sim.report(now - t0_);
  if (bed_) r["bed"] = bedDiagnosticsJson(bedDiagnostics(sim, cfg_));
  return r;
}

void Progress::start(coupling::Simulation& sim) {
  t0_ = lastWall_ = MPI_Wtime();
  steps0_ = lastSteps_ = sim.steps();
  time0_ = sim.time();
  if (!reportKeys_.empty()) {
    // Every rank computes the same report (collective) and so refuses the same keys, also
    // without a table (--quiet, run.progress_interval_s = 0): a misspelt column is an error.
    const Json r = rowReport(sim, t0_);
    for (std::size_t k = 0; k < reportKeys_.size(); ++k) {
      const Json::json_pointer& ptr = reportPointers_[k];
      if (r.contains(ptr) && (r[ptr].is_number() || r[ptr].is_boolean())) continue;
      // What there is under the deepest part of the key that exists.
      std::string prefix = reportKeys_[k];
      while (!prefix.empty() && !r.contains(pointerOf(prefix))) {
        const auto dot = prefix.rfind('.');
        prefix = dot == std::string::npos ? std::string() : prefix.substr(0, dot);
      }
      std::vector<std::string> keys;
      numberKeys(prefix.empty() ? r : r[pointerOf(prefix)], prefix, keys);
      std::string some;
      for (std::size_t i = 0; i < keys.size() && i < 12; ++i) some += (i ? ", " : "") + keys[i];
      if (keys.size() > 12) some += ", ... (" + std::to_string(keys.size()) + " in all)";
      throw ConfigError("run.progress_columns",
                        "'" + reportKeys_[k] + "' is " +
                            (r.contains(ptr) ? "not a number" : "no key") +
                            " of this run's report" +
                            (keys.empty() ? std::string(" (no numbers there)")
                                          : "; numbers " +
                                                (prefix.empty() ? std::string("of the report")
                                                                : "under '" + prefix + "'") +
                                                ": " + some) +
                            " (the keys: docs/benchmarks.md)");
    }
  }
  if (!on()) return;
  if (root_) {
    line_.clear();
    std::size_t k = 0;
    for (const Column c : columns_) {
      const std::string& name = c == kReport ? reportKeys_[k++] : progressColumnNames()[c];
      fmt::format_to(std::back_inserter(line_), " {:>{}}", name,
                     std::max<int>(kFormat[c].width, static_cast<int>(name.size())));
    }
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
    if (const auto* dem = sim.particles()) {
      const auto& p = dem->particles();
      for (const auto& e : p.extra)
        if (e.name == "temperature") {
          const std::vector<double>& T = e.data[0];
          double mt = 0, m = 0;
          for (std::size_t i = 0; i < p.nOwned; ++i) {
            mt += p.mass[i] * T[i];
            m += p.mass[i];
          }
          sums[kSumMassT] = mt;
          sums[kSumMass] = m;
        }
    }
    if (auto* fluid = sim.fluid()) {
      if (fluid->hasHeat()) {
        const fv::FluidFields& f = fluid->fields();
        double et = 0, e = 0;
        forEach(f.T.interior(), [&](int i, int j, int k) {
          et += f.eps(i, j, k) * f.T(i, j, k);
          e += f.eps(i, j, k);
        });
        sums[kSumEpsT] = et;
        sums[kSumEps] = e;
      }
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
  if (reportKeys_.empty()) {
    if (root_) print(sim, sums, now, nullptr);
  } else {
    const Json r = rowReport(sim, now);  // collective
    if (root_) print(sim, sums, now, &r);
  }
  lastWall_ = now;
  lastSteps_ = sim.steps();
}

void Progress::print(coupling::Simulation& sim, const std::array<double, kSums>& sums, double now,
                     const Json* report) {
  const auto* dem = sim.particles();
  const auto* fluid = sim.fluid();
  const fv::FluidCounters fc = fluid ? fluid->counters() : fv::FluidCounters{};
  const long long steps = sim.steps();
  const long long done = steps - steps0_;  // steps of this run (this process)
  const double elapsed = now - t0_;
  const double rate = done > 0 && elapsed > 0 ? static_cast<double>(done) / elapsed : 0.0;
  line_.clear();
  auto out = std::back_inserter(line_);
  std::size_t reportColumn = 0;
  for (const Column c : columns_) {
    ColumnFormat f = kFormat[c];
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
      case kTFluid:
        have = sums[kSumEps] > 0;
        x = have ? sums[kSumEpsT] / sums[kSumEps] : 0.0;
        break;
      case kTParticles:
        have = sums[kSumMass] > 0;
        x = have ? sums[kSumMassT] / sums[kSumMass] : 0.0;
        break;
      case kReport: {
        const std::string& key = reportKeys_[reportColumn];
        f.width = std::max<int>(f.width, static_cast<int>(key.size()));
        const Json::json_pointer& ptr = reportPointers_[reportColumn++];
        have = report && report->contains(ptr);
        if (have) {
          const Json& v = (*report)[ptr];
          if (v.is_number_integer() || v.is_number_unsigned() || v.is_boolean()) {
            f.kind = ColumnFormat::kInteger;
            n = v.is_boolean() ? (v.get<bool>() ? 1 : 0) : v.get<long long>();
          } else if (v.is_number()) {
            x = v.get<double>();
          } else {
            have = false;
          }
        }
        break;
      }
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
