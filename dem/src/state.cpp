// dem/src/state.cpp — the DEM state: canonical snapshot (save) and restore from any rank's subset
// (checkpoints, re-balancing), particle rows of the field table.
#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>
#include <span>
#include <string>

#include "impl.hpp"
#include "rows.hpp"

namespace coloc::dem {

using namespace detail;

// ---------------------------------------------------------------------------------------------
// state: checkpoint/restart and re-balancing

int DemSolver::Impl::ownerRank(const double* x) const {
  return search.bins().ownerRank(dec, x);
}

namespace {
/// Row i (w doubles, written by pack(i, out)) to rank dest[i], through a plan built from the
/// destinations (partition/comm_plan.hpp; payload only to the ranks with rows); returns what
/// arrived, rank after rank, each rank's rows in its order. `plan` tells how many came from
/// each rank.
template <class Pack>
std::vector<double> toRanks(CommPlan& plan, const Comm& comm, std::span<const int> dest, int w,
                            Pack&& pack) {
  plan = CommPlan::fromDestinations(comm, dest);
  const std::span<double> buf = plan.packBuffer(w);
  const auto idx = plan.exportIndex();
  for (std::size_t k = 0; k < idx.size(); ++k)
    pack(static_cast<std::size_t>(idx[k]), buf.data() + k * static_cast<std::size_t>(w));
  std::vector<double> in(plan.importCount() * static_cast<std::size_t>(w));
  plan.forwardPacked(w, in);
  return in;
}
// A contact history as a row of doubles: holder (its id, or its place in a block of rows),
// partner id, shear displacement. The one place the record is written and read.
constexpr int kHistRec = 5;
void historyRecord(double holder, const ContactHistory& c, double* o) {
  o[0] = holder;
  o[1] = static_cast<double>(c.partner);
  std::copy(c.shear.begin(), c.shear.end(), o + 2);
}
std::int64_t historyHolder(const double* row) {
  return static_cast<std::int64_t>(row[0]);
}
std::int64_t historyPartner(const double* row) {
  return static_cast<std::int64_t>(row[1]);
}
const double* historyShear(const double* row) {
  return row + 2;
}

/// The histories of a state read from a file (any rank may hold any history) to the ranks that
/// now own their holders (the owned particles `p`), through a directory (rank holder % P) that
/// learns every holder's owner and forwards. `mine` receives the rows, `row` each one's holder.
void routeHistoriesById(const Comm& comm, const ParticleStore& p, DemState& st, CommPlan& plan,
                        std::vector<double>& mine, std::vector<int>& row) {
  const int P = comm.size();
  const std::size_t n = p.nOwned;
  std::string err;
  std::vector<int> dest(st.contacts.size());
  for (std::size_t h = 0; h < st.contacts.size(); ++h) {
    const auto& c = st.contacts[h];
    if (c.holder < 0) {
      if (err.empty()) err = fmt::format("a restored contact history has holder id {}", c.holder);
      dest[h] = 0;
      continue;
    }
    dest[h] = static_cast<int>(c.holder % P);
  }
  comm.raiseIfAny(err);
  const std::vector<double> held =
      toRanks(plan, comm, dest, kHistRec, [&](std::size_t h, double* o) {
        historyRecord(static_cast<double>(st.contacts[h].holder), st.contacts[h], o);
      });
  st = DemState{};  // the input is no longer needed
  dest.resize(n);
  for (std::size_t i = 0; i < n; ++i) dest[i] = static_cast<int>(p.id[i] % P);
  // ids owned by each rank, rank after rank
  const std::vector<double> reg = toRanks(
      plan, comm, dest, 1, [&](std::size_t i, double* o) { o[0] = static_cast<double>(p.id[i]); });
  std::vector<int> histAt;  // rows of `held` kept, in order
  {
    std::vector<std::pair<std::int64_t, int>> owner;  // (id, owner rank)
    std::size_t k = 0;
    for (int r = 0; r < P; ++r)
      for (int c = 0; c < plan.importsFrom(r); ++c, ++k)
        owner.emplace_back(static_cast<std::int64_t>(reg[k]), r);
    std::sort(owner.begin(), owner.end());
    dest.clear();
    for (std::size_t h = 0; h + kHistRec <= held.size(); h += kHistRec) {
      const auto id = historyHolder(&held[h]);
      const auto it = std::lower_bound(owner.begin(), owner.end(), std::make_pair(id, -1));
      if (it == owner.end() || it->first != id) {
        if (err.empty())
          err = fmt::format(
              "a restored contact history names holder {}, which is not among the restored "
              "particles",
              id);
        continue;
      }
      dest.push_back(it->second);
      histAt.push_back(static_cast<int>(h));
    }
  }
  comm.raiseIfAny(err);
  mine = toRanks(plan, comm, dest, kHistRec, [&](std::size_t k, double* o) {
    std::copy_n(held.data() + histAt[k], kHistRec, o);
  });
  // the holder's local row
  std::vector<std::pair<std::int64_t, int>> byId(n);
  for (std::size_t i = 0; i < n; ++i) byId[i] = {p.id[i], static_cast<int>(i)};
  std::sort(byId.begin(), byId.end());
  row.resize(mine.size() / kHistRec);
  for (std::size_t h = 0; h < row.size(); ++h) {
    const auto id = historyHolder(&mine[h * kHistRec]);
    row[h] = std::lower_bound(byId.begin(), byId.end(), std::make_pair(id, -1))->second;
  }
}
}  // namespace

DemFlow DemSolver::Impl::globalFlow() const {
  DemFlow f = flow;
  double buf[8] = {static_cast<double>(f.countOut), f.massOut};
  for (std::size_t k = 0; k < 6; ++k) buf[2 + k] = static_cast<double>(f.countOutByFace[k]);
  comm.sumInPlace(std::span<double>(buf, 8));
  f.countOut = static_cast<long long>(buf[0]);
  f.massOut = buf[1];
  for (std::size_t k = 0; k < 6; ++k) f.countOutByFace[k] = static_cast<long long>(buf[2 + k]);
  return f;
}

void DemSolver::Impl::restore(DemState& st) {
  const int P = comm.size();
  const auto& q = st.particles;
  time = st.time;
  steps = st.steps;
  rebuilds = st.rebuilds;
  {
    // the tallies are global (the same in every rank's state, or absent there): taken from
    // the lowest rank with the longest record; the out tallies continue on rank 0 only (they
    // are summed over the ranks)
    std::vector<double> v = st.flow.pack();
    const auto sizes = comm.allgather(static_cast<long long>(v.size()));
    int from = 0;
    for (int r = 1; r < P; ++r)
      if (sizes[static_cast<std::size_t>(r)] > sizes[static_cast<std::size_t>(from)]) from = r;
    v.resize(static_cast<std::size_t>(sizes[static_cast<std::size_t>(from)]));
    comm.broadcast(std::span<double>(v), from);
    const std::size_t nIn = inflow.size();
    flow = DemFlow::unpack(v);
    flow.due.resize(nIn, 0);
    flow.inserted.resize(nIn, 0);
    flow.dueMass.resize(nIn, 0.0);
    flow.waiting.resize(nIn);
    if (!comm.isRoot()) {
      flow.countOut = 0;
      flow.massOut = 0;
      flow.countOutByFace = {};
    }
  }
  const DemHeat accounts = st.heat;  // (st is emptied below)
  // 1. particles to their owners (by position), a general all-to-all: any rank may hold any
  //    subset of the state
  //    as rows of the state fields; the solver takes the state's extra fields (the same on
  //    every rank: the row widths are compared)
  std::string err;
  for (const auto& e : q.extra)
    if ((e.ops & kOpState) && !std::any_of(p.extra.begin(), p.extra.end(),
                                           [&](const auto& f) { return f.name == e.name; }))
      p.addField(e.name, e.components, e.ops);
  const std::size_t W = rowWidth(q, kOpState);
  if (W != rowWidth(p, kOpState) ||
      comm.max(static_cast<long long>(W)) != comm.min(static_cast<long long>(W)))
    err =
        "the restored state's extra particle fields differ between the ranks or from the solver's";
  comm.raiseIfAny(err);
  // The position of the last rebuild (x0) of each row: where the run that saved built its
  // blocks' particles, bins, ghosts and lists; the current x when the state has none.
  const bool x0Here = std::all_of(st.xRebuild.begin(), st.xRebuild.end(),
                                  [&](const auto& c) { return c.size() == q.nOwned; });
  const bool x0Any =
      std::any_of(st.xRebuild.begin(), st.xRebuild.end(), [](const auto& c) { return !c.empty(); });
  if (!x0Here && x0Any)
    err = "the restored state's rebuild positions (x_rebuild) do not match its particles";
  const bool withX0 = comm.min(x0Here ? 1LL : 0LL) == 1;
  const auto x0 = [&](std::size_t i, int d) {
    return withX0 ? st.xRebuild[static_cast<std::size_t>(d)][i] : q.x[d][i];
  };
  for (std::size_t i = 0; i < q.nOwned && err.empty(); ++i)
    for (int d = 0; d < 3; ++d)
      if (!std::isfinite(x0(i, d))) {
        err = fmt::format(
            "restored particle {} has a rebuild position (x_rebuild) that is not finite", q.id[i]);
        break;
      }
  comm.raiseIfAny(err);
  std::vector<int> dest(q.nOwned);
  std::vector<int> place(q.nOwned);  // row i's place among the rows sent to dest[i]
  {
    std::vector<int> sent(static_cast<std::size_t>(P), 0);
    for (std::size_t i = 0; i < q.nOwned; ++i) {
      const double xi[3] = {x0(i, 0), x0(i, 1), x0(i, 2)};
      dest[i] = ownerRank(xi);
      place[i] = sent[static_cast<std::size_t>(dest[i])]++;
    }
  }
  // a row: the state's fields, then x0
  const std::size_t R = W + 3;
  CommPlan plan;
  std::vector<double> in =
      toRanks(plan, comm, dest, static_cast<int>(R), [&](std::size_t i, double* o) {
        detail::packRow(q, kOpState, i, nullptr, o);
        for (int d = 0; d < 3; ++d) o[W + static_cast<std::size_t>(d)] = x0(i, d);
      });
  const std::size_t n = in.size() / R;
  std::vector<int> firstRowFrom(static_cast<std::size_t>(P));  // arrived rows, rank by rank
  for (int r = 0; r < P; ++r) firstRowFrom[static_cast<std::size_t>(r)] = plan.importOffset(r);
  detail::resizeAll(p, n);
  p.nOwned = n;
  p.nGhost = 0;
  // (id, x now) of every arrived row, by id: the particles sit at x0 for the rebuild below
  // (without x0 they sit at x, where they stay)
  std::vector<std::pair<std::int64_t, std::array<double, 3>>> xNow;
  for (std::size_t i = 0; i < n; ++i) {
    const double* row = in.data() + i * R;
    detail::unpackRow(p, kOpState, row, i, true);
    if (!withX0) continue;
    xNow.push_back({p.id[i], {p.x[0][i], p.x[1][i], p.x[2][i]}});
    for (int d = 0; d < 3; ++d) p.x[d][i] = row[W + static_cast<std::size_t>(d)];
  }
  std::sort(xNow.begin(), xNow.end(),
            [](const auto& a, const auto& b) { return a.first < b.first; });
  for (std::size_t i = 0; i < n && err.empty(); ++i)
    if (p.material[i] < 0 || p.material[i] >= forces.law.nMat)
      err = fmt::format("restored particle {} has material {} ({} declared)", p.id[i],
                        p.material[i], forces.law.nMat);
  comm.raiseIfAny(err);
  // 2. every history to the rank of its holder; `row` = the holder's local row
  std::vector<double> mine;
  std::vector<int> row;
  const bool withRows = st.contactRow.size() == st.contacts.size() &&
                        std::all_of(st.contactRow.begin(), st.contactRow.end(), [&](int a) {
                          return a >= 0 && static_cast<std::size_t>(a) < q.nOwned;
                        });
  if (comm.min(withRows ? 1LL : 0LL) == 1) {
    // in memory: each history goes where its holder went, carrying the holder's place there
    std::vector<int> to(st.contacts.size());
    for (std::size_t h = 0; h < st.contacts.size(); ++h)
      to[h] = dest[static_cast<std::size_t>(st.contactRow[h])];
    mine = toRanks(plan, comm, to, kHistRec, [&](std::size_t h, double* o) {
      const auto a = static_cast<std::size_t>(st.contactRow[h]);
      historyRecord(static_cast<double>(place[a]), st.contacts[h], o);
    });
    row.resize(mine.size() / kHistRec);
    std::size_t k = 0;
    for (int r = 0; r < P; ++r)
      for (int c = 0; c < plan.importsFrom(r); ++c, ++k)
        row[k] = firstRowFrom[static_cast<std::size_t>(r)] +
                 static_cast<int>(historyHolder(&mine[k * kHistRec]));
    st = DemState{};
  } else {
    routeHistoriesById(comm, p, st, plan, mine, row);
  }
  const std::size_t nh = row.size();
  // 3. history rows per local particle (the format migration and the list build use)
  HistoryPool& hist = search.mutableHistory();
  hist.hStart.assign(n + 1, 0);
  for (std::size_t h = 0; h < nh; ++h) ++hist.hStart[static_cast<std::size_t>(row[h]) + 1];
  for (std::size_t i = 0; i < n; ++i) hist.hStart[i + 1] += hist.hStart[i];
  hist.hKey.assign(nh, 0.0);
  hist.hS.assign(3 * nh, 0.0);
  std::vector<int> cur(hist.hStart.begin(), hist.hStart.end() - 1);
  for (std::size_t h = 0; h < nh; ++h) {
    const auto e = static_cast<std::size_t>(cur[static_cast<std::size_t>(row[h])]++);
    const double* rec = &mine[h * kHistRec];
    hist.hKey[e] = static_cast<double>(historyPartner(rec));
    std::copy_n(historyShear(rec), 3, &hist.hS[3 * e]);
  }
  // 4. the saving run's last rebuild, redone: at x0 the particles take the same ranks, the same
  //    (bin, id) order, ghosts and Verlet lists (so the same sums in the same order), and x0 is
  //    again the rebuild check's reference; then every particle moves to where it is now and the
  //    ghosts follow. No force recomputation: the saved forces start the next velocity-Verlet
  //    half step; the force pass below only refreshes the diagnostics (contacts, overlap) and
  //    leaves f, torque and histories as saved
  checkTimeStep();
  rebuild(true);
  search.compactHistory();  // the rows held every history twice (under both particles of a pair)
  trimRows(hist.hKey);      // sized for those rows, now x0 (3 per particle)
  const std::function<std::string()> at = [this] { return where(); };
  for (std::size_t i = 0; i < p.nOwned && err.empty() && withX0; ++i) {
    const auto it = std::lower_bound(xNow.begin(), xNow.end(), p.id[i],
                                     [](const auto& e, std::int64_t id) { return e.first < id; });
    if (it == xNow.end() || it->first != p.id[i]) {
      err = fmt::format(
          "restored particle {} left its rank at the rebuild at its rebuild position (x_rebuild)",
          p.id[i]);
      break;
    }
    for (int d = 0; d < 3; ++d) p.x[d][i] = it->second[static_cast<std::size_t>(d)];
    // where it is now must be a place a step could have left it: inside the walls (a periodic
    // axis wraps at the next rebuild)
    for (int d = 0; d < 3 && err.empty(); ++d)
      if (!search.bins().periodic[d] && detail::crossAxis(p, search.bins(), i, d) == detail::kLost)
        err = detail::lostMessage(p, search.bins(), i, d, at());
  }
  comm.raiseIfAny(err);
  if (withX0) {  // the ghosts to where their owners are now
    ScopedPhase g(timers, Phase::DemGhost);
    exchange->updateGhosts();
  }
  {
    ScopedPhase f(timers, Phase::DemForce);
    std::vector<double> keep;
    keep.reserve(6 * n);
    for (const auto* a : {&p.f, &p.torque})
      for (int k = 0; k < 3; ++k) keep.insert(keep.end(), (*a)[k].begin(), (*a)[k].begin() + n);
    computeForces(false);
    std::size_t o = 0;
    for (auto* a : {&p.f, &p.torque})
      for (int k = 0; k < 3; ++k, o += n)
        std::copy(keep.begin() + static_cast<std::ptrdiff_t>(o),
                  keep.begin() + static_cast<std::ptrdiff_t>(o + n), (*a)[k].begin());
  }
  checkOverlap(comm.max(forces.tally().maxOverlap));
  if (heat.on) restoreHeat(accounts);
}

void DemSolver::Impl::restoreHeat(const DemHeat& a) {
  // the global accounts from the lowest rank whose state has them; each rank keeps the shares of
  // its own state (zero without), so the sums over the ranks are the saved ones. No state has
  // them (a file from before them): zeros, and the run's initial enthalpy is the restored one.
  const int P = comm.size();
  const int from = static_cast<int>(comm.min(a.known ? static_cast<long long>(comm.rank()) : P));
  if (from == P) {
    heat.setAccounts(DemHeat{});
    heat.enthalpyInitial = comm.sum(heat.localEnthalpy(p));
    return;
  }
  DemHeat mine = a.known ? a : DemHeat{};
  double g[2] = {a.enthalpyInitial, a.inflowIn};
  comm.broadcast(std::span<double>(g, 2), from);
  mine.enthalpyInitial = g[0];
  mine.inflowIn = g[1];
  heat.setAccounts(mine);
}

DemState DemSolver::Impl::save() {
  // The solver as it is, untouched: the particles where they are (up to skin/2 outside their
  // block since the last rebuild), their forces, the histories of the current lists, and x0,
  // from which restore() redoes that rebuild.
  DemState st;
  st.time = time;
  st.steps = steps;
  st.rebuilds = rebuilds;
  st.flow = globalFlow();
  if (heat.on) st.heat = heat.accounts();
  const std::size_t n = p.nOwned;
  st.particles = ownedRows(p);
  for (int d = 0; d < 3; ++d) {
    const double* x0 = search.history().x0(d, n);
    st.xRebuild[static_cast<std::size_t>(d)].assign(x0, x0 + n);
  }
  // every touching history under each owned particle of the pair (a restart on other ranks may
  // separate them), as seen from that particle
  for (std::size_t q = 0; q < p.size(); ++q) {
    const auto a = static_cast<std::size_t>(search.bins().binItems[q]);
    for (int e = search.list().rowStart[q]; e < search.list().rowStart[q + 1]; ++e) {
      const int sl = search.list().slot[static_cast<std::size_t>(e)];
      if (sl < 0) continue;
      const double* sh = &search.history().hS[3 * static_cast<std::size_t>(sl)];
      if (sh[0] == 0 && sh[1] == 0 && sh[2] == 0) continue;
      const int j = search.list().nbr[static_cast<std::size_t>(e)];
      if (a < n) {
        ContactHistory c;
        c.holder = p.id[a];
        c.partner = j >= 0 ? p.id[static_cast<std::size_t>(j)] : j;
        c.shear = {sh[0], sh[1], sh[2]};
        st.contacts.push_back(c);
        st.contactRow.push_back(static_cast<int>(a));
      }
      if (j >= 0 && static_cast<std::size_t>(j) < n) {
        ContactHistory c;
        c.holder = p.id[static_cast<std::size_t>(j)];
        c.partner = p.id[a];
        c.shear = {-sh[0], -sh[1], -sh[2]};
        st.contacts.push_back(c);
        st.contactRow.push_back(j);
      }
    }
  }
  return st;
}

}  // namespace coloc::dem
