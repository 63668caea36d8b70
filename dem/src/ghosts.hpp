// dem/src/ghosts.hpp — the ghost plan of the DEM: send lists per axis and side, built at each
// rebuild and reused by the ghost updates between rebuilds; the send/receive buffers of the
// face exchanges (ghosts and migration) hold rows of the field table (rows.hpp).
#pragma once

#include <array>
#include <vector>

#include "buffers.hpp"

namespace coloc::dem::detail {

struct GhostPlan {
  struct Swap {  // 0: to the low neighbour, 1: to the high one
    std::vector<int> send;
    double shift = 0;                  // added to the position along the axis (periodic faces)
    int recvStart = 0, recvCount = 0;  // ghosts received from the opposite neighbour
  };
  std::array<std::array<Swap, 2>, 3> swaps;
  std::array<std::vector<double>, 2> sbuf, rbuf;
  std::size_t bytes() const {
    std::size_t b = cap(sbuf[0]) + cap(sbuf[1]) + cap(rbuf[0]) + cap(rbuf[1]);
    for (const auto& a : swaps)
      for (const auto& s : a) b += cap(s.send);
    return b;
  }
};

}  // namespace coloc::dem::detail
