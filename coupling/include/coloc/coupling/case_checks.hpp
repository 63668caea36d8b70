// coloc/coupling/case_checks.hpp — checks of a whole case that no single key's range expresses,
// and the memory estimate, made before anything large is allocated (`coloc run`, `coloc check`;
// docs/case-files.md).
#pragma once

#include <string>
#include <vector>

#include "coloc/core/comm.hpp"
#include "coloc/core/config.hpp"
#include "coloc/partition/decomposition.hpp"

namespace coloc::coupling {

/// Cross-key checks; throws ConfigError naming the keys:
///  - name: a plain name (it becomes the folder out/<name>): not empty, no '/', not . or ..;
///  - output.checkpoint_file: inside the output folder (not absolute, no ".."), and none of the
///    run's own files (report.json, series.csv, fields_*.h5, ...; io/checkpoint_file.hpp);
///  - a coupled run with a fixed fluid.dt that is not a whole multiple of particles.dt (the CFD
///    step is a whole number of DEM steps; the run would silently use another step);
///  - an inlet with no outlet face (the inflow has nowhere to go);
///  - coupling.self_velocity where it does not apply (self_velocity.hpp).
/// Returns notes: where what runs differs from a key's face value (announced by the driver on
/// rank 0 and stored in report.json under run.notes).
std::vector<std::string> checkCase(const Config& cfg);

/// The number of particles the case's sources create.
double sourceParticleCount(const Config& cfg);
/// The particles the inflows insert over the run, at most what the box holds (densely packed).
double inflowParticleCount(const Config& cfg);
/// The particles the inflows make due over the run: the longest their waiting lists can grow.
double inflowWaitingCount(const Config& cfg);

/// Estimated resident memory of one rank, from its block and its particles. Coefficients
/// measured with peak RSS on this project's runs (docs/case-files.md, "Memory estimate").
struct MemoryEstimate {
  long long cells = 0;         // owned cells of the block
  long long ghostedCells = 0;  // with the fluid's two ghost layers on every side
  double particles = 0;
  double baseBytes = 0;      // MPI, hypre, HDF5 and the program itself
  double fluidBytes = 0;     // fluid fields and the pressure solver's (hypre) matrix and vectors
  double couplingBytes = 0;  // deposited fields, fluid fraction, drag coefficients
  double particleBytes = 0;  // particle arrays, neighbour lists, bins, contact histories
  double inflowBytes = 0;    // the inflows' waiting lists (every rank holds them whole)
  double total() const {
    return baseBytes + fluidBytes + couplingBytes + particleBytes + inflowBytes;
  }
};
MemoryEstimate estimateMemory(const Config& cfg, Int3 blockCells, double particles);

/// The largest uniform block of the case on `ranks` ranks (cells along each axis).
Int3 largestUniformBlock(const Config& cfg, int ranks);

/// What the machine offers one rank: run.memory_limit (GiB) when set, else /proc/meminfo's
/// MemAvailable divided by `ranksOnNode`, and at most the address space this process may still
/// map (RLIMIT_AS, `ulimit -v`, less what is mapped now). `how` says which. 0 when unknown.
double memoryLimitPerRank(const Config& cfg, int ranksOnNode, std::string* how);

/// "1.23 GiB"
std::string bytesText(double bytes);

/// Collective: refuses (ConfigError naming domain.cells, particles.sources and run.memory_limit)
/// a case whose estimate on the largest uniform block, with the mean particle count per rank,
/// exceeds what this node offers a rank. Reads /proc/meminfo on every rank; same verdict
/// everywhere.
void checkMemory(const Comm& world, const Config& cfg);

}  // namespace coloc::coupling
