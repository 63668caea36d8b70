#include "coloc/core/failure.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <chrono>
#include <condition_variable>
#include <cstdio>
#include <cstdlib>
#include <map>
#include <mutex>
#include <thread>

namespace coloc {
namespace {

using Clock = std::chrono::steady_clock;

/// The watchdog: armed deadlines, and one thread (started at the first arming) that ends every
/// rank when the earliest passes. Process-wide like MPI itself; never destroyed (the thread may
/// still wait on it while the process exits).
struct Watch {
  std::mutex m;
  std::condition_variable cv;
  struct Entry {
    Clock::time_point deadline;
    std::string message;
    int code = 3;
  };
  std::map<long long, Entry> armed;  // id -> entry; id 0 is the local failure
  long long next = 1;
  double wait = 10.0;
  std::string lastError;
  std::map<long long, std::string> doomed;  // removeOnAbort: id -> path
  long long nextDoomed = 1;
  bool started = false;

  void ensureThread() {  // with m held
    if (started) return;
    started = true;
    // Under SimGrid SMPI the ranks are threads of one process on simulated time: a wall-clock
    // deadline would fire while the other ranks are merely being simulated, and an MPI call
    // from a thread that is not a simulated rank is not allowed. SimGrid itself stops a
    // simulation in which every rank waits (a deadlock).
    if (mpiIsSimulated()) return;
    std::thread([this] { run(); }).detach();
  }
  void run() {
    std::unique_lock<std::mutex> lock(m);
    while (true) {
      if (armed.empty()) {
        cv.wait(lock);
        continue;
      }
      auto first = armed.begin();
      for (auto it = armed.begin(); it != armed.end(); ++it)
        if (it->second.deadline < first->second.deadline) first = it;
      const Clock::time_point when = first->second.deadline;
      if (Clock::now() < when) {
        cv.wait_until(lock, when);
        continue;
      }
      // A local failure is the cause; else say what did not return, after the last error.
      const auto local = armed.find(0);
      std::string msg;
      int code = first->second.code;
      if (local != armed.end()) {
        msg = local->second.message;
        code = local->second.code;
      } else {
        msg = (lastError.empty() ? std::string() : lastError + "; then ") + first->second.message;
      }
      int rank = 0, size = 1;
      MPI_Comm_rank(MPI_COMM_WORLD, &rank);
      MPI_Comm_size(MPI_COMM_WORLD, &size);
      const std::string who = size > 1 ? fmt::format("rank {}: ", rank) : "";
      std::fprintf(stderr,
                   "coloc: error: %s%s (the other ranks did not join the error check within "
                   "%g s: stopping every rank)\n",
                   who.c_str(), msg.c_str(), wait);
      std::fflush(stderr);
      for (const auto& entry : doomed) std::remove(entry.second.c_str());
      MPI_Abort(MPI_COMM_WORLD, code);
      std::_Exit(code);
    }
  }
};

Watch& watch() {
  static Watch* w = new Watch;  // intentionally never freed (see Watch)
  return *w;
}

/// Rank 0's deadline passes first, the others' a second later: when several ranks are stuck,
/// rank 0 prints and its MPI_Abort ends the others before they print too.
Clock::time_point deadlineFromNow(double seconds) {
  int rank = 0, ready = 0;
  MPI_Initialized(&ready);
  if (ready) MPI_Comm_rank(MPI_COMM_WORLD, &rank);
  if (rank > 0) seconds += 1.0;
  // Bounded to what the clock can hold from now (the key's range is far below; a library
  // caller may pass anything): a deadline past the clock's end would wrap into the past.
  const Clock::time_point now = Clock::now();
  const double room = 0.5 * std::chrono::duration<double>(Clock::time_point::max() - now).count();
  if (!(seconds > 0)) seconds = 0;  // NaN too
  seconds = std::min({seconds, room, 1e9});
  return now + std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(seconds));
}

}  // namespace

long long removeOnAbort(const std::string& path) {
  Watch& w = watch();
  std::lock_guard<std::mutex> lock(w.m);
  const long long id = w.nextDoomed++;
  w.doomed[id] = path;
  return id;
}

void forgetOnAbort(long long id) {
  if (id <= 0) return;
  Watch& w = watch();
  std::lock_guard<std::mutex> lock(w.m);
  w.doomed.erase(id);
}

void setFailureWait(double seconds) {
  Watch& w = watch();
  std::lock_guard<std::mutex> lock(w.m);
  w.wait = seconds;
}

double failureWait() {
  Watch& w = watch();
  std::lock_guard<std::mutex> lock(w.m);
  return w.wait;
}

void noteLocalFailure(const std::string& message, int exitCode) {
  Watch& w = watch();
  std::lock_guard<std::mutex> lock(w.m);
  if (w.armed.count(0)) return;  // the first failure is the cause
  w.armed[0] = {deadlineFromNow(w.wait), message, exitCode};
  w.ensureThread();
  w.cv.notify_all();
}

void failureShared() {
  Watch& w = watch();
  std::lock_guard<std::mutex> lock(w.m);
  w.armed.erase(0);
  w.cv.notify_all();
}

void rememberError(const char* what) {
  Watch& w = watch();
  std::lock_guard<std::mutex> lock(w.m);
  w.lastError = what ? what : "";
}

FailureDeadline::FailureDeadline(const std::string& what, int exitCode) {
  Watch& w = watch();
  std::lock_guard<std::mutex> lock(w.m);
  id_ = w.next++;
  w.armed[id_] = {deadlineFromNow(w.wait), what, exitCode};
  w.ensureThread();
  w.cv.notify_all();
}

FailureDeadline::~FailureDeadline() {
  Watch& w = watch();
  std::lock_guard<std::mutex> lock(w.m);
  w.armed.erase(id_);
  w.cv.notify_all();
}

FailureChannel::FailureChannel(const Comm& comm) {
  MPI_Comm dup = MPI_COMM_NULL;
  MPI_Comm_dup(comm.raw(), &dup);
  comm_ = Comm(dup);
}

FailureChannel::~FailureChannel() {
  int finalized = 0;
  MPI_Finalized(&finalized);
  MPI_Comm c = comm_.raw();
  if (!finalized && c != MPI_COMM_NULL) MPI_Comm_free(&c);
}

FailureChannel::Verdict FailureChannel::agree(const std::string& error, int code, int signal,
                                              int where, int request) const {
  const int me = comm_.rank(), size = comm_.size();
  const bool mine = !error.empty() || code != 0;
  if (mine) noteLocalFailure(error.empty() ? "failed" : error, code != 0 ? code : 3);
  // One allreduce in the common case: the lowest failing rank, the largest signal and request.
  int in[3] = {mine ? me : size, -signal, -request}, out[3] = {size, 0, 0};
  MPI_Allreduce(in, out, 3, MPI_INT, MPI_MIN, comm_.raw());
  Verdict v;
  v.signal = -out[1];
  v.request = -out[2];
  if (out[0] == size) return v;
  v.rank = out[0];
  v.failing = comm_.sum(mine ? 1 : 0);
  int c[2] = {code != 0 ? code : 3, where};
  MPI_Bcast(c, 2, MPI_INT, v.rank, comm_.raw());
  v.code = c[0];
  v.where = c[1];
  v.message = comm_.broadcast(v.rank == me ? error : std::string(), v.rank);
  if (v.failing < size && size > 1) v.message = fmt::format("rank {}: {}", v.rank, v.message);
  failureShared();
  return v;
}

}  // namespace coloc
