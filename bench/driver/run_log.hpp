// What rank 0 of a `coloc run` says, on the terminal and in the run's log file (OUT/log.txt):
// every line it prints, progress lines, notes, warnings and errors included.
#pragma once

#include <cstdarg>
#include <cstdio>
#include <string>
#include <vector>

namespace coloc {

/// Rank 0's messages: each goes to stdout or stderr as before and, once open(), to the log file
/// too (lines from before open() are kept and written first). The other ranks print nothing.
/// A log file that cannot be written loses lines, not the run: the terminal has them all.
class RunLog {
 public:
  explicit RunLog(bool root);
  ~RunLog();
  RunLog(const RunLog&) = delete;
  RunLog& operator=(const RunLog&) = delete;

  /// Rank 0: opens `path` (new, or appended to when `append`: a restart continuing its run in
  /// the same folder). Throws IoError when it cannot be created.
  void open(const std::string& path, bool append);
  /// printf to stdout and the log.
  void out(const char* format, ...) __attribute__((format(printf, 2, 3)));
  /// printf to stderr and the log.
  void err(const char* format, ...) __attribute__((format(printf, 2, 3)));
  /// printf to the log only (what --quiet keeps off the terminal).
  void file(const char* format, ...) __attribute__((format(printf, 2, 3)));
  bool root() const { return root_; }

 private:
  void write(std::FILE* stream, const char* format, va_list args);  // stream null: log only
  bool root_;
  std::FILE* file_ = nullptr;
  std::string pending_;     // lines before open()
  std::vector<char> text_;  // the formatted line (kept: no allocation in the time loop)
};

}  // namespace coloc
