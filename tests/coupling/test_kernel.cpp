// Deposition and interpolation kernels on the shared decomposition, at 1, 2 and 4 ranks:
// partition of unity, exact adjointness of deposit (with the reverse halo sum) and interpolation
// (with the halo gather and the wall mirror), and the same deposited field at any rank count.
#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "coloc/coupling/kernel.hpp"
#include "coloc/partition/halo.hpp"

using namespace coloc;
using namespace coloc::coupling;

namespace {

GlobalGrid grid() {
  GlobalGrid g;
  g.origin = {0.0, -0.1, 0.0};
  g.length = {1.0, 0.2, 0.3};
  g.cells = {13, 4, 6};
  g.periodic = {false, false, true};
  return g;
}

/// The same global particle set on every rank count; each rank keeps the particles it owns.
void ownedParticles(const Decomposition& dec, std::vector<double>& x, std::vector<double>& y,
                    std::vector<double>& z, std::vector<double>& q, int count = 400) {
  std::mt19937_64 rng(42);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  const auto& g = dec.grid();
  for (int p = 0; p < count; ++p) {
    const Real3 r{g.origin[0] + g.length[0] * u(rng), g.origin[1] + g.length[1] * u(rng),
                  g.origin[2] + g.length[2] * u(rng)};
    const double w = 0.5 + u(rng);
    if (dec.ownerOfPoint(r) != dec.rank()) continue;
    x.push_back(r[0]);
    y.push_back(r[1]);
    z.push_back(r[2]);
    q.push_back(w);
  }
}

double field(int gi, int gj, int gk) {
  return std::sin(0.7 * gi + 0.3) + 0.5 * gj - 0.25 * gk * gk;
}

class KernelTest : public ::testing::TestWithParam<KernelKind> {};

}  // namespace

TEST_P(KernelTest, DepositConservesTotalsAcrossBlocks) {
  const auto dec = Decomposition::uniform(Comm::world(), grid());
  std::vector<double> x, y, z, q;
  ownedParticles(dec, x, y, z, q);
  CellField f(cellLayout(dec, 1));
  Stencils s;
  EXPECT_EQ(s.compute(GetParam(), dec, f.layout(), x, y, z, x.size()), -1);
  for (std::size_t p = 0; p < x.size(); ++p) {
    double sum = 0;
    s.forEachCell(p, [&](std::int32_t, double w) { sum += w; });
    ASSERT_NEAR(sum, 1.0, 1e-14);
  }
  deposit(s, q, 1.0, f);
  HaloPlan halo(dec, f.layout());
  halo.scatterSum(f, Fold::Mirror);
  double local = 0, qsum = 0;
  forEach(f.interior(), [&](int i, int j, int k) { local += f(i, j, k); });
  for (double v : q) qsum += v;
  EXPECT_NEAR(dec.comm().sum(local), dec.comm().sum(qsum), 1e-12 * dec.comm().sum(qsum));
}

TEST_P(KernelTest, DepositAndInterpolateAreAdjoint) {
  const auto dec = Decomposition::uniform(Comm::world(), grid());
  std::vector<double> x, y, z, q;
  ownedParticles(dec, x, y, z, q);
  const auto layout = cellLayout(dec, 1);
  Stencils s;
  s.compute(GetParam(), dec, layout, x, y, z, x.size());
  CellField dep(layout), f(layout);
  deposit(s, q, 1.0, dep);
  HaloPlan halo(dec, layout);
  halo.scatterSum(dep, Fold::Mirror);
  forEach(f.interior(), [&](int i, int j, int k) {
    f(i, j, k) = field(dec.lo()[0] + i, dec.lo()[1] + j, dec.lo()[2] + k);
  });
  halo.gather(f);
  fillWallGhostsByMirror(dec, f);
  std::vector<double> at(x.size());
  interpolate(s, f, at);
  double lhs = 0, rhs = 0;
  forEach(f.interior(), [&](int i, int j, int k) { lhs += f(i, j, k) * dep(i, j, k); });
  for (std::size_t p = 0; p < x.size(); ++p) rhs += q[p] * at[p];
  lhs = dec.comm().sum(lhs);
  rhs = dec.comm().sum(rhs);
  EXPECT_NEAR(lhs, rhs, 1e-12 * std::abs(rhs));
}

