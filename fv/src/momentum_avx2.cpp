// The explicit momentum terms and the predictor compiled with -mavx2 -ffp-contract=off
// (fv/CMakeLists.txt); explicitTerms() (momentum.cpp) calls it on CPUs that have the instructions.
#include "momentum_kernels.hpp"

namespace coloc::fv {

COLOC_MOMENTUM_DEFINE(explicitTermsAvx2, predictFacesAvx2)

}  // namespace coloc::fv
