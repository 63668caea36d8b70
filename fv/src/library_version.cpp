// The hypre version (coloc/fv/library_version.hpp).
#include "coloc/fv/library_version.hpp"

#include <HYPRE_config.h>

namespace coloc::fv {

std::string hypreVersion() {
  return HYPRE_RELEASE_VERSION;
}

}  // namespace coloc::fv
