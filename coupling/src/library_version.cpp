// The version of SLEEF (coloc/coupling/library_version.hpp).
#include "coloc/coupling/library_version.hpp"

#include <sleef.h>

namespace coloc::coupling {

std::string sleefVersion() {
  return std::to_string(SLEEF_VERSION_MAJOR) + "." + std::to_string(SLEEF_VERSION_MINOR) + "." +
         std::to_string(SLEEF_VERSION_PATCHLEVEL);
}

}  // namespace coloc::coupling
