// Rank 0's messages, on the terminal and in OUT/log.txt (run_log.hpp).
#include "run_log.hpp"

#include <cerrno>
#include <cstdarg>
#include <cstring>

#include "coloc/core/error.hpp"

namespace coloc {

RunLog::RunLog(bool root) : root_(root), text_(root ? 4096 : 0) {}

RunLog::~RunLog() {
  if (file_) std::fclose(file_);
}

void RunLog::open(const std::string& path, bool append) {
  if (!root_) return;
  if (file_) std::fclose(file_);
  file_ = std::fopen(path.c_str(), append ? "ae" : "we");
  if (!file_) throw IoError("cannot create the log file '" + path + "': " + std::strerror(errno));
  if (append) std::fputs("coloc: ---- the run continues (--restart) ----\n", file_);
  std::fwrite(pending_.data(), 1, pending_.size(), file_);
  std::fflush(file_);
  pending_.clear();
  pending_.shrink_to_fit();
}

void RunLog::out(const char* format, ...) {
  va_list args;
  va_start(args, format);
  write(stdout, format, args);
  va_end(args);
}

void RunLog::err(const char* format, ...) {
  va_list args;
  va_start(args, format);
  write(stderr, format, args);
  va_end(args);
}

void RunLog::file(const char* format, ...) {
  va_list args;
  va_start(args, format);
  write(nullptr, format, args);
  va_end(args);
}

void RunLog::write(std::FILE* stream, const char* format, va_list args) {
  if (!root_) return;
  va_list again;
  va_copy(again, args);
  const int n = std::vsnprintf(text_.data(), text_.size(), format, args);
  if (n < 0) {
    va_end(again);
    return;
  }
  if (static_cast<std::size_t>(n) >= text_.size()) {  // a long message (rare, not the loop's)
    text_.resize(static_cast<std::size_t>(n) + 1);
    std::vsnprintf(text_.data(), text_.size(), format, again);
  }
  va_end(again);
  const std::size_t len = static_cast<std::size_t>(n);
  if (stream) {
    if (stream == stderr) std::fflush(stdout);  // in order on a terminal that shows both
    std::fwrite(text_.data(), 1, len, stream);
    std::fflush(stream);
  }
  if (file_) {
    std::fwrite(text_.data(), 1, len, file_);
    std::fflush(file_);
  } else {
    pending_.append(text_.data(), len);
  }
}

}  // namespace coloc
