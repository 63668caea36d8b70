// Schumann's packed-bed solution (tests/coupling/schumann.hpp) against its known properties:
//  - theta_f = 1 at the inlet (y = 0), 0 before the front (z < 0), exp(-y) on the front (z = 0);
//  - the symmetry J(y, z) + J(z, y) = 1 + exp(-y-z) I0(2 sqrt(yz)) to 1e-12;
//  - an independent quadrature of J(y, z) = 1 - int_0^y exp(-z-xi) I0(2 sqrt(z xi)) dxi
//    (composite Simpson, std::cyl_bessel_i) to 1e-9, y, z up to 40;
//  - Klinkenberg's approximation (A. Klinkenberg, Ind. Eng. Chem. 40 (1948) 1992),
//    theta_f ~ (1 + erf(sqrt z - sqrt y + 1/(8 sqrt z) + 1/(8 sqrt y)))/2, to 1e-3 for
//    y, z >= 10 (measured 3.8e-4);
//  - the ODEs: dtheta_f/dy = theta_s - theta_f and dtheta_s/dz = theta_f - theta_s by central
//    differences to 1e-6; theta_f and theta_s lie in [0, 1], theta_f >= theta_s;
//  - SchumannBed's variables: y and z of a bed in physical units.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>

#include "schumann.hpp"

