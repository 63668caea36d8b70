// The HDF5 library version (coloc/io/library_version.hpp).
#include "coloc/io/library_version.hpp"

#include <fmt/format.h>
#include <hdf5.h>

namespace coloc {

std::string hdf5Version() {
  unsigned major = 0, minor = 0, release = 0;
  if (H5get_libversion(&major, &minor, &release) < 0) return H5_VERS_INFO;
  return fmt::format("{}.{}.{}", major, minor, release);
}

}  // namespace coloc
