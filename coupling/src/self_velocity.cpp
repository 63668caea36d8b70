#include "coloc/coupling/self_velocity.hpp"

#include <cmath>
#include <numbers>

#include "coloc/core/error.hpp"
#include "coloc/partition/setup.hpp"

namespace coloc::coupling {

namespace {

// The discrete unsteady Green's function (offsets in the order of kSelfOffsets) a time t after a
// unit force was switched on, at s = nu t / h^2 = 2^(j/4), j = -24..16, units 1/(mu h); and the
// pressure-gradient response (units 1/h^3). Both from coupling/scripts/self_green.py (N = 128).
constexpr int kBuildCount = 41;
constexpr double kBuildLog2First = -6.0, kBuildLog2Step = 0.25;
constexpr double kGreenBuild[kBuildCount][6] = {
    {0.0059364, -0.0003334, -0.0001809, 0.0035587, -0.0000866, -0.0000761},  // s = 0.015625
    {0.0070083, -0.0003841, -0.0002148, 0.0042061, -0.0000967, -0.0000903},  // s = 0.0185814
    {0.0082626, -0.0004396, -0.0002550, 0.0049656, -0.0001063, -0.0001071},  // s = 0.0220971
    {0.0097261, -0.0004990, -0.0003024, 0.0058544, -0.0001144, -0.0001270},  // s = 0.026278
    {0.0114276, -0.0005607, -0.0003584, 0.0068914, -0.0001194, -0.0001504},  // s = 0.03125
    {0.0133978, -0.0006220, -0.0004241, 0.0080972, -0.0001191, -0.0001778},  // s = 0.0371627
    {0.0156677, -0.0006787, -0.0005009, 0.0094933, -0.0001103, -0.0002097},  // s = 0.0441942
    {0.0182683, -0.0007248, -0.0005901, 0.0111019, -0.0000888, -0.0002465},  // s = 0.052556
    {0.0212278, -0.0007516, -0.0006930, 0.0129449, -0.0000485, -0.0002885},  // s = 0.0625
    {0.0245695, -0.0007476, -0.0008100, 0.0150423, 0.0000185, -0.0003357},   // s = 0.0743254
    {0.0283087, -0.0006975, -0.0009411, 0.0174107, 0.0001226, -0.0003875},   // s = 0.0883883
    {0.0324490, -0.0005819, -0.0010847, 0.0200610, 0.0002766, -0.0004425},   // s = 0.105112
    {0.0369784, -0.0003777, -0.0012371, 0.0229959, 0.0004965, -0.0004976},   // s = 0.125
    {0.0418658, -0.0000579, -0.0013913, 0.0262071, 0.0008010, -0.0005482},   // s = 0.148651
    {0.0470579, 0.0004066, -0.0015363, 0.0296730, 0.0012110, -0.0005864},    // s = 0.176777
    {0.0524788, 0.0010451, -0.0016556, 0.0333569, 0.0017486, -0.0006010},    // s = 0.210224
    {0.0580313, 0.0018834, -0.0017267, 0.0372062, 0.0024349, -0.0005763},    // s = 0.25
    {0.0636021, 0.0029402, -0.0017214, 0.0411542, 0.0032873, -0.0004921},    // s = 0.297302
    {0.0690712, 0.0042223, -0.0016066, 0.0451242, 0.0043169, -0.0003238},    // s = 0.353553
    {0.0743225, 0.0057216, -0.0013483, 0.0490353, 0.0055246, -0.0000450},    // s = 0.420448
    {0.0792569, 0.0074137, -0.0009157, 0.0528110, 0.0068999, 0.0003704},     // s = 0.5
    {0.0838024, 0.0092592, -0.0002880, 0.0563871, 0.0084198, 0.0009426},     // s = 0.594604
    {0.0879204, 0.0112086, 0.0005408, 0.0597183, 0.0100514, 0.0016817},      // s = 0.707107
    {0.0916056, 0.0132090, 0.0015583, 0.0627812, 0.0117556, 0.0025842},      // s = 0.840896
    {0.0948804, 0.0152105, 0.0027351, 0.0655735, 0.0134923, 0.0036315},      // s = 1
    {0.0977849, 0.0171718, 0.0040294, 0.0681086, 0.0152247, 0.0047932},      // s = 1.18921
    {0.1003672, 0.0190624, 0.0053951, 0.0704095, 0.0169230, 0.0060323},      // s = 1.41421
    {0.1026738, 0.0208626, 0.0067887, 0.0725022, 0.0185649, 0.0073115},      // s = 1.68179
    {0.1047456, 0.0225613, 0.0081747, 0.0744109, 0.0201355, 0.0085981},      // s = 2
    {0.1066155, 0.0241540, 0.0095271, 0.0761562, 0.0216255, 0.0098666},      // s = 2.37841
    {0.1083096, 0.0256403, 0.0108284, 0.0777548, 0.0230302, 0.0110986},      // s = 2.82843
    {0.1098487, 0.0270225, 0.0120680, 0.0792206, 0.0243480, 0.0122818},      // s = 3.36359
    {0.1112497, 0.0283044, 0.0132399, 0.0805653, 0.0255793, 0.0134083},      // s = 4
    {0.1125268, 0.0294908, 0.0143414, 0.0817990, 0.0267260, 0.0144735},      // s = 4.75683
    {0.1136923, 0.0305871, 0.0153721, 0.0829312, 0.0277913, 0.0154755},      // s = 5.65685
    {0.1147568, 0.0315986, 0.0163330, 0.0839700, 0.0287787, 0.0164137},      // s = 6.72717
    {0.1157297, 0.0325309, 0.0172263, 0.0849231, 0.0296922, 0.0172892},      // s = 8
    {0.1166193, 0.0333895, 0.0180548, 0.0857976, 0.0305362, 0.0181036},      // s = 9.51366
    {0.1174332, 0.0341795, 0.0188215, 0.0865997, 0.0313149, 0.0188595},      // s = 11.3137
    {0.1181781, 0.0349060, 0.0195301, 0.0873355, 0.0320326, 0.0195595},      // s = 13.4543
    {0.1188598, 0.0355737, 0.0201839, 0.0880104, 0.0326935, 0.0202067},      // s = 16
};
constexpr double kSelfPressure[6] = {0.1049207, 0.0250662, 0.0116129,
                                     0.0146296, 0.0074169, 0.0048863};

}  // namespace

SelfVelocity selfVelocityFromConfig(const Config& cfg) {
  const std::string name = cfg.string("coupling.self_velocity");
  if (name == "none") return SelfVelocity::None;
  if (name != "stokeslet")
    throw ConfigError("coupling.self_velocity", "unknown correction '" + name + "'");
  if (cfg.string("coupling.kernel") != "trilinear")
    throw ConfigError(
        "coupling.self_velocity",
        "the stokeslet correction is derived for the trilinear kernel (coupling.kernel "
        "is '" +
            cfg.string("coupling.kernel") + "')");
  if (cfg.integer("coupling.smoothing_passes") != 0)
    throw ConfigError("coupling.self_velocity",
                      "the stokeslet correction is derived without smoothing (set "
                      "coupling.smoothing_passes to 0)");
  const GlobalGrid g = gridFromConfig(cfg);
  const double h0 = g.spacing(0);
  for (int d = 1; d < 3; ++d)
    if (std::abs(g.spacing(d) - h0) > 1e-9 * h0)
      throw ConfigError("coupling.self_velocity",
                        "the stokeslet correction is derived for cubic cells (domain.length / "
                        "domain.cells differ between axes)");
  return SelfVelocity::Stokeslet;
}

std::array<double, 3> selfResponse(const std::array<double, 3>& t) {
  // Per axis, the pair weights of the stencil: offset 0 with (1-t)^2 + t^2, offset 1 with
  // 2 t (1-t) (both signs; the Green's function is even in each offset for a == b).
  double w[3][2];
  for (int d = 0; d < 3; ++d) {
    w[d][0] = (1.0 - t[d]) * (1.0 - t[d]) + t[d] * t[d];
    w[d][1] = 2.0 * t[d] * (1.0 - t[d]);
  }
  std::array<double, 3> r{};
  for (int a = 0; a < 3; ++a) {
    const int b = (a + 1) % 3, c = (a + 2) % 3;
    double s = 0;
    for (int oa = 0; oa < 2; ++oa)
      for (int ob = 0; ob < 2; ++ob)
        for (int oc = 0; oc < 2; ++oc) s += w[a][oa] * w[b][ob] * w[c][oc] * kSelfGreen[oa][ob][oc];
    r[a] = s;
  }
  return r;
}

double equivalentWidth(double r) {
  // Gaussian force density exp(-x^2 / (2 sigma^2)) / (2 pi sigma^2)^{3/2}: the Stokes velocity at
  // its centre is F (2/3) / ((2 pi)^{3/2} mu sigma) (the isotropic projection keeps 2/3).
  constexpr double pi = std::numbers::pi;
  return (2.0 / 3.0) / (std::pow(2.0 * pi, 1.5) * r);
}

double buildUp(double sigma, double nu, double t) {
  if (t <= 0) return 0.0;
  return 1.0 - sigma / std::sqrt(sigma * sigma + 2.0 * nu * t);
}

double discreteGreen(int along, int across1, int across2, double s) {
  const int o = 3 * along + across1 + across2;
  if (!(s > 0)) return 0.0;
  const double x = (std::log2(s) - kBuildLog2First) / kBuildLog2Step;
  if (x <= 0) return kGreenBuild[0][o] * s / std::exp2(kBuildLog2First);  // linear from t = 0
  if (x >= kBuildCount - 1) {
    // The free-space tail: the deficit falls as (2/3) / (4 pi^{3/2} sqrt(s)) (docs).
    const double sLast = std::exp2(kBuildLog2First + kBuildLog2Step * (kBuildCount - 1));
    const double steady = kSelfGreen[along][across1][across2];
    return steady - (steady - kGreenBuild[kBuildCount - 1][o]) * std::sqrt(sLast / s);
  }
  const int k = static_cast<int>(x);
  const double f = x - k;
  return (1.0 - f) * kGreenBuild[k][o] + f * kGreenBuild[k + 1][o];
}

double discretePressure(int along, int across1, int across2) {
  return kSelfPressure[3 * along + across1 + across2];
}

SelfResponse selfMobility(const std::array<double, 3>& t, const std::array<double, 3>& dir,
                          double h, double mu, double nu, double eps, double tRun, double betaEff) {
  // The 8 stencil cells o (bit d: the upper cell along axis d) and their weights.
  std::array<double, 8> w{};
  for (int o = 0; o < 8; ++o) {
    w[o] = 1.0;
    for (int d = 0; d < 3; ++d) w[o] *= (o >> d & 1) ? t[d] : 1.0 - t[d];
  }
  const double s = nu * tRun / (h * h);
  const double b = betaEff / (mu * h * eps);  // beta_eff in units of mu h eps
  // The 6 distinct offsets (along, across1 + across2) at this time, once per call.
  double g6[6];
  for (int o = 0; o < 6; ++o) g6[o] = discreteGreen(o / 3, o % 3 > 0 ? 1 : 0, o % 3 > 1 ? 1 : 0, s);
  SelfResponse out{};
  for (int a = 0; a < 3; ++a) {
    const int b1 = (a + 1) % 3, b2 = (a + 2) % 3;
    // G between stencil cells o and o' (offsets 0 or 1 per axis) and the pressure response.
    double G[8][8], Q[8][8];
    for (int o = 0; o < 8; ++o)
      for (int q = 0; q < 8; ++q) {
        const int x = o ^ q, oa = x >> a & 1, o1 = x >> b1 & 1, o2 = x >> b2 & 1;
        G[o][q] = g6[3 * oa + o1 + o2];
        Q[o][q] = kSelfPressure[3 * oa + o1 + o2];
      }
    // The fluid takes the drag implicitly: cell o receives beta_eff w_o (U - v~ - delta_o), its
    // own disturbance delta_o lowers it. Per unit undisturbed slip, delta = b y with
    // (I + b G W) y = G w (Gaussian elimination; the matrix is I plus a small positive part).
    double A[8][9];
    for (int o = 0; o < 8; ++o) {
      double rhs = 0;
      for (int q = 0; q < 8; ++q) {
        A[o][q] = (o == q ? 1.0 : 0.0) + b * G[o][q] * w[q];
        rhs += G[o][q] * w[q];
      }
      A[o][8] = rhs;
    }
    for (int p = 0; p < 8; ++p)
      for (int r = p + 1; r < 8; ++r) {
        const double m = A[r][p] / A[p][p];
        for (int c = p; c < 9; ++c) A[r][c] -= m * A[p][c];
      }
    std::array<double, 8> y{};
    for (int p = 7; p >= 0; --p) {
      double v = A[p][8];
      for (int c = p + 1; c < 8; ++c) v -= A[p][c] * y[c];
      y[p] = v / A[p][p];
    }
    // The particle reads u_at = U - b w.y (per unit slip) and receives F = beta_eff (1 - b w.y):
    // c = (w.y) / (mu h eps (1 - b w.y)). The force's irrotational part, distributed as
    // w_o (1 - b y_o), is read back through the pressure gradient.
    double wy = 0, wqf = 0;
    for (int o = 0; o < 8; ++o) {
      wy += w[o] * y[o];
      for (int q = 0; q < 8; ++q) wqf += w[o] * Q[o][q] * w[q] * (1.0 - b * y[q]);
    }
    const double share = 1.0 - b * wy;
    out.mobility += dir[a] * dir[a] * wy / (mu * h * eps * share);
    out.pressure[a] = wqf / (h * h * h * eps * share);
  }
  return out;
}

}  // namespace coloc::coupling
