// dem/src/ghosts.hpp — the ghost plan of the DEM. On a process grid: per axis, the send lists of
// the two faces and the CommPlan (partition/comm_plan.hpp) built from them at each rebuild and
// reused by the ghost updates between rebuilds (no count exchange then); one plan rebuilt per
// migration sweep. On a tiled layout (Decomposition::isTiled, ghosts_tiled.cpp): the boxes near
// this one (targets), one plan per ghost build for all of them, one exchange per migration. Rows
// are those of the field table (rows.hpp).
#pragma once

#include <array>
#include <vector>

#include "buffers.hpp"
#include "coloc/core/timers.hpp"
#include "coloc/partition/comm_plan.hpp"

namespace coloc::dem::detail {

struct GhostPlan {
  struct Swap {  // 0: to the low neighbour, 1: to the high one
    std::vector<int> send;
    double shift = 0;  // added to the position along the axis (periodic faces)
  };
  /// Where the ghosts of one sweep come from: `count` rows at import row `from` of the axis'
  /// plan become ghosts `at`, ... (rows from the high neighbour first, then the low one).
  struct Segment {
    int from = 0, count = 0, at = 0;
  };
  std::array<std::array<Swap, 2>, 3> swaps;
  std::array<CommPlan, 3> plan;  // ghost build / update, one per axis
  std::array<std::array<Segment, 2>, 3> seg;
  std::array<int, 3> nSeg{};
  CommPlan mig;  // one migration sweep (items: the doubles of the packed rows)
  std::array<std::vector<double>, 2> sbuf;  // migration rows per face
  std::vector<double> rbuf;                 // imports of one exchange
  std::vector<int> rank, index, counts;     // scratch of the plan builds

  // Tiled layouts. A target is a box whose bins lie within one bin (the interaction range) of
  // this box's, or a periodic image of one (this box's own images included): an owned particle
  // whose position + shift lies in [lo, hi) (the target's bounds widened by the range) is a
  // ghost there. Targets are ordered by rank, then image, so the ghosts of a build arrive by
  // source rank, target image, source row: the same order on every run.
  struct Target {
    int rank = 0;
    std::array<double, 3> shift{}, lo{}, hi{};
  };
  bool tiled = false;
  std::vector<Target> targets;
  std::vector<int> near;  // the targets' ranks, distinct, ascending (this rank if it has images)
  std::vector<int> runs;  // rows per target of the last ghost build (consecutive in the plan)
  std::vector<int> cand;  // scratch: owned particles within the range of a face of this box
  std::vector<int> dest;  // scratch: destination of every owned particle (migration)
  std::vector<long long> at;  // scratch: next export position per rank (migration)
  CommPlan box;               // ghost build / update on the targets

  std::size_t bytes() const {
    std::size_t b = cap(sbuf[0]) + cap(sbuf[1]) + cap(rbuf) + cap(rank) + cap(index) +
                    cap(targets) + cap(near) + cap(runs) + cap(cand) + cap(dest) + cap(at);
    for (const auto& a : swaps)
      for (const auto& s : a) b += cap(s.send);
    return b;
  }
};

/// The ledger entry of one plan operation: its payload, plus the count messages of a build.
inline void book(Timers& timers, const PlanTraffic& t, long long countMessages, double seconds,
                 Traffic kind) {
  const long long msgs = t.messages + countMessages;
  if (msgs > 0) timers.book(Exchange::IntraPhysics, t.remoteBytes, msgs, seconds, kind);
}

}  // namespace coloc::dem::detail
