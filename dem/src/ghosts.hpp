// dem/src/ghosts.hpp — the ghost plan of the DEM: per axis, the send lists of the two faces and
// the CommPlan (partition/comm_plan.hpp) built from them at each rebuild and reused by the ghost
// updates between rebuilds (no count exchange then); one plan rebuilt per migration sweep. Rows
// are those of the field table (rows.hpp).
#pragma once

#include <array>
#include <vector>

#include "buffers.hpp"
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
  std::size_t bytes() const {
    std::size_t b = cap(sbuf[0]) + cap(sbuf[1]) + cap(rbuf) + cap(rank) + cap(index);
    for (const auto& a : swaps)
      for (const auto& s : a) b += cap(s.send);
    return b;
  }
};

}  // namespace coloc::dem::detail
