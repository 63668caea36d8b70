// The agreement at the end of each phase of `coloc run` (run.cpp): what failed, on which rank,
// with which exit status (run.hpp), agreed by every rank (coloc/core/failure.hpp).
#pragma once

#include <new>
#include <string>

#include "coloc/core/comm.hpp"
#include "coloc/core/error.hpp"
#include "coloc/core/failure.hpp"
#include "run.hpp"
#include "stop_signals.hpp"

namespace coloc {

/// The start of the message of an allocation failure (report.json: out_of_memory).
inline constexpr const char* kOutOfMemory = "out of memory";

inline bool outOfMemory(const std::string& message) {
  return message.find(kOutOfMemory) != std::string::npos;
}

/// Runs `f` on every rank and agrees on the outcome at its end (coloc/core/failure.hpp): the
/// exit status by the error's type (IoError: kIoErrorStatus, other coloc::Error: `errorCode`,
/// anything else: kRunFailedStatus), the message of the lowest failing rank, and `where`, a
/// number the caller gives the part of the phase that was running (set through the pointer),
/// and `request`, a flag any rank may raise for the verdict (read after `f`; progress.hpp).
template <class F>
FailureChannel::Verdict phase(const FailureChannel& channel, int errorCode, F&& f,
                              int* where = nullptr, const int* request = nullptr) {
  std::string err;
  int code = 0;
  try {
    f();
  } catch (const IoError& e) {
    err = e.what();
    code = kIoErrorStatus;
  } catch (const Error& e) {
    err = e.what();
    code = errorCode;
  } catch (const std::bad_alloc& e) {
    err = std::string(kOutOfMemory) + " (" + e.what() +
          "): an allocation failed; the memory estimate (coloc check) did not foresee it";
    code = kRunFailedStatus;
  } catch (const std::exception& e) {
    err = std::string("unexpected exception: ") + e.what();
    code = kRunFailedStatus;
  }
  return channel.agree(err, code, stopSignal(), where ? *where : 0, request ? *request : 0);
}

/// Runs `f` on rank 0 only and throws its coloc::Error (an IoError as one) on every rank, so
/// that a check only rank 0 makes (the output folder, its lock) is reported like an input error
/// every rank found, without a "rank 0:" prefix. Collective.
template <class F>
void onRoot(const Comm& world, F&& f) {
  std::string err;
  if (world.isRoot()) {
    try {
      f();
    } catch (const IoError& e) {
      err = std::string("I") + e.what();
    } catch (const std::exception& e) {  // a coloc::Error, or std::filesystem's
      err = std::string("E") + e.what();
    }
  }
  err = world.broadcast(err);
  if (err.empty()) return;
  if (err[0] == 'I') throw IoError(err.substr(1));
  throw Error(err.substr(1));
}

}  // namespace coloc
