// The reason of a failed write a user can act on (a full disk, a quota, no permission), from errno
// or the free space of the file system: no HDF5 here (also in the SMPI build).
#pragma once

#include <string>

namespace coloc::h5 {

/// What the failed system call said, for the errors a user can act on (errno of the last call;
/// set to 0 before the HDF5 call by ioCollective).
std::string ioReason();
/// After a failed write whose errno says nothing (MPI-IO often keeps it): a nearly full file
/// system of `file` is named.
std::string spaceReason(const std::string& file);

}  // namespace coloc::h5
