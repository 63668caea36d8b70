// dem/src/exchange.hpp — the particle exchange of the DEM: migration (owned particles that left
// the block go to their new owner, with their contact histories), the ghost build at a rebuild and
// the ghost update between rebuilds. One interface, two implementations, chosen once at set-up
// from the decomposition (makeExchange):
//   exchange_grid.cpp   a process grid: three staged sweeps (x, y, z), two faces each
//   exchange_tiled.cpp  a tiled layout (general boxes): one exchange with the boxes near this one
// The migrant rows both share are in exchange.cpp. An exchange owns its plans and buffers and
// works on what its owner lends it (ExchangeContext): the particles, the history rows, the bins,
// the communicator and the timers; it needs no DemSolver. Rows are those of the field table
// (rows.hpp); the transport is a CommPlan (partition/comm_plan.hpp).
#pragma once

#include <cmath>
#include <cstddef>
#include <functional>
#include <memory>
#include <span>
#include <string>
#include <vector>

#include "bins.hpp"
#include "buffers.hpp"
#include "coloc/core/timers.hpp"
#include "coloc/dem/dem.hpp"
#include "coloc/partition/comm_plan.hpp"
#include "history.hpp"

namespace coloc::dem::detail {

/// What an exchange works on, lent by its owner for the exchange's lifetime.
struct ExchangeContext {
  const Decomposition& dec;
  const Comm& comm;
  Timers& timers;     // the ledger of the exchanges (Traffic::DemMigrate, DemGhost)
  ParticleStore& p;   // owned rows [0, nOwned), then the ghosts
  HistoryPool& hist;  // rows per owned particle (hStart, hKey, hS): what migrants carry
  const Bins& bins;   // box, periodic axes, block bounds, owner rule
  double rc = 0;      // interaction range: an owned particle this close to a block is a ghost there
  /// Appended to error messages (" on rank r at step s, t = ..."); called only on an error.
  std::function<std::string()> where;
};

/// Migration along axis d of owned particle i: wraps its position across a periodic face,
/// returns -1 / +1 when it leaves the block through the low / high face along d, else 0;
/// kLost for a non-finite particle or one beyond a wall (lostMessage says which; the particle
/// is left as it was).
inline constexpr int kLost = 2;
int crossAxis(ParticleStore& p, const Bins& bins, std::size_t i, int d);
/// Why crossAxis found particle i lost along d: the message of the error, `where` (rank, step,
/// time) in it.
std::string lostMessage(const ParticleStore& p, const Bins& bins, std::size_t i, int d,
                        const std::string& where);

class ParticleExchange {
 public:
  virtual ~ParticleExchange() = default;
  ParticleExchange(const ParticleExchange&) = delete;
  ParticleExchange& operator=(const ParticleExchange&) = delete;

  /// Drops the ghosts, wraps owned positions across periodic faces, and sends every owned
  /// particle that left this block to its new owner (its kOpMigrate row and history rows);
  /// arrivals are appended as owned particles. Collective; raises (Comm::raiseIfAny) when a
  /// particle is non-finite or beyond a wall, or (tiled) moved beyond the boxes next to this one.
  virtual void migrate() = 0;
  /// Appends as ghosts the owned particles of other blocks (and periodic images) within the
  /// interaction range of this block, and keeps the plan for updateGhosts. Collective.
  virtual void buildGhosts() = 0;
  /// The ghosts' kOpGhostUpdate fields refreshed from their owners (same rows as the last build).
  virtual void updateGhosts() = 0;
  /// Bytes held by the plans' buffers (capacities).
  virtual std::size_t bytes() const = 0;

 protected:
  explicit ParticleExchange(const ExchangeContext& c) : c_(c) {}

  static constexpr int kLost = detail::kLost;
  /// crossAxis on the lent particles; the first loss of the migration noted (fail).
  int crossAxis(std::size_t i, int d) {
    const int dir = detail::crossAxis(c_.p, c_.bins, i, d);
    if (dir == kLost) fail([&] { return detail::lostMessage(c_.p, c_.bins, i, d, c_.where()); });
    return dir;
  }
  /// Notes the first failure of a migration (the message made only then); raiseFailure() at the
  /// migration's end raises it on every rank (collective) and clears it.
  template <class Message>
  void fail(Message&& message) {
    if (failure_.empty()) failure_ = message();
  }
  void raiseFailure() {
    std::string f;
    f.swap(failure_);
    c_.comm.raiseIfAny(f);
  }
  /// A migrant's row: the field table's kOpMigrate row (W doubles), its history count, then
  /// (partner id, shear 3) per history.
  std::size_t migrantLength(std::size_t i, std::size_t W) const {
    const auto h = static_cast<std::size_t>(c_.hist.hStart[i + 1] - c_.hist.hStart[i]);
    return W + 1 + 4 * h;
  }
  void packMigrant(std::size_t i, std::size_t W, std::span<double> out) const;
  /// Migrant rows laid end to end appended as owned particles.
  void unpackMigrants(std::span<const double> rows, std::size_t W);
  /// Owned row i kept as row w (w <= i) while rows before it leave, with its history rows.
  void keep(std::size_t i, std::size_t w, int& hw) {
    keepRow(c_.p, c_.hist, i, w, c_.hist.hStart[i], c_.hist.hStart[i + 1], hw);
  }

  ExchangeContext c_;
  std::string failure_;       // the first failure of the migration under way (empty: none)
  std::vector<double> rbuf_;  // imports of one exchange
  CommPlan mig_;              // migration (items: the doubles of the packed rows)
  std::vector<int> rank_, index_, counts_;  // scratch of the plan builds
};

/// The exchange of a process grid.
std::unique_ptr<ParticleExchange> gridExchange(const ExchangeContext& c);
/// The exchange of a tiled layout (Decomposition::isTiled); `b`: the bins of every box.
std::unique_ptr<ParticleExchange> tiledExchange(const ExchangeContext& c, const BinLayout& b);
/// The exchange of the decomposition c.dec (once, at set-up; c.bins set up for it).
inline std::unique_ptr<ParticleExchange> makeExchange(const ExchangeContext& c,
                                                      const BinLayout& b) {
  return c.dec.isTiled() ? tiledExchange(c, b) : gridExchange(c);
}

/// The ledger entry of one plan operation: its payload, plus the count messages of a build.
inline void book(Timers& timers, const PlanTraffic& t, long long countMessages, double seconds,
                 Traffic kind) {
  const long long msgs = t.messages + countMessages;
  if (msgs > 0) timers.book(Exchange::IntraPhysics, t.remoteBytes, msgs, seconds, kind);
}

}  // namespace coloc::dem::detail
