// coloc/coupling/library_version.hpp — the version of SLEEF (the drag laws' vectorised exp/log),
// which only coupling links (`coloc --version`).
#pragma once

#include <string>

namespace coloc::coupling {

/// SLEEF's version, MAJOR.MINOR.PATCH, as compiled against.
std::string sleefVersion();

}  // namespace coloc::coupling
