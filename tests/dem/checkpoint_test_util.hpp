// Helpers of the DEM tests that take a DemState through a checkpoint file (writeDemState and
// readDemState of coloc::coupling): a temporary file, written on one communicator and read on
// another (a restart on other ranks), then removed.
#pragma once

#include <unistd.h>

#include <cstdio>
#include <filesystem>
#include <string>

#include "coloc/core/comm.hpp"
#include "coloc/coupling/checkpoint.hpp"
#include "coloc/dem/dem.hpp"
#include "coloc/io/h5io.hpp"

namespace demtest {

/// A path in the temporary folder named after `tag`, the size of `comm` and the process of its
/// rank 0, the same on every rank of `comm`. Collective.
inline std::string tempFile(const coloc::Comm& comm, const std::string& tag) {
  const std::string path = (std::filesystem::temp_directory_path() /
                            ("coloc_" + tag + "_" + std::to_string(comm.size()) + "_" +
                             std::to_string(::getpid()) + ".h5"))
                               .string();
  return comm.broadcast(path);
}

/// `st` into the file `path` as the group /particles. Collective on `comm`.
inline void writeState(const coloc::Comm& comm, const std::string& path,
                       const coloc::dem::DemState& st) {
  coloc::H5File f = coloc::H5File::create(comm, path);
  coloc::coupling::writeDemState(f, "/particles", st);
  f.close();
}

/// The state of writeState, read on `comm` (an even split of the rows, not the writer's).
inline coloc::dem::DemState readState(const coloc::Comm& comm, const std::string& path) {
  coloc::H5File f = coloc::H5File::openRead(comm, path);
  coloc::dem::DemState st = coloc::coupling::readDemState(f, "/particles");
  f.close();
  return st;
}

/// Removes `path` once every rank of `comm` is done with it. Collective.
inline void removeFile(const coloc::Comm& comm, const std::string& path) {
  comm.barrier();
  if (comm.isRoot()) std::remove(path.c_str());
}

/// `st` written to a temporary file and read back on the same ranks; the file is removed.
inline coloc::dem::DemState throughFile(const coloc::Comm& comm, const std::string& tag,
                                        const coloc::dem::DemState& st) {
  const std::string path = tempFile(comm, tag);
  writeState(comm, path, st);
  coloc::dem::DemState back = readState(comm, path);
  removeFile(comm, path);
  return back;
}

}  // namespace demtest
