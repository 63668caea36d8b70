// What rank 0 of a `coloc run` says, on the terminal and in the run's log file (OUT/log.txt):
// every line it prints, progress rows, notes, warnings and errors included.
#pragma once

#include <fmt/format.h>

#include <cstdio>
#include <string>
#include <utility>

#include "coloc/core/config.hpp"

namespace coloc {

/// The first lines of a run's log (OUT/log.txt), from report.json's provenance: version and
/// commit, the command, date and host, ranks and nodes, the MPI environment that changes timings
/// (binding, yield), the build and the libraries; then the case and the output folder. Each line
/// starts with "coloc: ".
std::string logHeader(const Json& provenance, const std::string& casePath,
                      const std::string& outDir);

/// Rank 0's messages: each goes to stdout or stderr as before and, once open(), to the log file
/// too (lines from before open() are kept and written first). The other ranks print nothing.
/// A log file that cannot be written loses lines, not the run: the terminal has them all.
/// The messages are {fmt} format strings, checked at compile time ("{}", "{:.6g}", ...).
class RunLog {
 public:
  explicit RunLog(bool root);
  ~RunLog();
  RunLog(const RunLog&) = delete;
  RunLog& operator=(const RunLog&) = delete;

  /// Rank 0: opens `path` (new, or appended to when `append`: a restart continuing its run in
  /// the same folder), writes `header` (logHeader(); the log only, --quiet or not), then the
  /// lines from before. Throws IoError when it cannot be created.
  void open(const std::string& path, bool append, const std::string& header = "");
  /// Rank 0: appends to a log a run has closed, without the restart's mark (the snapshot that
  /// main() draws after MPI_Finalize: snapshot.hpp). Throws IoError when it cannot be opened.
  void reopen(const std::string& path);
  /// To stdout and the log.
  template <class... T>
  void out(fmt::format_string<T...> format, T&&... args) {
    if (root_) write(stdout, format, fmt::make_format_args(args...));
  }
  /// To stderr and the log.
  template <class... T>
  void err(fmt::format_string<T...> format, T&&... args) {
    if (root_) write(stderr, format, fmt::make_format_args(args...));
  }
  /// To the log only (what --quiet keeps off the terminal).
  template <class... T>
  void file(fmt::format_string<T...> format, T&&... args) {
    if (root_) write(nullptr, format, fmt::make_format_args(args...));
  }
  bool root() const { return root_; }

 private:
  void write(std::FILE* stream, fmt::string_view format, fmt::format_args args);  // null: log only
  bool root_;
  std::FILE* file_ = nullptr;
  std::string pending_;      // lines before open()
  fmt::memory_buffer text_;  // the formatted line (kept: no allocation in the time loop)
};

}  // namespace coloc
