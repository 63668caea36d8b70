// coloc/core/failure.hpp — what happens when a rank fails and the others do not know it.
//
// Errors that every rank sees together (a bad case file, a check made through
// Comm::raiseIfAny) end the run cleanly on every rank. A rank that fails alone is the hard case:
// the others may be waiting for it inside a collective (hypre, HDF5, MPI-IO) that it will never
// enter. coloc handles it in two layers:
//
//  1. Agreement at phase boundaries. The driver wraps each collective phase (set-up, each step,
//     the output, the checkpoint, the report) and ends it with FailureChannel::agree(): one
//     small allreduce on a duplicate communicator that nothing else uses, so a rank that failed
//     alone and waits there cannot be matched with a solver's collective. If the other ranks
//     reach the boundary, every rank learns the failure (code and message) and the run ends
//     through its normal failure path (report, files, exit status).
//  2. A deadline. A rank that failed alone arms a watchdog (noteLocalFailure): if no agreement
//     has shared the failure within failureWait() seconds (case key run.failure_wait_s), the
//     rank prints its message once and ends every rank with MPI_Abort(code). So nothing hangs,
//     even when the others are stuck in a collective of a library.
//
// Exit codes of the driver: bench/driver/run.hpp (docs/robustness.md).
#pragma once

#include <mpi.h>

#include <string>

#include "coloc/core/comm.hpp"

namespace coloc {

/// Seconds a rank that failed alone waits for the others to learn of it (default 10).
void setFailureWait(double seconds);
double failureWait();

/// This rank failed and the others may not know: arm the deadline. Cleared by failureShared().
void noteLocalFailure(const std::string& message, int exitCode);
/// A collective agreement showed the failure to every rank of the communicator: disarm.
void failureShared();
/// A half-written file that a deadline stop (layer 2) removes before it ends the rank: a stop
/// must not leave a partial file behind (the next run would find it). Returns an id for
/// forgetOnAbort, which the writer calls once the file is published or removed.
long long removeOnAbort(const std::string& path);
void forgetOnAbort(long long id);
/// The last coloc::Error made on this rank (for a deadline that fires while one is unwinding).
void rememberError(const char* what);

/// RAII: a collective call made on an error path (closing a half-written parallel file to
/// discard it). If it has not returned within failureWait() seconds, the rank prints the last
/// error and `what` and ends every rank. Cheap: no thread runs until a deadline is armed.
class FailureDeadline {
 public:
  FailureDeadline(const std::string& what, int exitCode);
  ~FailureDeadline();
  FailureDeadline(const FailureDeadline&) = delete;
  FailureDeadline& operator=(const FailureDeadline&) = delete;

 private:
  long long id_;
};

/// A duplicate of a communicator reserved for agreeing on failures (layer 1 above).
class FailureChannel {
 public:
  /// Collective over `comm` (MPI_Comm_dup).
  explicit FailureChannel(const Comm& comm);
  ~FailureChannel();
  FailureChannel(const FailureChannel&) = delete;
  FailureChannel& operator=(const FailureChannel&) = delete;

  struct Verdict {
    int code = 0;     // exit code of the lowest failing rank (0: no rank failed)
    int rank = -1;    // that rank
    int failing = 0;  // how many ranks failed
    int signal = 0;   // the largest stop signal any rank has received (0: none)
    int where = 0;    // the caller's label of the part that failed, from the lowest failing rank
    int request = 0;  // the largest request any rank passed (0: none)
    std::string message;  // its message; "rank R: " before it unless every rank failed
    bool failed() const { return code != 0; }
  };
  /// Collective: every rank passes its own failure ("" and 0 when it has none), the stop
  /// signal it has seen and a label of where it failed. A failing rank arms the deadline first;
  /// the verdict disarms it. `request` (>= 0) rides on the same allreduce: a flag one rank
  /// raises for all (the driver's "progress line on the next step", decided by rank 0's clock);
  /// the verdict carries the largest over the ranks, at no extra cost.
  Verdict agree(const std::string& error, int code, int signal = 0, int where = 0,
                int request = 0) const;
  const Comm& comm() const { return comm_; }

 private:
  Comm comm_;
};

}  // namespace coloc
