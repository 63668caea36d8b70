// The batched drag laws compiled with -mavx512f (coupling/CMakeLists.txt): packs of
// 8 particles; dragCoefficients() (drag.cpp) calls it on CPUs that have the instructions.
#include "drag_packs.hpp"

namespace coloc::coupling {

COLOC_DRAG_PACKS_DEFINE(dragPacksAvx512)

}  // namespace coloc::coupling
