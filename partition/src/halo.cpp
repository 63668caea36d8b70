#include "coloc/partition/halo.hpp"

#include <fmt/format.h>

#include <string>

#include "coloc/core/error.hpp"
#include "coloc/partition/box_halo.hpp"

namespace coloc {
namespace {

template <class F>
void forBox(const Field3<double>& f, const IndexBox& b, F&& fn) {
  for (int k = b.lo[2]; k < b.hi[2]; ++k)
    for (int j = b.lo[1]; j < b.hi[1]; ++j) {
      const std::ptrdiff_t base = f.index(b.lo[0], j, k);
      const int nx = b.hi[0] - b.lo[0];
      for (int i = 0; i < nx; ++i) fn(static_cast<std::size_t>(base + i));
    }
}

std::size_t pack(std::span<Field3<double>* const> fields, const IndexBox& b, double* out) {
  std::size_t n = 0;
  for (auto* f : fields) {
    const double* src = f->data().data();
    forBox(*f, b, [&](std::size_t idx) { out[n++] = src[idx]; });
  }
  return n;
}

void unpack(std::span<Field3<double>* const> fields, const IndexBox& b, const double* in,
            bool add) {
  std::size_t n = 0;
  for (auto* f : fields) {
    double* dst = f->data().data();
    if (add)
      forBox(*f, b, [&](std::size_t idx) { dst[idx] += in[n++]; });
    else
      forBox(*f, b, [&](std::size_t idx) { dst[idx] = in[n++]; });
  }
}

}  // namespace

HaloPlan::HaloPlan(const Decomposition& dec, const FieldLayout& layout)
    : HaloPlan(dec, layout, layout) {}

HaloPlan::HaloPlan(const Decomposition& dec, const FieldLayout& layout, const FieldLayout& storage)
    : dec_(&dec), layout_(layout), me_(dec.rank()) {
  if (dec.isTiled()) {
    // refuses thin boxes now
    box_ = std::make_shared<BoxHaloPlan>(dec.comm(), boxLayoutOf(dec), layout, storage);
    return;
  }
  const int g = layout.ghost;
  const IndexBox all = layout.allocated();
  for (int d = 0; d < 3; ++d) {
    const int n = layout.n[d], s = layout.stagger[d];
    static const char* axis[3] = {"x", "y", "z"};
    if (g > n && (dec.neighbour(d, -1) != MPI_PROC_NULL || dec.neighbour(d, +1) != MPI_PROC_NULL))
      throw ConfigError("partition.dims",
                        fmt::format("a block is {} cells thick along {}, thinner than the {} "
                                    "ghost layers the solvers need: use fewer ranks along that "
                                    "axis",
                                    n, axis[d], g));
    Side low, high;
    low.peer = dec.neighbour(d, -1);
    high.peer = dec.neighbour(d, +1);
    low.ownedEdge = all;
    low.ownedEdge.lo[d] = 0;
    low.ownedEdge.hi[d] = g + s;
    low.ghost = all;
    low.ghost.lo[d] = -g;
    low.ghost.hi[d] = 0;
    high.ownedEdge = all;
    high.ownedEdge.lo[d] = n - g;
    high.ownedEdge.hi[d] = n;
    high.ghost = all;
    high.ghost.lo[d] = n;
    high.ghost.hi[d] = n + g + s;
    sides_[d] = {low, high};
  }
}

void HaloPlan::ensureBuffers(std::size_t nFields) {
  if (nFields <= buffersFor_) return;
  for (int d = 0; d < 3; ++d)
    for (int s = 0; s < 2; ++s) {
      const auto& side = sides_[d][s];
      const long long v = std::max(side.ownedEdge.volume(), side.ghost.volume());
      sendBuf_[d][s].assign(static_cast<std::size_t>(v) * nFields, 0.0);
      recvBuf_[d][s].assign(static_cast<std::size_t>(v) * nFields, 0.0);
    }
  buffersFor_ = nFields;
}

BoxHaloPlan& HaloPlan::boxPlanFor(std::span<Field3<double>* const> fields) {
  // Fields of another storage than the one given at construction: tables for theirs (once).
  if (fields.empty() || fields[0]->layout() == box_->storage()) return *box_;
  box_ =
      std::make_shared<BoxHaloPlan>(dec_->comm(), boxLayoutOf(*dec_), layout_, fields[0]->layout());
  return *box_;
}

long long HaloPlan::bytesPerGather() const {
  if (box_) return box_->bytesPerGather();
  long long b = 0;
  for (int d = 0; d < 3; ++d)
    for (int s = 0; s < 2; ++s)
      if (sides_[d][s].peer != MPI_PROC_NULL)
        b += sides_[d][s].ownedEdge.volume() * static_cast<long long>(sizeof(double));
  return b;
}

void HaloPlan::sweep(int d, std::span<Field3<double>* const> fields, bool reverse, Timers* timers,
                     Exchange kind, Traffic traffic) {
  if (sides_[d][0].peer == MPI_PROC_NULL && sides_[d][1].peer == MPI_PROC_NULL) return;
  const Comm& comm = dec_->comm();
  const double t0 = MPI_Wtime();
  MPI_Request reqs[4];
  int nreq = 0;
  long long bytes = 0, msgs = 0;
  // Tags by direction of travel, so a rank that is its own neighbour (periodic, one block)
  // matches its two messages correctly.
  const int tagDown = 2 * d, tagUp = 2 * d + 1;
  for (int s = 0; s < 2; ++s) {
    const Side& side = sides_[d][s];
    if (side.peer == MPI_PROC_NULL) continue;
    // gather: receive into my ghosts what the peer sends from its owned edge;
    // scatter: receive into a buffer what the peer sends from its ghosts, to add to my edge.
    const IndexBox& rbox = reverse ? side.ownedEdge : side.ghost;
    const std::size_t count = static_cast<std::size_t>(rbox.volume()) * fields.size();
    const int tag = (s == 0) ? tagUp : tagDown;  // from my low peer data travels up
    reqs[nreq++] = comm.irecv(std::span<double>(recvBuf_[d][s].data(), count), side.peer, tag);
  }
  for (int s = 0; s < 2; ++s) {
    const Side& side = sides_[d][s];
    if (side.peer == MPI_PROC_NULL) continue;
    const IndexBox& sbox = reverse ? side.ghost : side.ownedEdge;
    const std::size_t count = pack(fields, sbox, sendBuf_[d][s].data());
    const int tag = (s == 0) ? tagDown : tagUp;
    reqs[nreq++] =
        comm.isend(std::span<const double>(sendBuf_[d][s].data(), count), side.peer, tag);
    if (side.peer != me_) {
      bytes += static_cast<long long>(count * sizeof(double));
      ++msgs;
    }
  }
  MPI_Waitall(nreq, reqs, MPI_STATUSES_IGNORE);
  for (int s = 0; s < 2; ++s) {
    const Side& side = sides_[d][s];
    if (side.peer == MPI_PROC_NULL) continue;
    if (reverse) {
      unpack(fields, side.ownedEdge, recvBuf_[d][s].data(), /*add=*/true);
    } else {
      unpack(fields, side.ghost, recvBuf_[d][s].data(), /*add=*/false);
    }
  }
  if (reverse) {
    for (int s = 0; s < 2; ++s) {
      const Side& side = sides_[d][s];
      if (side.peer == MPI_PROC_NULL) continue;
      for (auto* f : fields) {
        double* p = f->data().data();
        forBox(*f, side.ghost, [&](std::size_t idx) { p[idx] = 0.0; });
      }
    }
  }
  // Time only where something left the rank: a rank that is its own neighbour copies in memory.
  if (timers) timers->book(kind, bytes, msgs, msgs > 0 ? MPI_Wtime() - t0 : 0.0, traffic);
}

bool HaloPlan::crossesRanks() const {
  if (box_) {
    for (int q : box_->neighbours())
      if (q != me_) return true;
    return false;
  }
  for (const auto& d : sides_)
    for (const auto& side : d)
      if (side.peer != MPI_PROC_NULL && side.peer != me_) return true;
  return false;
}

void HaloPlan::fold(int d, std::span<Field3<double>* const> fields) {
  if (layout_.stagger[d]) return;
  const int g = layout_.ghost, n = layout_.n[d];
  const IndexBox all = layout_.allocated();
  for (int s = 0; s < 2; ++s) {
    if (sides_[d][s].peer != MPI_PROC_NULL) continue;
    for (auto* f : fields) {
      for (int m = 0; m < g; ++m) {
        const int ghostLayer = s == 0 ? -1 - m : n + m;
        const int ownedLayer = s == 0 ? std::min(m, n - 1) : std::max(n - 1 - m, 0);
        IndexBox layer = all;
        layer.lo[d] = ghostLayer;
        layer.hi[d] = ghostLayer + 1;
        const std::ptrdiff_t shift = (ownedLayer - ghostLayer) * (d == 0   ? 1
                                                                  : d == 1 ? f->strideY()
                                                                           : f->strideZ());
        double* p = f->data().data();
        forBox(*f, layer, [&](std::size_t idx) {
          p[static_cast<std::ptrdiff_t>(idx) + shift] += p[idx];
          p[idx] = 0.0;
        });
      }
    }
  }
}

void HaloPlan::gather(std::span<Field3<double>* const> fields, Timers* timers, Exchange kind,
                      Traffic traffic) {
  if (box_) return boxPlanFor(fields).gather(fields, timers, kind, traffic);
  ensureBuffers(fields.size());
  for (int d = 0; d < 3; ++d) sweep(d, fields, /*reverse=*/false, timers, kind, traffic);
}

void HaloPlan::scatterSum(std::span<Field3<double>* const> fields, Fold f, Timers* timers,
                          Exchange kind, Traffic traffic) {
  if (box_) return boxPlanFor(fields).scatterSum(fields, f, timers, kind, traffic);
  ensureBuffers(fields.size());
  for (int d = 2; d >= 0; --d) {
    sweep(d, fields, /*reverse=*/true, timers, kind, traffic);
    if (f != Fold::Mirror) continue;
    // The fold at walls is the kernel's boundary treatment, arithmetic inside the block, not
    // an exchange: booked to the deposition phase.
    if (timers) timers->start(Phase::CouplingDeposit);
    fold(d, fields);
    if (timers) timers->stop(Phase::CouplingDeposit);
  }
}

}  // namespace coloc
