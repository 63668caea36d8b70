// coloc/core/report.hpp — the run report (DIR/report.json, docs/benchmarks.md).
#pragma once

#include <string>

#include "coloc/core/comm.hpp"
#include "coloc/core/config.hpp"
#include "coloc/core/timers.hpp"
#include "coloc/core/version.hpp"  // kVersion, from CMake's project(VERSION)

namespace coloc {

class Report {
 public:
  /// Starts the report with coloc_version, case and config (the resolved configuration).
  Report(const std::string& caseSource, const Json& resolvedConfig);

  /// Set a value at a dotted path ("run.steps"), creating objects on the way.
  void set(const std::string& path, Json value);
  /// Merge an object at the top level (e.g. the output of Timers::report()).
  void merge(const Json& object);
  /// Collective: memory.{peak_rss_bytes_max,peak_rss_bytes_sum}.
  void addMemory(const Comm& comm);
  const Json& json() const { return json_; }

  /// Rank 0 writes DIR/report.json (creating DIR); returns the path. Collective (errors are
  /// raised on every rank).
  std::string write(const Comm& comm, const std::string& dir) const;

 private:
  Json json_;
};

/// Create a directory and its parents (rank-local); throws Error on failure.
void makeDirectories(const std::string& dir);

}  // namespace coloc
