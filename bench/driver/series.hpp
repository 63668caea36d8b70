// The per-step time series of a run, OUT/series.csv (docs/output.md).
#pragma once

#include <optional>
#include <string>
#include <vector>

#include "coloc/core/comm.hpp"
#include "coloc/core/config.hpp"
#include "coloc/coupling/simulation.hpp"
#include "diagnostics.hpp"

namespace coloc {

/// A per-step time series (series.csv): coupling totals, the particles of
/// output.series_particles / output.series_particle_ids, and the bed diagnostics
/// (diagnostics.hpp) on the steps of output.diagnostics_interval and the last step (empty fields
/// in the other rows).
/// Rank 0 writes the header to series.csv.tmp and renames it (an old series.csv is replaced whole),
/// then appends each row with one write(); a row that cannot be written whole is cut off again
/// (ftruncate), so the file holds whole rows only, and the error waits in error() for the step's
/// agreement (no extra collective).
class Series {
 public:
  /// Collective. Throws ConfigError for a particle id the run does not have, IoError (rank 0)
  /// when the file cannot be made.
  Series(const Comm& comm, const std::string& path, coupling::Simulation& sim, const Config& cfg);
  ~Series();
  Series(const Series&) = delete;
  Series& operator=(const Series&) = delete;

  /// One row; the diagnostics when due or at the end of the run. Returns them when computed.
  /// Collective.
  std::optional<BedDiagnostics> record(coupling::Simulation& sim);
  /// Rank 0: the write error of the last record(), if any (then the series stops growing).
  const std::string& error() const { return error_; }
  /// Rank 0: to stable storage (with each checkpoint, at the end).
  void sync();

 private:
  /// One write() of the whole text; on a short or failed write the file is cut back.
  bool append(const std::string& text);
  const Comm& comm_;
  const Config& cfg_;
  std::vector<long long> ids_;
  /// The column of particle id (-1: none), for ids 0 .. column_.size() - 1 (the largest id in
  /// the series): one comparison rejects the other particles.
  std::vector<long long> column_;
  std::vector<double> row_;  // the step's 9 values per particle (reused)
  long long diagEvery_ = 0;
  int fd_ = -1;
  std::string path_, line_, error_;
};

}  // namespace coloc
