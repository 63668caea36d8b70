// coloc/core/provenance.hpp — where a run comes from: report.json's "provenance" (docs/output.md):
// when and where it ran, on what, how the program was built, and the command that started it.
#pragma once

#include <string>

#include "coloc/core/comm.hpp"
#include "coloc/core/config.hpp"
#include "coloc/core/version.hpp"

namespace coloc {

/// Collective. The keys core knows: date (UTC, ISO 8601), host (rank 0's), cpu_model
/// (/proc/cpuinfo), cores (online, on rank 0's node), ranks, nodes, ranks_per_node_max,
/// oversubscribed (some node runs more ranks than it has cores online), cores_used (the sum over
/// nodes of min(ranks, cores): the cores of a figure of merit), coloc_version,
/// git_commit and git_dirty (of the source tree at build time; "unknown" outside a git
/// checkout), compiler, compiler_flags, build_type, mpi_library (MPI_Get_library_version),
/// mpi_env (what changes timings: ranks_per_node_min/max; binding, how each node's ranks sit on
/// its CPUs by their affinity masks: "exclusive", "overlapping" or "none"; cpus_per_rank_min/max;
/// cpus_rank0; yield_when_idle, Open MPI's mpi_yield_when_idle through MPI_T, true, false or
/// "unknown") and command_line. The versions of the libraries core does not link (hypre, HDF5)
/// are the caller's to add.
Json provenance(const Comm& comm, const std::string& commandLine);

/// The build, for `coloc --version` (core's part, one "  name: value" line each after the
/// first line "coloc VERSION"): git commit, compiler and build type, flags, MPI library. The
/// caller adds the libraries core does not link.
std::string buildDescription();

/// The command line as a shell would take it back: each argument quoted where it needs to be.
std::string commandLineText(int argc, const char* const* argv);

}  // namespace coloc
