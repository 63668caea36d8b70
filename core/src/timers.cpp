#include "coloc/core/timers.hpp"

#include <sys/resource.h>
#include <time.h>

namespace coloc {

double threadCpuSeconds() {
  timespec ts{};
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &ts);
  return static_cast<double>(ts.tv_sec) + 1e-9 * static_cast<double>(ts.tv_nsec);
}

void Timers::start(Phase p) {
  auto& s = slots_[idx(p)];
  if (s.depth++ > 0) return;
  const double wall = MPI_Wtime(), cpu = threadCpuSeconds();
  if (nActive_ > 0) {  // pause the enclosing phase
    auto& outer = slots_[idx(active_[static_cast<std::size_t>(nActive_ - 1)])];
    outer.wall += wall - outer.wall0;
    outer.cpu += cpu - outer.cpu0;
  }
  if (nActive_ < static_cast<int>(active_.size()))
    active_[static_cast<std::size_t>(nActive_++)] = p;
  s.wall0 = wall;
  s.cpu0 = cpu;
}

void Timers::stop(Phase p) {
  auto& s = slots_[idx(p)];
  if (--s.depth > 0) return;
  const double wall = MPI_Wtime(), cpu = threadCpuSeconds();
  s.wall += wall - s.wall0;
  s.cpu += cpu - s.cpu0;
  ++s.calls;
  // Remove p from the running phases (normally the innermost) and resume the enclosing one.
  for (int i = nActive_ - 1; i >= 0; --i) {
    if (active_[static_cast<std::size_t>(i)] != p) continue;
    for (int j = i; j + 1 < nActive_; ++j)
      active_[static_cast<std::size_t>(j)] = active_[static_cast<std::size_t>(j + 1)];
    --nActive_;
    break;
  }
  if (nActive_ > 0) {
    auto& outer = slots_[idx(active_[static_cast<std::size_t>(nActive_ - 1)])];
    outer.wall0 = wall;
    outer.cpu0 = cpu;
  }
}

void Timers::add(Phase p, double wallSeconds, double cpuSeconds) {
  auto& s = slots_[idx(p)];
  s.wall += wallSeconds;
  s.cpu += cpuSeconds;
  ++s.calls;
}

void Timers::book(Exchange kind, long long bytes, long long messages, double seconds,
                  Traffic traffic) {
  auto& l = ledger_[idx(kind)];
  l.bytes += bytes;
  l.messages += messages;
  l.seconds += seconds;
  if (traffic == Traffic::Auto)
    traffic = kind == Exchange::IntraPhysics         ? Traffic::FluidHalo
              : kind == Exchange::InterPhysicsRemote ? Traffic::DepositSum
                                                     : Traffic::ForceHandover;
  auto& t = traffic_[static_cast<std::size_t>(traffic)];
  t.bytes += bytes;
  t.messages += messages;
  t.seconds += seconds;
}

void Timers::syncPoint(const Comm& comm) {
  if (!syncPoints_ || comm.size() == 1) return;
  start(Phase::Sync);
  comm.barrier();
  stop(Phase::Sync);
}

void Timers::beginRun() {
  const Slot setup = slots_[idx(Phase::Setup)];
  slots_ = {};
  ledger_ = {};
  traffic_ = {};
  slots_[idx(Phase::Setup)] = setup;
}

void Timers::reset() {
  slots_ = {};
  ledger_ = {};
  traffic_ = {};
  nActive_ = 0;
}

Json Timers::report(const Comm& comm, double stepWallSeconds) const {
  Json out = Json::object();
  Json timers = Json::object();
  std::array<double, static_cast<std::size_t>(Category::Count)> catAvg{};
  double busyComputeLocal = 0;
  for (std::size_t i = 0; i < kPhases.size(); ++i) {
    const auto& s = slots_[i];
    const auto w = comm.minMaxAvg(s.wall);
    const auto b = comm.minMaxAvg(s.cpu);
    const long long calls = comm.max(s.calls);
    catAvg[static_cast<std::size_t>(kPhases[i].category)] += w.avg;
    const auto cat = kPhases[i].category;
    if ((cat == Category::Fluid || cat == Category::Particles || cat == Category::Coupling) &&
        kPhases[i].compute)
      busyComputeLocal += s.cpu;
    if (calls == 0) continue;
    timers[std::string(kPhases[i].name)] = {{"min", w.min},      {"avg", w.avg},
                                            {"max", w.max},      {"calls", calls},
                                            {"busy_avg", b.avg}, {"busy_max", b.max}};
  }
  out["timers"] = timers;
  Json ex = Json::object();
  for (std::size_t k = 0; k < ledger_.size(); ++k) {
    const auto t = comm.minMaxAvg(ledger_[k].seconds);
    ex[std::string(kExchangeNames[k])] = {{"bytes", comm.sum(ledger_[k].bytes)},
                                          {"messages", comm.sum(ledger_[k].messages)},
                                          {"time_s", t.avg},
                                          {"time_s_max", t.max}};
  }
  out["exchange"] = ex;
  Json kinds = Json::object();
  for (std::size_t k = 0; k < traffic_.size(); ++k) {
    const auto& t = traffic_[k];
    kinds[std::string(kTrafficNames[k])] = {{"bytes", comm.sum(t.bytes)},
                                            {"messages", comm.sum(t.messages)},
                                            {"bytes_max", comm.max(t.bytes)},
                                            {"messages_max", comm.max(t.messages)}};
  }
  out["exchange_kinds"] = kinds;
  const double denom = stepWallSeconds > 0 ? stepWallSeconds : 1.0;
  out["fractions"] = {
      {"fv", catAvg[static_cast<std::size_t>(Category::Fluid)] / denom},
      {"dem", catAvg[static_cast<std::size_t>(Category::Particles)] / denom},
      {"coupling", catAvg[static_cast<std::size_t>(Category::Coupling)] / denom},
      {"inter_physics", catAvg[static_cast<std::size_t>(Category::InterPhysics)] / denom},
      {"output", catAvg[static_cast<std::size_t>(Category::Output)] / denom},
      {"wait", catAvg[static_cast<std::size_t>(Category::Wait)] / denom}};
  const auto busy = comm.minMaxAvg(busyComputeLocal);
  out["load"] = {{"busy_s_min", busy.min},
                 {"busy_s_avg", busy.avg},
                 {"busy_s_max", busy.max},
                 {"imbalance", busy.avg > 0 ? busy.max / busy.avg : 1.0}};
  return out;
}

long long peakRssBytes() {
  rusage ru{};
  getrusage(RUSAGE_SELF, &ru);
  return static_cast<long long>(ru.ru_maxrss) * 1024LL;  // Linux: kilobytes
}

}  // namespace coloc
