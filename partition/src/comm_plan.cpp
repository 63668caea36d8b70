#include "coloc/partition/comm_plan.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <string>

#include "coloc/core/error.hpp"

namespace coloc {

namespace {
constexpr int kTagCounts = 7301;
constexpr int kTagRows = 7302;
}  // namespace

CommPlan::CommPlan(const Comm& comm, std::span<const int> rank, std::span<const int> index, int)
    : comm_(comm), me_(comm.rank()) {
  group(rank, index);
}

void CommPlan::group(std::span<const int> rank, std::span<const int> index) {
  // `index` empty: item k is rank[k]'s item k (identity).
  const int size = comm_.size();
  if (!index.empty() && rank.size() != index.size())
    throw Error("CommPlan: rank and index differ in length");
  sendCount_.assign(static_cast<std::size_t>(size), 0);
  std::string err;
  for (int r : rank) {
    if (r < 0 || r >= size) {
      err = fmt::format("CommPlan: destination rank {} outside the communicator", r);
      break;
    }
    ++sendCount_[static_cast<std::size_t>(r)];
  }
  if (!err.empty()) throw Error(err);
  // Group by destination, stable: a counting sort (sendOffset_ as the running position).
  sendOffset_.assign(static_cast<std::size_t>(size) + 1, 0);
  for (std::size_t r = 0; r < static_cast<std::size_t>(size); ++r)
    sendOffset_[r + 1] = sendOffset_[r] + sendCount_[r];
  exportIndex_.resize(rank.size());
  for (std::size_t k = 0; k < rank.size(); ++k)
    exportIndex_[static_cast<std::size_t>(sendOffset_[static_cast<std::size_t>(rank[k])]++)] =
        index.empty() ? static_cast<int>(k) : index[k];
}

void CommPlan::rebuild(std::span<const int> dest) {
  group(dest, {});
  comm_.alltoall(sendCount_, recvCount_);
  finish();
}

CommPlan::CommPlan(const Comm& comm, std::span<const int> rank, std::span<const int> index)
    : CommPlan(comm, rank, index, 0) {
  comm_.alltoall(sendCount_, recvCount_);
  finish();
}

CommPlan CommPlan::withNeighbours(const Comm& comm, std::span<const int> rank,
                                  std::span<const int> index, std::span<const int> neighbours) {
  CommPlan p;
  p.rebuild(comm, rank, index, neighbours);
  return p;
}

void CommPlan::rebuild(const Comm& comm, std::span<const int> rank, std::span<const int> index,
                       std::span<const int> neighbours) {
  comm_ = comm;
  me_ = comm.rank();
  group(rank, index);
  neighbourCounts(neighbours);
  finish();
}

void CommPlan::rebuildFromCounts(const Comm& comm, std::span<const int> sendCounts,
                                 std::span<const int> neighbours) {
  comm_ = comm;
  me_ = comm.rank();
  const auto size = static_cast<std::size_t>(comm.size());
  if (sendCounts.size() != size) throw Error("CommPlan::rebuildFromCounts: one count per rank");
  sendCount_.assign(sendCounts.begin(), sendCounts.end());
  long long n = 0;
  for (int c : sendCount_) n += c;
  exportIndex_.resize(static_cast<std::size_t>(n));
  for (std::size_t k = 0; k < exportIndex_.size(); ++k) exportIndex_[k] = static_cast<int>(k);
  neighbourCounts(neighbours);
  finish();
}

void CommPlan::neighbourCounts(std::span<const int> neighbours) {
  const int size = comm_.size();
  recvCount_.assign(static_cast<std::size_t>(size), 0);
  peers_.assign(neighbours.begin(), neighbours.end());
  std::sort(peers_.begin(), peers_.end());
  peers_.erase(std::unique(peers_.begin(), peers_.end()), peers_.end());
  for (int r = 0; r < size; ++r) {
    const bool listed = std::binary_search(peers_.begin(), peers_.end(), r);
    if (!listed && sendCount_[static_cast<std::size_t>(r)] > 0)
      throw Error(fmt::format("CommPlan: rows for rank {}, not a neighbour", r));
  }
  requests_.clear();
  requests_.reserve(2 * peers_.size());
  for (int r : peers_) {
    if (r == me_) {
      recvCount_[static_cast<std::size_t>(r)] = sendCount_[static_cast<std::size_t>(r)];
      continue;
    }
    requests_.push_back(
        comm_.irecv(std::span<int>(&recvCount_[static_cast<std::size_t>(r)], 1), r, kTagCounts));
  }
  for (int r : peers_)
    if (r != me_)
      requests_.push_back(comm_.isend(
          std::span<const int>(&sendCount_[static_cast<std::size_t>(r)], 1), r, kTagCounts));
  Comm::waitAll(requests_);
}

CommPlan CommPlan::fromDestinations(const Comm& comm, std::span<const int> dest) {
  return CommPlan(comm, dest, {});
}

CommPlan CommPlan::fromCounts(const Comm& comm, std::vector<int> sendCounts,
                              std::vector<int> recvCounts) {
  const auto size = static_cast<std::size_t>(comm.size());
  if (sendCounts.size() != size || recvCounts.size() != size)
    throw Error("CommPlan::fromCounts: one count per rank expected");
  CommPlan p;
  p.comm_ = comm;
  p.me_ = comm.rank();
  p.sendCount_ = std::move(sendCounts);
  p.recvCount_ = std::move(recvCounts);
  long long n = 0;
  for (int c : p.sendCount_) n += c;
  p.exportIndex_.resize(static_cast<std::size_t>(n));
  for (std::size_t k = 0; k < p.exportIndex_.size(); ++k) p.exportIndex_[k] = static_cast<int>(k);
  p.finish();
  return p;
}

void CommPlan::finish() {
  const auto size = sendCount_.size();
  sendOffset_.assign(size + 1, 0);
  recvOffset_.assign(size + 1, 0);
  sendPeers_.clear();
  recvPeers_.clear();
  for (std::size_t r = 0; r < size; ++r) {
    sendOffset_[r + 1] = sendOffset_[r] + sendCount_[r];
    recvOffset_[r + 1] = recvOffset_[r] + recvCount_[r];
    if (static_cast<int>(r) == me_) continue;
    if (sendCount_[r] > 0) sendPeers_.push_back(static_cast<int>(r));
    if (recvCount_[r] > 0) recvPeers_.push_back(static_cast<int>(r));
  }
  requests_.reserve(sendPeers_.size() + recvPeers_.size());
  sOff_.resize(size + 1);
  rOff_.resize(size + 1);
}

PlanTraffic CommPlan::exchange(const double* send, const std::vector<long long>& sOff,
                               const std::vector<int>& sPeers, double* recv,
                               const std::vector<long long>& rOff, const std::vector<int>& rPeers) {
  PlanTraffic t;
  requests_.clear();
  for (int r : rPeers) {
    const auto u = static_cast<std::size_t>(r);
    requests_.push_back(comm_.irecv(
        std::span<double>(recv + rOff[u], static_cast<std::size_t>(rOff[u + 1] - rOff[u])), r,
        kTagRows));
  }
  for (int r : sPeers) {
    const auto u = static_cast<std::size_t>(r);
    const auto len = static_cast<std::size_t>(sOff[u + 1] - sOff[u]);
    requests_.push_back(comm_.isend(std::span<const double>(send + sOff[u], len), r, kTagRows));
    t.remoteBytes += static_cast<long long>(len * sizeof(double));
    ++t.messages;
  }
  const auto m = static_cast<std::size_t>(me_);
  std::copy(send + sOff[m], send + sOff[m + 1], recv + rOff[m]);
  t.localBytes = (sOff[m + 1] - sOff[m]) * static_cast<long long>(sizeof(double));
  Comm::waitAll(requests_);
  return t;
}

std::span<double> CommPlan::packBuffer(int w) {
  const std::size_t len = exportIndex_.size() * static_cast<std::size_t>(w);
  if (sendBuf_.size() < len) sendBuf_.resize(len);
  return {sendBuf_.data(), len};
}

PlanTraffic CommPlan::forwardPacked(int w, std::span<double> dst) {
  if (dst.size() < importCount() * static_cast<std::size_t>(w))
    throw Error("CommPlan::forward: destination too small");
  for (std::size_t r = 0; r < sOff_.size(); ++r) {
    sOff_[r] = static_cast<long long>(sendOffset_[r]) * w;
    rOff_[r] = static_cast<long long>(recvOffset_[r]) * w;
  }
  return exchange(sendBuf_.data(), sOff_, sendPeers_, dst.data(), rOff_, recvPeers_);
}

PlanTraffic CommPlan::forward(std::span<const double> src, int w, std::span<double> dst) {
  const auto uw = static_cast<std::size_t>(w);
  const std::span<double> buf = packBuffer(w);
  for (std::size_t k = 0; k < exportIndex_.size(); ++k) {
    const double* row = src.data() + static_cast<std::size_t>(exportIndex_[k]) * uw;
    std::copy(row, row + uw, buf.data() + k * uw);
  }
  return forwardPacked(w, dst);
}

PlanTraffic CommPlan::reverseInExportOrder(std::span<const double> src, int w,
                                           std::span<double> dst) {
  if (src.size() < importCount() * static_cast<std::size_t>(w) ||
      dst.size() < exportIndex_.size() * static_cast<std::size_t>(w))
    throw Error("CommPlan::reverse: buffers too small");
  for (std::size_t r = 0; r < sOff_.size(); ++r) {
    sOff_[r] = static_cast<long long>(recvOffset_[r]) * w;
    rOff_[r] = static_cast<long long>(sendOffset_[r]) * w;
  }
  return exchange(src.data(), sOff_, recvPeers_, dst.data(), rOff_, sendPeers_);
}

PlanTraffic CommPlan::reverse(std::span<const double> src, int w, std::span<double> dst) {
  const auto uw = static_cast<std::size_t>(w);
  const std::size_t n = exportIndex_.size();
  if (recvBuf_.size() < n * uw) recvBuf_.resize(n * uw);
  const PlanTraffic t = reverseInExportOrder(src, w, {recvBuf_.data(), n * uw});
  for (std::size_t k = 0; k < n; ++k) {
    const double* row = recvBuf_.data() + k * uw;
    std::copy(row, row + uw, dst.data() + static_cast<std::size_t>(exportIndex_[k]) * uw);
  }
  return t;
}

PlanTraffic CommPlan::reverseSum(std::span<const double> src, int w, std::span<double> dst) {
  const auto uw = static_cast<std::size_t>(w);
  const std::size_t n = exportIndex_.size();
  if (recvBuf_.size() < n * uw) recvBuf_.resize(n * uw);
  const PlanTraffic t = reverseInExportOrder(src, w, {recvBuf_.data(), n * uw});
  for (std::size_t k = 0; k < n; ++k) {
    const double* row = recvBuf_.data() + k * uw;
    double* out = dst.data() + static_cast<std::size_t>(exportIndex_[k]) * uw;
    for (std::size_t c = 0; c < uw; ++c) out[c] += row[c];
  }
  return t;
}

PlanTraffic CommPlan::forwardVariable(std::span<const double> src,
                                      std::span<const long long> offset, std::vector<double>& dst,
                                      std::vector<long long>& dstOffset) {
  const std::size_t n = exportIndex_.size();
  // The lengths first, as one-double rows (exact below 2^53).
  std::vector<double> len(offset.size() > 0 ? offset.size() - 1 : 0);
  for (std::size_t i = 0; i < len.size(); ++i)
    len[i] = static_cast<double>(offset[i + 1] - offset[i]);
  std::vector<double> inLen(importCount());
  PlanTraffic t = forward(len, 1, inLen);
  dstOffset.assign(importCount() + 1, 0);
  for (std::size_t p = 0; p < inLen.size(); ++p)
    dstOffset[p + 1] = dstOffset[p] + static_cast<long long>(inLen[p]);
  // Payload offsets per rank, in doubles.
  std::vector<double> send;
  std::vector<long long> sOff(sendCount_.size() + 1, 0), rOff(sendCount_.size() + 1, 0);
  for (std::size_t r = 0; r < sendCount_.size(); ++r) {
    long long s = 0;
    for (int k = sendOffset_[r]; k < sendOffset_[r + 1]; ++k)
      s += static_cast<long long>(
          len[static_cast<std::size_t>(exportIndex_[static_cast<std::size_t>(k)])]);
    sOff[r + 1] = sOff[r] + s;
    rOff[r + 1] = dstOffset[static_cast<std::size_t>(recvOffset_[r + 1])];
  }
  send.reserve(static_cast<std::size_t>(sOff.back()));
  for (std::size_t k = 0; k < n; ++k) {
    const auto i = static_cast<std::size_t>(exportIndex_[k]);
    send.insert(send.end(), src.begin() + offset[i], src.begin() + offset[i + 1]);
  }
  dst.resize(static_cast<std::size_t>(dstOffset.back()));
  const PlanTraffic p = exchange(send.data(), sOff, sendPeers_, dst.data(), rOff, recvPeers_);
  t.remoteBytes += p.remoteBytes;
  t.localBytes += p.localBytes;
  t.messages += p.messages;
  return t;
}

}  // namespace coloc
