// Drag laws against values computed by hand (an independent Python transcription of each
// published formula; see coupling/drag.hpp for the sources). Tolerance 1e-10 relative.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <numbers>
#include <span>
#include <vector>

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

// The batched laws (what a coupled run uses: vectorised exp/log on packs of particles) against
// the scalar reference over a wide grid of (eps, Re), slip = 0 included. The batched form writes
// pow(a, b) as exp(b log a) and log10 as log / ln 10: their rounding differs from libm's by a few
// ulp times |b log a| (at most ~30 here), so 1e-13 relative holds with a margin.
TEST(Drag, BatchedEqualsScalarReference) {
  const double d = 1e-3;
  std::vector<double> eps, dia, slip;
  for (double e :
       {0.3, 0.36, 0.4, 0.45, 0.5, 0.6, 0.7, 0.7999999, 0.8, 0.85, 0.9, 0.95, 0.99, 0.999999, 1.0})
    for (double re : {0.0, 1e-14, 1e-12, 1e-9, 1e-6, 1e-3, 0.1, 1.0, 3.0, 31.6, 100.0, 999.0,
                      1000.0, 1001.0, 1e4, 1e5, 1e6}) {
      eps.push_back(e);
      dia.push_back(d);
      slip.push_back(re * nu / (e * d));
    }
  const std::size_t n = eps.size();
  std::vector<double> beta(n);
  // Every instruction set this CPU runs (the one a run uses among them).
  for (auto packs : {DragPacks::Widest, DragPacks::Build, DragPacks::Avx2, DragPacks::Avx512})
    for (auto law : {DragLaw::Stokes, DragLaw::DiFelice, DragLaw::Gidaspow, DragLaw::Beetstra}) {
      if (!dragCoefficientsOn(packs, law, eps, dia, slip, rho, nu, beta)) continue;
      double worst = 0;
      for (std::size_t i = 0; i < n; ++i) {
        const double ref = dragCoefficient(law, eps[i], dia[i], slip[i], rho, nu);
        ASSERT_TRUE(std::isfinite(beta[i]) && beta[i] > 0) << dragLawName(law) << " i " << i;
        EXPECT_NEAR(beta[i] / ref, 1.0, 1e-13)
            << dragLawName(law) << " eps " << eps[i] << " slip " << slip[i];
        worst = std::max(worst, std::abs(beta[i] / ref - 1.0));
      }
      std::printf("%s, packs %d: largest relative difference %.2g\n", dragLawName(law),
                  static_cast<int>(packs), worst);
    }
}

// A particle's value does not depend on where it falls in a batch: every particle of a batch
// alone (the padded remainder of a pack) and at every offset and batch length gives the same bits
// as in one long batch.
TEST(Drag, BatchedValueIndependentOfPositionAndLength) {
  std::vector<double> eps, dia, slip;
  for (int i = 0; i < 37; ++i) {
    eps.push_back(0.35 + 0.0175 * i);
    dia.push_back(1e-3 * (1.0 + 0.01 * i));
    slip.push_back(i % 5 == 0 ? 0.0 : 1e-3 * i * i);
  }
  const std::size_t n = eps.size();
  for (auto packs : {DragPacks::Widest, DragPacks::Build, DragPacks::Avx2, DragPacks::Avx512})
    for (auto law : {DragLaw::Stokes, DragLaw::DiFelice, DragLaw::Gidaspow, DragLaw::Beetstra}) {
      std::vector<double> all(n), part(n);
      if (!dragCoefficientsOn(packs, law, eps, dia, slip, rho, nu, all)) continue;
      for (std::size_t off = 0; off < n; ++off)
        for (std::size_t len = 1; off + len <= n; ++len) {
          const std::span<const double> e(eps.data() + off, len), dd(dia.data() + off, len),
              s(slip.data() + off, len);
          dragCoefficientsOn(packs, law, e, dd, s, rho, nu, std::span<double>(part.data(), len));
          for (std::size_t k = 0; k < len; ++k)
            ASSERT_EQ(part[k], all[off + k])
                << dragLawName(law) << " particle " << off + k << " at " << k << " of " << len;
        }
    }
}
