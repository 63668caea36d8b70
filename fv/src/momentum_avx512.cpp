// The explicit momentum terms and the predictor compiled with -mavx512f -ffp-contract=off
// (fv/CMakeLists.txt); explicitTerms() (momentum.cpp) calls it on CPUs that have the instructions.
#include "momentum_kernels.hpp"

namespace coloc::fv {

COLOC_MOMENTUM_DEFINE(explicitTermsAvx512, predictFacesAvx512)

}  // namespace coloc::fv
