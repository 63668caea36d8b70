// Rank 0's messages, on the terminal and in OUT/log.txt (run_log.hpp).
#include "run_log.hpp"

#include <unistd.h>

#include <cerrno>
#include <cstring>

#include "coloc/core/error.hpp"
#include "coloc/core/files.hpp"

namespace coloc {

namespace {

/// The log file, appended to (or emptied first), a regular file only and never through a
/// symbolic link (coloc/core/files.hpp); throws IoError naming it.
std::FILE* openLog(const std::string& path, bool truncate) {
  const int fd = openForAppend(path);
  if (truncate && ::ftruncate(fd, 0) != 0) {
    const int e = errno;
    ::close(fd);
    throw IoError("cannot empty the log file '" + path + "': " + std::strerror(e));
  }
  std::FILE* f = ::fdopen(fd, "a");
  if (!f) {
    const int e = errno;
    ::close(fd);
    throw IoError("cannot open the log file '" + path + "': " + std::strerror(e));
  }
  return f;
}

}  // namespace

RunLog::RunLog(bool root) : root_(root) {
  if (root_) text_.reserve(4096);
}

RunLog::~RunLog() {
  if (file_) std::fclose(file_);
}

std::string logHeader(const Json& p, const std::string& casePath, const std::string& outDir) {
  const auto text = [&](const char* key) {
    if (!p.contains(key)) return std::string("unknown");
    return p[key].is_string() ? p[key].get<std::string>() : p[key].dump();
  };
  const Json env = p.value("mpi_env", Json::object());
  const auto envText = [&](const char* key) {
    if (!env.contains(key)) return std::string("unknown");
    return env[key].is_string() ? env[key].get<std::string>() : env[key].dump();
  };
  const bool dirty =
      p.contains("git_dirty") && p["git_dirty"].is_boolean() && p["git_dirty"].get<bool>();
  std::string h;
  h += fmt::format("coloc: coloc {}, git {}{}\n", text("coloc_version"), text("git_commit"),
                   dirty ? " (with uncommitted changes)" : "");
  h += fmt::format("coloc: command: {}\n", text("command_line"));
  h += fmt::format("coloc: {} on {} ({}, {} cores online)\n", text("date"), text("host"),
                   text("cpu_model"), text("cores"));
  h += fmt::format(
      "coloc: {} rank(s) on {} node(s), {}-{} a node{}; binding {} (rank 0 on CPUs {}); "
      "yield when idle {}\n",
      text("ranks"), text("nodes"), envText("ranks_per_node_min"), envText("ranks_per_node_max"),
      p.value("oversubscribed", false) ? ", oversubscribed" : "", envText("binding"),
      envText("cpus_rank0"), envText("yield_when_idle"));
  h += fmt::format("coloc: MPI: {}\n", text("mpi_library"));
  h += fmt::format("coloc: build: {} {}, flags {}; hypre {}, HDF5 {}\n", text("compiler"),
                   text("build_type"), text("compiler_flags"), text("hypre_version"),
                   text("hdf5_version"));
  h += fmt::format("coloc: case file {}, output folder {}\n", casePath, outDir);
  return h;
}

void RunLog::open(const std::string& path, bool append, const std::string& header) {
  if (!root_) return;
  if (file_) std::fclose(file_);
  file_ = nullptr;
  file_ = openLog(path, !append);
  if (append) std::fputs("coloc: ---- the run continues (--restart) ----\n", file_);
  std::fwrite(header.data(), 1, header.size(), file_);
  std::fwrite(pending_.data(), 1, pending_.size(), file_);
  std::fflush(file_);
  pending_.clear();
  pending_.shrink_to_fit();
}

void RunLog::reopen(const std::string& path) {
  if (!root_) return;
  if (file_) std::fclose(file_);
  file_ = nullptr;
  file_ = openLog(path, false);
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
