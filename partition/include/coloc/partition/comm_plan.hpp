// coloc/partition/comm_plan.hpp — the one irregular communication plan: which items of this
// rank go to which ranks, built once, then reused for any number of exchanges of rows.
//
// A plan is built from (destination rank, local index) pairs: item `index[k]` of this rank is
// exported to rank `rank[k]` (an item may be exported to several ranks: copies). The counts are
// exchanged once, at build (an alltoall of one count per rank, or messages to the listed
// neighbours only when the plan knows them, or nothing when the caller knows the import counts).
// Exports are grouped by destination in the order they were given (stable); imports arrive
// grouped by source rank, ascending, in the order the source gave them: the order is the same on
// every run and independent of message timing. The rows a rank exports to itself are copied in
// memory. Payload messages go only to the ranks with rows (no alltoall of payload).
//
//   forward(src, w, dst)      owner -> copies (gather, distribute, migrate): row index[k] of
//                             `src` (w doubles) to import position p of `dst` on rank[k].
//   reverse(src, w, dst)      copies -> owner: import row p returns to row index[k]
//                             (overwritten; with several copies the last in export order wins).
//   reverseSum(src, w, dst)   copies -> owner, summed: dst[index[k]] += the returned rows, in
//                             export order (fixed, so the sums are deterministic).
//   forwardVariable(...)      rows of varying length (e.g. contact histories): the lengths go
//                             first (one exchange), then the payload (a second one).
//
// Buffers live in the plan and grow only. Every operation returns what this rank sent, split
// into bytes to other ranks (messages) and bytes kept in memory, for the exchange ledger
// (core/timers.hpp): the plan books nothing itself, the caller names the kind.
#pragma once

#include <cstddef>
#include <span>
#include <vector>

#include "coloc/core/comm.hpp"

namespace coloc {

/// What one operation sent from this rank.
struct PlanTraffic {
  long long remoteBytes = 0;  // to other ranks
  long long localBytes = 0;   // rows this rank exported to itself (copied in memory)
  long long messages = 0;     // other ranks that received a non-empty message
};

class CommPlan {
 public:
  CommPlan() = default;
  /// Item index[k] goes to rank[k]. Collective: the counts are exchanged by an alltoall of one
  /// count per rank.
  CommPlan(const Comm& comm, std::span<const int> rank, std::span<const int> index);
  /// The same when the plan knows its neighbours: `neighbours` are the only ranks that may send
  /// to or receive from this one (a symmetric relation; this rank may be among them); the counts
  /// go in one message to each of them, nothing to the others.
  static CommPlan withNeighbours(const Comm& comm, std::span<const int> rank,
                                 std::span<const int> index, std::span<const int> neighbours);
  /// Item i goes to dest[i] (migration, proxies). Collective as above (alltoall of counts).
  static CommPlan fromDestinations(const Comm& comm, std::span<const int> dest);
  /// Rebuilds this plan for new destinations (dest[i] for item i), reusing its storage: the
  /// per-step form of fromDestinations (no allocation once the plan has seen its largest size).
  void rebuild(std::span<const int> dest);
  /// Rebuilds this plan as withNeighbours(comm, rank, index, neighbours) would build it, reusing
  /// its storage (per-rebuild form: no allocation once the plan has seen its largest size).
  void rebuild(const Comm& comm, std::span<const int> rank, std::span<const int> index,
               std::span<const int> neighbours);
  /// Items already grouped by destination (sendCounts[r] consecutive items for rank r, index =
  /// position), the import counts learnt from the neighbours only (one message to each); storage
  /// reused. For rows laid end to end whose lengths vary (the items are then doubles).
  void rebuildFromCounts(const Comm& comm, std::span<const int> sendCounts,
                         std::span<const int> neighbours);
  /// First import / export row of rank r (its rows are importsFrom(r) / exportsTo(r) long).
  int importOffset(int r) const { return recvOffset_[static_cast<std::size_t>(r)]; }
  int exportOffset(int r) const { return sendOffset_[static_cast<std::size_t>(r)]; }

