#include "coloc/core/comm.hpp"

#include <fmt/format.h>

#include <cstdio>

#include "coloc/core/error.hpp"
#include "coloc/core/failure.hpp"

namespace coloc {

std::string mpiLibraryVersion() {
  char version[MPI_MAX_LIBRARY_VERSION_STRING] = {};
  int len = 0;
  MPI_Get_library_version(version, &len);
  std::string text(version, static_cast<std::size_t>(len > 0 ? len : 0));
  if (const auto nl = text.find('\n'); nl != std::string::npos) text.resize(nl);
  while (!text.empty() && (text.back() == '\0' || text.back() == ' ' || text.back() == '\r'))
    text.pop_back();
  return text;
}

bool mpiIsSimulated() {
  return mpiLibraryVersion().starts_with("SMPI");
}

MpiSession::MpiSession(int* argc, char*** argv) {
  int initialised = 0;
  MPI_Initialized(&initialised);
  if (!initialised) MPI_Init(argc, argv);
}

MpiSession::~MpiSession() {
  int finalised = 0;
  MPI_Finalized(&finalised);
  if (!finalised) MPI_Finalize();
}

int Comm::rank() const {
  int r = 0;
  MPI_Comm_rank(comm_, &r);
  return r;
}

int Comm::size() const {
  int s = 1;
  MPI_Comm_size(comm_, &s);
  return s;
}

void Comm::barrier() const {
  MPI_Barrier(comm_);
}

MinMaxAvg Comm::minMaxAvg(double v) const {
  double in[2] = {v, -v}, out[2];
  MPI_Allreduce(in, out, 2, MPI_DOUBLE, MPI_MAX, comm_);
  MinMaxAvg r;
  r.max = out[0];
  r.min = -out[1];
  r.sum = sum(v);
  r.avg = r.sum / size();
  return r;
}

std::string Comm::broadcast(std::string s, int root) const {
  long long n = static_cast<long long>(s.size());
  MPI_Bcast(&n, 1, MPI_LONG_LONG, root, comm_);
  s.resize(static_cast<std::size_t>(n));
  if (n > 0) MPI_Bcast(s.data(), static_cast<int>(n), MPI_CHAR, root, comm_);
  return s;
}

std::string Comm::firstError(const std::string& localError, int exitCode) const {
  const int me = rank();
  // A rank that failed arms the deadline (coloc/core/failure.hpp) before it waits for the
  // others here: if they never come (stuck in another collective), it ends every rank.
  if (!localError.empty()) noteLocalFailure(localError, exitCode);
  const int failing = localError.empty() ? size() : me;
  const int first = min(failing);
  if (first == size()) return {};
  std::string msg = broadcast(first == me ? localError : std::string(), first);
  failureShared();
  if (size() > 1) msg = fmt::format("rank {}: {}", first, msg);
  return msg;
}

void Comm::raiseIfAny(const std::string& localError) const {
  std::string msg = firstError(localError);
  if (!msg.empty()) throw Error(msg);
}

void Comm::alltoall(const std::vector<int>& sendCounts, std::vector<int>& recvCounts) const {
  recvCounts.resize(sendCounts.size());
  MPI_Alltoall(sendCounts.data(), 1, MPI_INT, recvCounts.data(), 1, MPI_INT, comm_);
}

int Comm::displacements(const std::vector<int>& counts, std::vector<int>& displ) {
  displ.resize(counts.size());
  int total = 0;
  for (std::size_t r = 0; r < counts.size(); ++r) {
    displ[r] = total;
    total += counts[r];
  }
  return total;
}

void Comm::waitAll(std::span<MPI_Request> reqs) {
  MPI_Waitall(static_cast<int>(reqs.size()), reqs.data(), MPI_STATUSES_IGNORE);
}

int Comm::exchangeCount(int sendCount, int dest, int src, int tag) const {
  int recvCount = 0;
  MPI_Sendrecv(&sendCount, 1, MPI_INT, dest, tag, &recvCount, 1, MPI_INT, src, tag, comm_,
               MPI_STATUS_IGNORE);
  return src == MPI_PROC_NULL ? 0 : recvCount;
}

void abortAll(const std::string& message, int code) {
  int rank = 0;
  MPI_Comm_rank(MPI_COMM_WORLD, &rank);
  std::fprintf(stderr, "coloc: fatal (rank %d): %s\n", rank, message.c_str());
  std::fflush(stderr);
  MPI_Abort(MPI_COMM_WORLD, code);
  std::abort();
}

}  // namespace coloc