TEST_P(KernelTest, TrilinearInterpolationIsExactForLinearFieldsInside) {
  if (GetParam() != KernelKind::Trilinear) GTEST_SKIP();
  const auto dec = Decomposition::uniform(Comm::world(), grid());
  const auto& g = dec.grid();
  const auto layout = cellLayout(dec, 1);
  CellField f(layout);
  HaloPlan halo(dec, layout);
  auto lin = [&](double px, double py, double pz) { return 2.0 * px - 3.0 * py + 0.5 * pz + 1.0; };
  forEach(layout.allocated(), [&](int i, int j, int k) {
    f(i, j, k) = lin(g.origin[0] + (dec.lo()[0] + i + 0.5) * g.spacing(0),
                     g.origin[1] + (dec.lo()[1] + j + 0.5) * g.spacing(1),
                     g.origin[2] + (dec.lo()[2] + k + 0.5) * g.spacing(2));
  });
  std::vector<double> x, y, z, q;
  ownedParticles(dec, x, y, z, q);
  Stencils s;
  s.compute(KernelKind::Trilinear, dec, layout, x, y, z, x.size());
  std::vector<double> at(x.size());
  interpolate(s, f, at);
  for (std::size_t p = 0; p < x.size(); ++p) ASSERT_NEAR(at[p], lin(x[p], y[p], z[p]), 1e-12);
}

TEST_P(KernelTest, DepositedFieldIsIndependentOfTheRankCount) {
  const auto dec = Decomposition::uniform(Comm::world(), grid());
  // Global picture of the deposit on this decomposition vs computed serially on every rank.
  auto globalDeposit = [&](const Decomposition& d, bool everyoneAll) {
    std::vector<double> x, y, z, q;
    if (everyoneAll) {
      // the reference: this rank deposits every particle onto one block holding the whole box
      std::mt19937_64 rng(42);
      std::uniform_real_distribution<double> u(0.0, 1.0);
      const auto& g = d.grid();
      for (int p = 0; p < 400; ++p) {
        x.push_back(g.origin[0] + g.length[0] * u(rng));
        y.push_back(g.origin[1] + g.length[1] * u(rng));
        z.push_back(g.origin[2] + g.length[2] * u(rng));
        q.push_back(0.5 + u(rng));
      }
    } else {
      ownedParticles(d, x, y, z, q);
    }
    const auto layout = cellLayout(d, 1);
    CellField f(layout);
    Stencils s;
    s.compute(GetParam(), d, layout, x, y, z, x.size());
    deposit(s, q, 1.0, f);
    HaloPlan halo(d, layout);
    halo.scatterSum(f, Fold::Mirror);
    std::vector<double> out(static_cast<std::size_t>(d.grid().cellCount()), 0.0);
    forEach(f.interior(), [&](int i, int j, int k) {
      const int gi = d.lo()[0] + i, gj = d.lo()[1] + j, gk = d.lo()[2] + k;
      out[static_cast<std::size_t>(gi + 13 * (gj + 4 * gk))] = f(i, j, k);
    });
    d.comm().sumInPlace(std::span<double>(out));
    return out;
  };
  const auto a = globalDeposit(dec, false);
  // Reference: one block holding everything, built on a communicator of one rank.
  MPI_Comm self;
  MPI_Comm_split(MPI_COMM_WORLD, Comm::world().rank(), 0, &self);
  {
    const auto one = Decomposition::uniform(Comm(self), grid());
    const auto b = globalDeposit(one, true);
    for (std::size_t c = 0; c < a.size(); ++c)
      ASSERT_NEAR(a[c], b[c], 1e-12 * (1.0 + std::abs(b[c]))) << c;
  }
  MPI_Comm_free(&self);
}

