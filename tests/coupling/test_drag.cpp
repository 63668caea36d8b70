// Drag laws against values computed by hand (an independent Python transcription of each
// published formula; see coupling/drag.hpp for the sources). Tolerance 1e-10 relative.
#include <gtest/gtest.h>

#include <cmath>
#include <numbers>

#include "coloc/coupling/drag.hpp"

using namespace coloc::coupling;

namespace {
constexpr double rho = 1000.0, nu = 1e-6;
void expectRel(double got, double ref, double tol = 1e-10) {
  EXPECT_NEAR(got / ref, 1.0, tol) << "got " << got << " expected " << ref;
}
}  // namespace

TEST(Drag, StokesIsThreePiMuD) {
  expectRel(dragCoefficient(DragLaw::Stokes, 0.7, 1e-3, 0.3, rho, nu), 9.424777960769e-06);
}

TEST(Drag, DiFeliceMatchesHandValues) {
  expectRel(dragCoefficient(DragLaw::DiFelice, 0.6, 2e-3, 0.05, rho, nu), 2.123726782203e-04);
  expectRel(dragCoefficient(DragLaw::DiFelice, 1.0, 1e-3, 0.01, rho, nu), 1.811695822654e-05);
}

TEST(Drag, GidaspowErgunAndWenYuBranches) {
  expectRel(dragCoefficient(DragLaw::Gidaspow, 0.5, 1e-3, 0.02, rho, nu), 9.686577348569e-05);
  expectRel(dragCoefficient(DragLaw::Gidaspow, 0.9, 1e-3, 0.02, rho, nu), 2.607449378075e-05);
}

TEST(Drag, BeetstraMatchesHandValuesAndTendsToStokes) {
  expectRel(dragCoefficient(DragLaw::Beetstra, 0.6, 1e-3, 0.02, rho, nu), 7.870047148329e-05);
  expectRel(beetstraF(0.6, 0.6 * 1e-3 * 0.02 / nu), 1.391729895581e+01);
  EXPECT_NEAR(beetstraF(1.0 - 1e-12, 1e-12), 1.0, 1e-5);
}

TEST(Drag, CreepingLimitsAreFiniteAndContinuous) {
  for (auto law : {DragLaw::Stokes, DragLaw::DiFelice, DragLaw::Gidaspow, DragLaw::Beetstra}) {
    const double b0 = dragCoefficient(law, 0.95, 1e-3, 0.0, rho, nu);
    const double b1 = dragCoefficient(law, 0.95, 1e-3, 1e-9, rho, nu);
    EXPECT_TRUE(std::isfinite(b0) && b0 > 0) << dragLawName(law);
    EXPECT_NEAR(b1 / b0, 1.0, 1e-3) << dragLawName(law);
  }
}

TEST(Drag, NamesRoundTrip) {
  for (auto law : {DragLaw::Stokes, DragLaw::DiFelice, DragLaw::Gidaspow, DragLaw::Beetstra})
    EXPECT_EQ(dragLawFromName(dragLawName(law)), law);
}
