// Binary collisions against the references of docs/dem.md:
//  - head-on sphere-sphere and sphere-wall: restitution within 1 % of e = 0.9 and 0.5 (Hertz
//    with LIGGGHTS damping, and the linear spring-dashpot), Hertz contact duration within 3 % of
//    t_c = 2.87 (m*^2 / (R* E*^2 v))^(1/5) in the elastic case (Johnson, Contact Mechanics, 1985);
//  - a sphere sliding on a wall with friction mu: deceleration mu g, pure rolling at 5/7 of the
//    initial speed (classic rigid-body result), both within 2 %.
#include <gtest/gtest.h>

#include <cmath>
#include <sstream>

#include "dem_test_util.hpp"

namespace {

constexpr double kR = 0.01, kRho = 2500, kE = 1e7, kNu = 0.3, kV = 1.0;

std::string material(double e, double mu) {
  std::ostringstream os;
  os << "{\"density\": " << kRho << ", \"young\": " << kE << ", \"poisson\": " << kNu
     << ", \"restitution\": " << e << ", \"friction\": " << mu << "}";
  return os.str();
}

struct Impact {
  double restitution = 0, duration = 0;
};

/// Two spheres (pair) or one sphere and the low-z wall, approaching at relative speed kV.
Impact collide(bool wall, double e, const std::string& model = "hertz_mindlin") {
  // Hertz: t_c ~ 2.0e-3 s (200 steps). Linear (k_n = 2e4 N/m): t_c = pi sqrt(m*/k_n) ~ 1.6e-3 s;
  // its damping force jumps at first touch, so the error is first order in dt: 800 steps.
  const double dt = model == "linear" ? 2e-6 : 1e-5;
  std::ostringstream c;
  c << "{\"domain\": {\"length\": [0.2, 0.2, 0.2], \"cells\": [4, 4, 4]},"
    << " \"particles\": {\"dt\": " << dt << ", \"contact_model\": \"" << model << "\","
    << " \"linear\": {\"kn\": 2e4}, \"walls\": " << (wall ? "true" : "false") << ","
    << " \"materials\": [" << material(e, 0.0) << "], \"sources\": [{\"type\": \"list\", ";
  if (wall)
    c << "\"positions\": [0.1, 0.1, 0.0105], \"radius\": " << kR << ", \"velocity\": [0, 0, " << -kV
      << "]}]}}";
  else
    c << "\"positions\": [0.0895, 0.1, 0.1, 0.1105, 0.1, 0.1], \"radius\": " << kR
      << ", \"velocities\": [" << 0.5 * kV << ", 0, 0, " << -0.5 * kV << ", 0, 0]}]}}";
  demtest::Case run(c.str());
  auto& p = run.p();
  // gap(t): surface distance; contact while gap < 0. Crossing times by linear interpolation.
  const auto gap = [&] {
    if (wall) return p.x[2][0] - kR;
    return std::fabs(p.x[0][1] - p.x[0][0]) - 2 * kR;
  };
  const auto relVel = [&] { return wall ? -p.v[2][0] : p.v[0][0] - p.v[0][1]; };
  double t0 = -1, t1 = -1, prev = gap();
  for (int step = 0; step < 10000 && t1 < 0; ++step) {
    run.dem->substep();
    const double gnow = gap(), t = run.dem->time();
    if (t0 < 0 && prev >= 0 && gnow < 0) t0 = t - dt * gnow / (gnow - prev);
    if (t0 >= 0 && prev < 0 && gnow >= 0) t1 = t - dt * gnow / (gnow - prev);
    prev = gnow;
  }
  EXPECT_GT(t0, 0.0);
  EXPECT_GT(t1, t0);
  for (int step = 0; step < 10; ++step) run.dem->substep();  // well clear of the contact
  return {-relVel() / kV, t1 - t0};                          // rebound speed / impact speed
}

double mass() {
  return kRho * 4.0 / 3.0 * M_PI * kR * kR * kR;
}
double estar() {
  return 1.0 / (2 * (1 - kNu * kNu) / kE);
}

TEST(DemContact, SphereSphereRestitution) {
  for (double e : {0.9, 0.5}) {
    const auto r = collide(false, e);
    std::printf("sphere-sphere hertz e=%.2f: measured %.5f\n", e, r.restitution);
    EXPECT_NEAR(r.restitution, e, 0.01 * e);  // reference e, tolerance 1 %
  }
}

TEST(DemContact, SphereWallRestitution) {
  for (double e : {0.9, 0.5}) {
    const auto r = collide(true, e);
    std::printf("sphere-wall hertz e=%.2f: measured %.5f\n", e, r.restitution);
    EXPECT_NEAR(r.restitution, e, 0.01 * e);
  }
}

TEST(DemContact, LinearRestitution) {
  for (double e : {0.9, 0.5}) {
    const auto a = collide(false, e, "linear");
    const auto b = collide(true, e, "linear");
    std::printf("linear e=%.2f: sphere-sphere %.5f sphere-wall %.5f\n", e, a.restitution,
                b.restitution);
    EXPECT_NEAR(a.restitution, e, 0.01 * e);
    EXPECT_NEAR(b.restitution, e, 0.01 * e);
  }
}

TEST(DemContact, HertzDurationElastic) {
  // sphere-sphere: m* = m/2, R* = R/2, E* = E/(2(1-nu^2)); sphere-wall (same material):
  // m* = m, R* = R, E* the same.
  const double m = mass(), Es = estar();
  const double tPair = 2.87 * std::pow((m / 2) * (m / 2) / ((kR / 2) * Es * Es * kV), 0.2);
  const double tWall = 2.87 * std::pow(m * m / (kR * Es * Es * kV), 0.2);
  const auto a = collide(false, 1.0);
  const auto b = collide(true, 1.0);
  std::printf("elastic: pair t=%.6e (ref %.6e) e=%.6f, wall t=%.6e (ref %.6e) e=%.6f\n", a.duration,
              tPair, a.restitution, b.duration, tWall, b.restitution);
  EXPECT_NEAR(a.duration, tPair, 0.03 * tPair);  // tolerance 3 %
  EXPECT_NEAR(b.duration, tWall, 0.03 * tWall);
  EXPECT_NEAR(a.restitution, 1.0, 1e-3);
  EXPECT_NEAR(b.restitution, 1.0, 1e-3);
}

TEST(DemContact, SlidingSphereRolls) {
  // A sphere on the floor under gravity, released with v0 along x and no spin: while it slides,
  // dv/dt = -mu g; it rolls without slipping from v = 5/7 v0 on (t = 2 v0 / (7 mu g)).
  const double r = 0.005, mu = 0.3, g = 9.81, v0 = 0.5, dt = 2e-5;
  const double m = kRho * 4.0 / 3.0 * M_PI * r * r * r;
  const double Es = estar();
  const double delta = std::pow(3 * m * g / (4 * Es * std::sqrt(r)), 2.0 / 3.0);  // static overlap
  std::ostringstream c;
  c << "{\"gravity\": [0, 0, " << -g << "], \"domain\": {\"length\": [0.2, 0.04, 0.04], "
    << "\"cells\": [10, 2, 2]}, \"particles\": {\"dt\": " << dt << ", \"materials\": ["
    << material(0.5, mu) << "], \"sources\": [{\"type\": \"list\", \"positions\": [0.02, 0.02, "
    << r - delta << "], \"radius\": " << r << "}]}}";
  demtest::Case run(c.str());
  auto& p = run.p();
  for (int s = 0; s < 2500; ++s) run.dem->substep();  // settle on the floor (damped, e = 0.5)
  ASSERT_LT(std::fabs(p.v[2][0]), 1e-6);
  p.v[0][0] = v0;
  const double tRoll = 2 * v0 / (7 * mu * g);
  const int nRoll = static_cast<int>(tRoll / dt);
  // least-squares slope of v_x(t) over the sliding phase [0.1, 0.9] t_roll
  double st = 0, sv = 0, stt = 0, stv = 0, n = 0;
  for (int s = 1; s <= 2 * nRoll; ++s) {
    run.dem->substep();
    if (s > nRoll / 10 && s < 9 * nRoll / 10) {
      const double t = s * dt, v = p.v[0][0];
      st += t, sv += v, stt += t * t, stv += t * v, n += 1;
    }
  }
  const double slope = (n * stv - st * sv) / (n * stt - st * st);
  const double vEnd = p.v[0][0], rollEnd = p.omega[1][0] * r;
  std::printf("sliding: deceleration %.5f (ref %.5f), final v %.6f (ref %.6f), omega r %.6f\n",
              -slope, mu * g, vEnd, 5.0 / 7.0 * v0, rollEnd);
  EXPECT_NEAR(-slope, mu * g, 0.02 * mu * g);                // tolerance 2 %
  EXPECT_NEAR(vEnd, 5.0 / 7.0 * v0, 0.02 * 5.0 / 7.0 * v0);  // tolerance 2 %
  EXPECT_NEAR(rollEnd, vEnd, 0.02 * vEnd);                   // rolling without slip
}

TEST(DemContact, RollingResistanceDecelerates) {
  // A sphere rolling without slip on the floor with rolling resistance mu_r (constant directional
  // torque mu_r R* |F_n|, R* = r, |F_n| = m g): T/r = (m + I/r^2) a gives a = 5/7 mu_r g.
  const double r = 0.005, mu = 0.5, muR = 0.1, g = 9.81, v0 = 0.5, dt = 2e-5;
  const double m = kRho * 4.0 / 3.0 * M_PI * r * r * r;
  const double delta = std::pow(3 * m * g / (4 * estar() * std::sqrt(r)), 2.0 / 3.0);
  std::ostringstream c;
  c << "{\"gravity\": [0, 0, " << -g << "], \"domain\": {\"length\": [0.2, 0.04, 0.04], "
    << "\"cells\": [10, 2, 2]}, \"particles\": {\"dt\": " << dt
    << ", \"materials\": [{\"density\": " << kRho << ", \"young\": " << kE
    << ", \"poisson\": " << kNu << ", \"restitution\": 0.5, \"friction\": " << mu
    << ", \"rolling_friction\": " << muR << "}], \"sources\": [{\"type\": \"list\", "
    << "\"positions\": [0.02, 0.02, " << r - delta << "], \"radius\": " << r << "}]}}";
  demtest::Case run(c.str());
  auto& p = run.p();
  for (int s = 0; s < 2500; ++s) run.dem->substep();
  ASSERT_LT(std::fabs(p.v[2][0]), 1e-6);
  p.v[0][0] = v0;
  p.omega[1][0] = v0 / r;  // rolling without slip
  double st = 0, sv = 0, stt = 0, stv = 0, n = 0;
  for (int s = 1; s <= 5000; ++s) {
    run.dem->substep();
    if (s > 500) {
      const double t = s * dt, v = p.v[0][0];
      st += t, sv += v, stt += t * t, stv += t * v, n += 1;
    }
  }
  const double slope = (n * stv - st * sv) / (n * stt - st * st);
  const double ref = 5.0 / 7.0 * muR * g;
  std::printf("rolling resistance: deceleration %.5f (ref %.5f), omega r / v %.6f\n", -slope, ref,
              p.omega[1][0] * r / p.v[0][0]);
  EXPECT_NEAR(-slope, ref, 0.02 * ref);  // tolerance 2 %
  EXPECT_NEAR(p.omega[1][0] * r, p.v[0][0], 0.02 * p.v[0][0]);
}

}  // namespace
