// coloc/io/library_version.hpp — the HDF5 library io/ writes with, for report.json's provenance
// (only io/ links HDF5; the driver asks here).
#pragma once

#include <string>

namespace coloc {

/// The version of the HDF5 library linked at run time (H5get_libversion), e.g. "1.10.8".
std::string hdf5Version();

}  // namespace coloc