TEST_P(KernelTest, FusedPassesEqualOneFieldPassesBitForBit) {
  // interpolate() of 7 fields and deposit() of 5 terms in one pass each give, field by field,
  // exactly the values of the one-field kernels (same weights, same order of the additions):
  // sparse particles (interpolate() falls back to one pass a field), and dense ones.
  const auto dec = Decomposition::uniform(Comm::world(), grid());
  for (const int count : {40, 400, 8000}) {
    std::vector<double> x, y, z, q;
    ownedParticles(dec, x, y, z, q, count);
    const std::size_t n = x.size();
    const auto layout = cellLayout(dec, 1);
    Stencils s;
    s.compute(GetParam(), dec, layout, x, y, z, n);
    std::vector<CellField> f(7, CellField(layout));
    for (int k = 0; k < 7; ++k)
      forEach(layout.allocated(), [&](int i, int j, int l) {
        f[k](i, j, l) = field(i + k, j, l) / (1.0 + k) + 1e-3 * (i * j - l);
      });
    std::vector<std::vector<double>> one(7, std::vector<double>(n)), fused = one;
    const CellField* in[7];
    double* out[7];
    for (int k = 0; k < 7; ++k) {
      interpolate(s, f[k], one[k]);
      in[k] = &f[k];
      out[k] = fused[k].data();
    }
    interpolate(s, in, out);
    for (int k = 0; k < 7; ++k)
      for (std::size_t p = 0; p < n; ++p) ASSERT_EQ(one[k][p], fused[k][p]) << k << " " << p;

    std::vector<double> b(n);
    for (std::size_t p = 0; p < n; ++p) b[p] = 0.1 + 0.37 * static_cast<double>(p % 11);
    std::vector<CellField> d1(5, CellField(layout, 0.25)), d5 = d1;  // f_c += ...
    deposit(s, std::span<const double>(), 0.7, d1[0]);
    deposit(s, q, 1.3, d1[1]);
    for (int k = 2; k < 5; ++k) depositProduct(s, q, b, 0.3 * k, d1[k]);
    const DepositTerm terms[5] = {{nullptr, nullptr, 0.7, &d5[0]},
                                  {q.data(), nullptr, 1.3, &d5[1]},
                                  {q.data(), b.data(), 0.3 * 2, &d5[2]},
                                  {q.data(), b.data(), 0.3 * 3, &d5[3]},
                                  {q.data(), b.data(), 0.3 * 4, &d5[4]}};
    deposit(s, terms);
    for (int k = 0; k < 5; ++k)
      for (std::size_t c = 0; c < d1[k].data().size(); ++c)
        ASSERT_EQ(d1[k].data()[c], d5[k].data()[c]) << k << " " << c;
  }
}

INSTANTIATE_TEST_SUITE_P(Kernels, KernelTest,
                         ::testing::Values(KernelKind::Centroid, KernelKind::Trilinear));

TEST(Smoothing, ConservesTotalsAndIsSelfAdjoint) {
  // <S a, b> = <a, S b> over the owned cells (walls and periodic axes, any rank count), and the
  // total is conserved: what makes the smoothed deposit and the smoothed interpolation adjoint.
  const auto dec = Decomposition::uniform(Comm::world(), grid());
  const auto layout = cellLayout(dec, 1);
  CellField a(layout), b(layout), scratch(layout);
  forEach(a.interior(), [&](int i, int j, int k) {
    const int gi = dec.lo()[0] + i, gj = dec.lo()[1] + j, gk = dec.lo()[2] + k;
    a(i, j, k) = (gi == 3 && gj == 1 && gk == 2) ? 1.0 : 0.0;  // a spike
    b(i, j, k) = field(gi, gj, gk);
  });
  auto dot = [&](const CellField& x, const CellField& y) {
    double s = 0;
    forEach(x.interior(), [&](int i, int j, int k) { s += x(i, j, k) * y(i, j, k); });
    return dec.comm().sum(s);
  };
  auto total = [&](const CellField& x) {
    double s = 0;
    forEach(x.interior(), [&](int i, int j, int k) { s += x(i, j, k); });
    return dec.comm().sum(s);
  };
  HaloPlan halo(dec, layout);
  CellField sa = a, sb = b;
  smooth(dec, halo, sa, scratch);
  smooth(dec, halo, sb, scratch);
  EXPECT_NEAR(total(sa), 1.0, 1e-14);
  EXPECT_NEAR(dot(sa, b), dot(a, sb), 1e-13);
  double peak = 0;
  forEach(sa.interior(), [&](int i, int j, int k) { peak = std::max(peak, sa(i, j, k)); });
  EXPECT_NEAR(dec.comm().max(peak), 1.0 - 6.0 / 8.0, 1e-14);  // the spike spreads
}
