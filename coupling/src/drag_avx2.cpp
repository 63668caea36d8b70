// The batched drag laws compiled with -mavx2 -mfma (coupling/CMakeLists.txt): packs of
// 4 particles; dragCoefficients() (drag.cpp) calls it on CPUs that have the instructions.
#include "drag_packs.hpp"

namespace coloc::coupling {

COLOC_DRAG_PACKS_DEFINE(dragPacksAvx2)

}  // namespace coloc::coupling