namespace {

using coloc::test::schumannFluid;
using coloc::test::schumannJ;
using coloc::test::schumannSolid;

/// J(y, z) by composite Simpson on n intervals of the integral form.
double quadratureJ(double y, double z, int n = 20000) {
  const auto f = [&](double xi) {
    return std::exp(-z - xi) * std::cyl_bessel_i(0.0, 2.0 * std::sqrt(z * xi));
  };
  const double h = y / n;
  double s = f(0) + f(y);
  for (int i = 1; i < n; ++i) s += (i % 2 ? 4.0 : 2.0) * f(i * h);
  return 1.0 - s * h / 3.0;
}

const double kArgs[] = {0.05, 0.3, 1.0, 2.5, 5.0, 10.0, 17.0, 25.0, 40.0};

TEST(Schumann, BoundaryAndInitialValues) {
  for (double z : kArgs) EXPECT_EQ(schumannFluid(0.0, z), 1.0);
  for (double y : kArgs) {
    EXPECT_EQ(schumannFluid(y, -1e-3), 0.0);
    EXPECT_EQ(schumannSolid(y, -1e-3), 0.0);
    EXPECT_EQ(schumannSolid(y, 0.0), 0.0);
    EXPECT_NEAR(schumannFluid(y, 0.0), std::exp(-y), 1e-15);
    EXPECT_NEAR(schumannJ(y, 1e-12), std::exp(-y), 1e-11);  // continuous onto the front
  }
}

TEST(Schumann, SymmetryRelation) {
  double worst = 0;
  for (double y : kArgs)
    for (double z : kArgs) {
      const double lhs = schumannJ(y, z) + schumannJ(z, y);
      // exp(-y-z) I0(2 sqrt(yz)) without overflow: I0 is finite up to 2 sqrt(yz) = 80 here
      const double rhs = 1.0 + std::exp(-y - z) * std::cyl_bessel_i(0.0, 2.0 * std::sqrt(y * z));
      worst = std::max(worst, std::fabs(lhs - rhs));
    }
  // large arguments, where I0 overflows: exp(-y-z) I0(2 sqrt(yz)) ~ exp(-(sqrt y - sqrt z)^2) /
  // sqrt(4 pi sqrt(yz)) (1 + 1/(16 sqrt(yz)) + ...)
  const double y = 900, z = 1000, s = std::sqrt(y * z);
  const double asym = std::exp(-std::pow(std::sqrt(y) - std::sqrt(z), 2)) /
                      std::sqrt(4 * M_PI * s) * (1 + 1 / (16 * s) + 9 / (512 * s * s));
  const double big = std::fabs(schumannJ(y, z) + schumannJ(z, y) - 1.0 - asym);
  std::printf(
      "symmetry: max |J(y,z) + J(z,y) - 1 - exp(-y-z) I0| = %.2e; y = 900, z = 1000: %.2e\n", worst,
      big);
  EXPECT_LT(worst, 1e-12);
  EXPECT_LT(big, 1e-10);
}

TEST(Schumann, IndependentQuadrature) {
  double worst = 0;
  for (double y : kArgs)
    for (double z : kArgs) worst = std::max(worst, std::fabs(schumannJ(y, z) - quadratureJ(y, z)));
  // two values to quote: J(1, 1) = 0.654254161276836, J(10, 10) = 0.544890155942413
  std::printf("quadrature: max |J - J_quad| = %.2e; J(1,1) = %.15f, J(10,10) = %.15f\n", worst,
              schumannJ(1, 1), schumannJ(10, 10));
  EXPECT_LT(worst, 1e-9);
  EXPECT_NEAR(schumannJ(1, 1), 0.654254161276836, 1e-12);
  EXPECT_NEAR(schumannJ(10, 10), 0.544890155942413, 1e-12);
}

TEST(Schumann, KlinkenbergApproximation) {
  double worst = 0;
  for (double y : {10.0, 20.0, 50.0, 100.0, 400.0})
    for (double z : {10.0, 20.0, 50.0, 100.0, 400.0}) {
      const double k = 0.5 * (1 + std::erf(std::sqrt(z) - std::sqrt(y) + 1 / (8 * std::sqrt(z)) +
                                           1 / (8 * std::sqrt(y))));
      worst = std::max(worst, std::fabs(schumannJ(y, z) - k));
    }
  std::printf("Klinkenberg: max |J - approximation| = %.2e (y, z >= 10)\n", worst);
  EXPECT_LT(worst, 1e-3);
}

TEST(Schumann, SatisfiesTheEquations) {
  const double e = 1e-4;
  double worst = 0;
  for (double y : {0.5, 2.0, 7.0, 20.0})
    for (double z : {0.5, 2.0, 7.0, 20.0}) {
      const double tf = schumannFluid(y, z), ts = schumannSolid(y, z);
      const double dfy = (schumannFluid(y + e, z) - schumannFluid(y - e, z)) / (2 * e);
      const double dsz = (schumannSolid(y, z + e) - schumannSolid(y, z - e)) / (2 * e);
      worst = std::max({worst, std::fabs(dfy - (ts - tf)), std::fabs(dsz - (tf - ts))});
      EXPECT_GE(tf, ts);
      EXPECT_GE(ts, 0.0);
      EXPECT_LE(tf, 1.0);
    }
  EXPECT_LT(worst, 1e-6);
}

TEST(Schumann, BedVariables) {
  coloc::test::SchumannBed b;
  b.eps = 0.4;
  b.d = 2e-3;
  b.h = 500;
  b.rhoF = 1000;
  b.cF = 4000;
  b.rhoS = 2500;
  b.cS = 800;
  b.us = 2e-3;
  const double av = 6 * 0.6 / 2e-3;  // 1800 1/m
  EXPECT_DOUBLE_EQ(b.av(), av);
  EXPECT_DOUBLE_EQ(b.y(0.05), 500 * av * 0.05 / (1000 * 4000 * 2e-3));
  EXPECT_DOUBLE_EQ(b.z(0.05, 30), 500 * av * (30 - 0.4 * 0.05 / 2e-3) / (2500 * 800 * 0.6));
  EXPECT_EQ(b.fluid(0.05, 5), 0.0);  // the fluid front reaches x = 0.05 m at t = 10 s
  EXPECT_DOUBLE_EQ(b.fluid(0.05, 30), schumannJ(b.y(0.05), b.z(0.05, 30)));
}

}  // namespace