  /// Items already grouped by destination (sendCounts[r] consecutive items for rank r, index =
  /// position) and the import counts known to the caller (recvCounts[r] from rank r): no
  /// communication at build (re-mapping between two known decompositions).
  static CommPlan fromCounts(const Comm& comm, std::vector<int> sendCounts,
                             std::vector<int> recvCounts);

  const Comm& comm() const { return comm_; }
  std::size_t exportCount() const { return exportIndex_.size(); }
  std::size_t importCount() const { return static_cast<std::size_t>(recvOffset_.back()); }
  /// Local index of export k (k in destination order) and its rank.
  std::span<const int> exportIndex() const { return exportIndex_; }
  /// Rows coming from / going to each rank (size() entries).
  int importsFrom(int r) const { return recvCount_[static_cast<std::size_t>(r)]; }
  int exportsTo(int r) const { return sendCount_[static_cast<std::size_t>(r)]; }

  /// Owner -> copies: src holds rows indexed by local index (w doubles each), dst receives
  /// importCount() rows. Collective over the ranks of the plan.
  PlanTraffic forward(std::span<const double> src, int w, std::span<double> dst);
  /// Packing in place (no gather copy): the plan's send buffer, exportCount() rows of w doubles
  /// in export order (row k is item exportIndex()[k]); fill it, then forwardPacked().
  std::span<double> packBuffer(int w);
  PlanTraffic forwardPacked(int w, std::span<double> dst);
  /// Copies -> owner without the scatter: dst receives exportCount() rows in export order (row k
  /// belongs to item exportIndex()[k]).
  PlanTraffic reverseInExportOrder(std::span<const double> src, int w, std::span<double> dst);
  /// Copies -> owner: src holds importCount() rows; row index[k] of dst is overwritten.
  PlanTraffic reverse(std::span<const double> src, int w, std::span<double> dst);
  /// Copies -> owner, added to dst[index[k]] in export order.
  PlanTraffic reverseSum(std::span<const double> src, int w, std::span<double> dst);
  /// Rows of varying length: row i of src is src[offset[i], offset[i+1]). dst gets the imported
  /// rows back to back and dstOffset (importCount() + 1 entries) where each starts.
  PlanTraffic forwardVariable(std::span<const double> src, std::span<const long long> offset,
                              std::vector<double>& dst, std::vector<long long>& dstOffset);

 private:
  CommPlan(const Comm& comm, std::span<const int> rank, std::span<const int> index, int);
  void group(std::span<const int> rank, std::span<const int> index);  // exports by rank, stable
  void finish();  // offsets and peer lists from the counts
  // recvCount_ from one count message to and from each neighbour (validated; no others).
  void neighbourCounts(std::span<const int> neighbours);
  // Blocks of `send` (offsets sOff in doubles, per rank) to the ranks, blocks from the ranks into
  // `recv` (offsets rOff); the block to this rank itself is copied.
  PlanTraffic exchange(const double* send, const std::vector<long long>& sOff,
                       const std::vector<int>& sPeers, double* recv,
                       const std::vector<long long>& rOff, const std::vector<int>& rPeers);

  Comm comm_;
  int me_ = 0;
  std::vector<int> exportIndex_;                    // local index of each export, grouped by rank
  std::vector<int> sendCount_, recvCount_;          // rows per rank
  std::vector<int> sendOffset_{0}, recvOffset_{0};  // first row per rank (size() + 1 entries)
  std::vector<int> sendPeers_, recvPeers_;          // other ranks with rows, ascending
  std::vector<long long> sOff_, rOff_;              // scratch: offsets in doubles for one exchange
  std::vector<double> sendBuf_, recvBuf_;
  std::vector<int> peers_;  // scratch: the neighbours, sorted
  std::vector<MPI_Request> requests_;
};

}  // namespace coloc
