// coloc/fv/library_version.hpp — the hypre library the pressure solve uses, for report.json's
// provenance (only fv/ links hypre; the driver asks here).
#pragma once

#include <string>

namespace coloc::fv {

/// hypre's release the build was compiled against (HYPRE_RELEASE_VERSION), e.g. "2.26.0".
std::string hypreVersion();

}  // namespace coloc::fv
