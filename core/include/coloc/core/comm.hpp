// coloc/core/comm.hpp — all MPI of the project goes through this small module.
//
// Comm wraps a communicator (world, or a Cartesian one made by partition/) with the few
// collectives the solvers need, typed non-blocking point-to-point, and the collective error
// path raiseIfAny(). Nothing else in coloc includes <mpi.h> except partition's halo plan and
// hypre glue, which take the raw handle from Comm::raw().
#pragma once

#include <mpi.h>

#include <array>
#include <cstdint>
#include <span>
#include <string>
#include <vector>

namespace coloc {

/// RAII for MPI_Init/MPI_Finalize (and HYPRE_Init/Finalize via the fv library's own guard).
class MpiSession {
 public:
  MpiSession(int* argc, char*** argv);
  ~MpiSession();
  MpiSession(const MpiSession&) = delete;
  MpiSession& operator=(const MpiSession&) = delete;
};

/// The first line of MPI_Get_library_version, trailing blanks removed (callable before MPI_Init).
std::string mpiLibraryVersion();

/// True under SimGrid's SMPI (a simulated cluster, docs/smpi.md): every rank is a thread of one
/// process and time is simulated (wall-clock deadlines mean nothing there). Needs MPI_Init.
bool mpiIsSimulated();

template <class T>
MPI_Datatype mpiType();
template <>
inline MPI_Datatype mpiType<double>() {
  return MPI_DOUBLE;
}
template <>
inline MPI_Datatype mpiType<float>() {
  return MPI_FLOAT;
}
template <>
inline MPI_Datatype mpiType<int>() {
  return MPI_INT;
}
template <>
inline MPI_Datatype mpiType<long long>() {
  return MPI_LONG_LONG;
}
template <>
inline MPI_Datatype mpiType<unsigned long long>() {
  return MPI_UNSIGNED_LONG_LONG;
}
template <>
inline MPI_Datatype mpiType<long>() {
  return MPI_LONG;
}
template <>
inline MPI_Datatype mpiType<unsigned long>() {
  return MPI_UNSIGNED_LONG;
}
template <>
inline MPI_Datatype mpiType<char>() {
  return MPI_CHAR;
}
template <>
inline MPI_Datatype mpiType<std::uint8_t>() {
  return MPI_UINT8_T;
}

struct MinMaxAvg {
  double min = 0, max = 0, avg = 0, sum = 0;
};

class Comm {
 public:
  Comm() : comm_(MPI_COMM_WORLD) {}
  explicit Comm(MPI_Comm c) : comm_(c) {}
  static Comm world() { return Comm(MPI_COMM_WORLD); }

  int rank() const;
  int size() const;
  MPI_Comm raw() const { return comm_; }
  bool isRoot() const { return rank() == 0; }

  void barrier() const;
  double wtime() const { return MPI_Wtime(); }

  template <class T>
  T sum(T v) const {
    return allreduce(v, MPI_SUM);
  }
  template <class T>
  T max(T v) const {
    return allreduce(v, MPI_MAX);
  }
  template <class T>
  T min(T v) const {
    return allreduce(v, MPI_MIN);
  }
  // An empty span reduces nothing and calls no collective (every rank passes the same length,
  // so every rank skips it): SimGrid 3.32's Open MPI collectives divide by the count and raise
  // SIGFPE on a zero-count allreduce (a fluid-only run's empty series row did).
  template <class T>
  void sumInPlace(std::span<T> v) const {
    if (v.empty()) return;
    MPI_Allreduce(MPI_IN_PLACE, v.data(), static_cast<int>(v.size()), mpiType<T>(), MPI_SUM, comm_);
  }
  template <class T>
  void maxInPlace(std::span<T> v) const {
    if (v.empty()) return;
    MPI_Allreduce(MPI_IN_PLACE, v.data(), static_cast<int>(v.size()), mpiType<T>(), MPI_MAX, comm_);
  }
  MinMaxAvg minMaxAvg(double v) const;
  template <class T>
  std::vector<T> allgather(T v) const {
    std::vector<T> out(static_cast<std::size_t>(size()));
    MPI_Allgather(&v, 1, mpiType<T>(), out.data(), 1, mpiType<T>(), comm_);
    return out;
  }

  /// Broadcast a string from `root` (used for the case file text: one reader, same text
  /// everywhere).
  std::string broadcast(std::string s, int root = 0) const;
  template <class T>
  void broadcast(std::span<T> v, int root = 0) const {
    MPI_Bcast(v.data(), static_cast<int>(v.size()), mpiType<T>(), root, comm_);
  }

  /// Collective error path: every rank calls it; if any rank passes a non-empty message, every
  /// rank throws coloc::Error with the message of the lowest failing rank (prefixed by its rank).
  void raiseIfAny(const std::string& localError) const;
  /// The same agreement, returned: "" when no rank failed, else the message raiseIfAny would
  /// throw (for callers that throw another Error type). `exitCode`: what the deadline of a rank
  /// that failed alone ends the run with (coloc/core/failure.hpp).
  std::string firstError(const std::string& localError, int exitCode = 3) const;

  template <class T>
  MPI_Request isend(std::span<const T> buf, int dest, int tag) const {
    MPI_Request r;
    MPI_Isend(buf.data(), static_cast<int>(buf.size()), mpiType<T>(), dest, tag, comm_, &r);
    return r;
  }
  template <class T>
  MPI_Request irecv(std::span<T> buf, int src, int tag) const {
    MPI_Request r;
    MPI_Irecv(buf.data(), static_cast<int>(buf.size()), mpiType<T>(), src, tag, comm_, &r);
    return r;
  }
  static void waitAll(std::span<MPI_Request> reqs);

  /// All-to-all of one count per rank (counts.size() == size()).
  void alltoall(const std::vector<int>& sendCounts, std::vector<int>& recvCounts) const;
  /// All-to-all of variable blocks: sendCounts[r] values starting at sendDispl[r] go to rank r;
  /// the block from rank r lands at recvDispl[r] (counts from alltoall(), displacements from
  /// displacements()). The caller owns every buffer, so nothing is allocated here.
  template <class T>
  void alltoallv(std::span<const T> send, const std::vector<int>& sendCounts,
                 const std::vector<int>& sendDispl, std::span<T> recv,
                 const std::vector<int>& recvCounts, const std::vector<int>& recvDispl) const {
    MPI_Alltoallv(send.data(), sendCounts.data(), sendDispl.data(), mpiType<T>(), recv.data(),
                  recvCounts.data(), recvDispl.data(), mpiType<T>(), comm_);
  }
  /// Exclusive prefix sum of counts into displ (resized to counts.size()); returns the total.
  static int displacements(const std::vector<int>& counts, std::vector<int>& displ);

  /// Exchange counts with a peer (returns the count received); used to size variable messages.
  int exchangeCount(int sendCount, int dest, int src, int tag) const;

 private:
  template <class T>
  T allreduce(T v, MPI_Op op) const {
    T out{};
    MPI_Allreduce(&v, &out, 1, mpiType<T>(), op, comm_);
    return out;
  }
  MPI_Comm comm_;
};

/// Ends every rank at once; for failures that cannot be made collective (last resort).
[[noreturn]] void abortAll(const std::string& message, int code = 3);

}  // namespace coloc
