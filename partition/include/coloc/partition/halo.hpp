// coloc/partition/halo.hpp — the halo plan: built once for a field layout, reused every step.
//
// gather():     owned values -> neighbours' ghost layers (faces, edges and corners), by three
//               staged sweeps x, y, z with non-blocking MPI; each sweep carries the ghosts filled
//               by the previous ones, so edges and corners arrive without diagonal messages.
// scatterSum(): the reverse (z, y, x): ghost contributions are sent to the owner and added to
//               its owned values, then the ghosts are zeroed; used for deposition. At a
//               non-periodic box face, Fold::Mirror adds ghost layer -1-m onto owned layer m
//               (contributions of a kernel that pokes through a wall stay in the domain), Keep
//               leaves them in the ghosts. With timers, the fold is booked to the
//               coupling_deposit phase (arithmetic inside the block, not an exchange).
// Buffers are allocated on first use for the largest field count seen and never again.
// Every message is booked in the Timers ledger under the exchange kind the caller names.
// On a tiled decomposition the plan holds a BoxHaloPlan (partition/box_halo.hpp) and forwards
// both operations to it: one message per box neighbour, same results (sums to rounding). The box
// plan's index tables are made for the storage layout of the fields it is applied to (which may
// keep more ghost layers than the plan moves): built again only when that layout changes.
#pragma once

#include <memory>
#include <span>
#include <vector>

#include "coloc/core/timers.hpp"
#include "coloc/partition/decomposition.hpp"
#include "coloc/partition/field.hpp"

namespace coloc {

enum class Fold { Keep, Mirror };
class BoxHaloPlan;

class HaloPlan {
 public:
  HaloPlan() = default;
  /// Throws ConfigError if a block is thinner than the ghost width along an axis with neighbours.
  /// `storage`: the layout of the fields the plan will move (more ghost layers than `layout`
  /// moves, or the same); a tiled plan builds its index tables for it once, here.
  HaloPlan(const Decomposition& dec, const FieldLayout& layout);
  HaloPlan(const Decomposition& dec, const FieldLayout& layout, const FieldLayout& storage);

  const FieldLayout& layout() const { return layout_; }

  void gather(std::span<Field3<double>* const> fields, Timers* timers = nullptr,
              Exchange kind = Exchange::IntraPhysics, Traffic traffic = Traffic::Auto);
  void gather(Field3<double>& f, Timers* timers = nullptr, Exchange kind = Exchange::IntraPhysics,
              Traffic traffic = Traffic::Auto) {
    Field3<double>* p = &f;
    gather(std::span<Field3<double>* const>(&p, 1), timers, kind, traffic);
  }
  void scatterSum(std::span<Field3<double>* const> fields, Fold fold, Timers* timers = nullptr,
                  Exchange kind = Exchange::InterPhysicsRemote, Traffic traffic = Traffic::Auto);
  void scatterSum(Field3<double>& f, Fold fold, Timers* timers = nullptr,
                  Exchange kind = Exchange::InterPhysicsRemote, Traffic traffic = Traffic::Auto) {
    Field3<double>* p = &f;
    scatterSum(std::span<Field3<double>* const>(&p, 1), fold, timers, kind, traffic);
  }

  /// Bytes this rank sends in one gather of one field (for reports and benchmarks).
  long long bytesPerGather() const;
  /// True when some neighbour is another rank. A block that is only its own neighbour (periodic
  /// axes on one rank) copies in memory: its sweeps book no exchange time (nothing is sent).
  bool crossesRanks() const;

 private:
  struct Side {
    int peer = MPI_PROC_NULL;
    IndexBox ownedEdge;  // owned layers next to this side: sent by gather, summed into by scatter
    IndexBox ghost;      // ghost layers beyond this side: received by gather, sent by scatter
  };
  void sweep(int d, std::span<Field3<double>* const> fields, bool reverse, Timers* timers,
             Exchange kind, Traffic traffic);
  void fold(int d, std::span<Field3<double>* const> fields);
  void ensureBuffers(std::size_t nFields);
  BoxHaloPlan& boxPlanFor(std::span<Field3<double>* const> fields);

  std::shared_ptr<BoxHaloPlan> box_;  // tiled layouts: the general box plan does the work
  const Decomposition* dec_ = nullptr;
  FieldLayout layout_;
  int me_ = 0;
  std::array<std::array<Side, 2>, 3> sides_{};
  std::array<std::array<std::vector<double>, 2>, 3> sendBuf_, recvBuf_;
  std::size_t buffersFor_ = 0;
};

}  // namespace coloc
