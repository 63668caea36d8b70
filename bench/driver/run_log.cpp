// Rank 0's messages, on the terminal and in OUT/log.txt (run_log.hpp).
#include "run_log.hpp"

#include <cerrno>
#include <cstring>

#include "coloc/core/error.hpp"

namespace coloc {

RunLog::RunLog(bool root) : root_(root) {
  if (root_) text_.reserve(4096);
}

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

void RunLog::reopen(const std::string& path) {
  if (!root_) return;
  if (file_) std::fclose(file_);
  file_ = std::fopen(path.c_str(), "ae");
  if (!file_) throw IoError("cannot open the log file '" + path + "': " + std::strerror(errno));
  std::fwrite(pending_.data(), 1, pending_.size(), file_);
  std::fflush(file_);
  pending_.clear();
}

void RunLog::write(std::FILE* stream, fmt::string_view format, fmt::format_args args) {
  if (!root_) return;
  text_.clear();  // keeps its capacity
  fmt::vformat_to(std::back_inserter(text_), format, args);
  if (stream) {
    if (stream == stderr) std::fflush(stdout);  // in order on a terminal that shows both
    std::fwrite(text_.data(), 1, text_.size(), stream);
    std::fflush(stream);
  }
  if (file_) {
    std::fwrite(text_.data(), 1, text_.size(), file_);
    std::fflush(file_);
  } else {
    pending_.append(text_.data(), text_.size());
  }
}

}  // namespace coloc
