// Animated applied fields (scene format 1.1, issue 17 outcome 3): `external_field` as keys
// [{t, B}] (linear, held outside) or {rotating: ...}; bodies feel the field of the instant, and the
// cache records it per frame. Checked against closed forms: the keyed and rotating field itself,
// the lag of a damped magnet dragged round by a rotating field, and the linearity of an induced
// moment along a keyed ramp.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <numbers>
#include <string>

#include "bake_fixture.h"
#include "scene/scene_magnetics.h"

namespace magbake::sim {
namespace {

using magnetics::kMu0;
using magnetics::Vec3;
constexpr double kPi = std::numbers::pi;

TEST(AppliedField, KeysInterpolateLinearlyAndHoldOutsideAndRotatingTurns) {
  const scene::Scene keyed = scene::load_scene_text(
      "magbake: 1.1\nunits: {length: mm, angle: deg}\n"
      "magnetics: {external_field: [{t: 0.5, B: [0, 0, 0.01]}, {t: 1.5, B: [0.02, 0, -0.01]}]}\n",
      "keyed.yaml");
  EXPECT_TRUE(keyed.applied_field_animated());
  EXPECT_EQ(keyed.applied_field(0.0), Vec3(0, 0, 0.01));   // held before the first key
  EXPECT_EQ(keyed.applied_field(0.5), Vec3(0, 0, 0.01));
  EXPECT_LT((keyed.applied_field(1.0) - Vec3(0.01, 0, 0)).norm(), 1e-18);
  EXPECT_LT((keyed.applied_field(1.25) - Vec3(0.015, 0, -0.005)).norm(), 1e-18);
  EXPECT_EQ(keyed.applied_field(9.0), Vec3(0.02, 0, -0.01));  // held after the last
  EXPECT_EQ(keyed.magnetics.external_field, Vec3(0, 0, 0.01));  // the value at t = 0
  const scene::Scene rot = scene::load_scene_text(
      "magbake: 1.1\nunits: {length: mm, angle: deg}\n"
      "magnetics: {external_field: {rotating: {magnitude: 0.002, axis: [0, 0, 2], frequency: 2, from: [1, 0, 1]}}}\n",
      "rotating.yaml");
  for (double t : {0.0, 0.1, 0.125, 0.3, 1.0}) {
    const double a = 2 * kPi * 2 * t;
    const Vec3 want = 0.002 * Vec3(std::cos(a), std::sin(a), 0);  // `from` projected normal to the axis
    EXPECT_LT((rot.applied_field(t) - want).norm(), 1e-15) << t;
  }
  const scene::Scene still = scene::load_scene_text(
      "magbake: 1\nunits: {length: mm, angle: deg}\nmagnetics: {external_field: [0, 1.0e-4, 0]}\n", "still.yaml");
  EXPECT_FALSE(still.applied_field_animated());
  EXPECT_EQ(still.applied_field(3.0), Vec3(0, 1e-4, 0));
}

// A compass needle (N42, 30 x 2 x 1 mm) on a vertical pivot in a 45 µT field turning at 0.5 Hz,
// angular damping d (γ = -ln(1 - d) = 9.2 per second): once its start has died away it turns
// with the field, behind it by the angle where the field's torque carries the drag:
// m B sin δ = γ I Ω, δ = 20.4 degrees here. Measured over the last second of 5 s, within 0.5
// degrees; the cache records the field of every frame.
TEST(AppliedField, AMagnetFollowsARotatingFieldWithTheExpectedLag) {
  const double B = 45e-6, f = 0.5, d = 0.9999;
  const double a = 0.030, b = 0.002, c = 0.001, rho = 7500;
  const double m = 1.3 * a * b * c / kMu0, I = rho * a * b * c * (a * a + b * b) / 12;
  const double gamma = -std::log(1 - d), omega = 2 * kPi * f;
  const double lag = std::asin(gamma * I * omega / (m * B));
  const std::string yaml =
      "magbake: 1.1\nunits: {length: mm, angle: deg}\ntime: {fps: 25, frames: [1, 126], dt: 0.001, sleep: 0}\n"
      "gravity: [0, 0, -9810]\n"
      "magnetics: {external_field: {rotating: {magnitude: 4.5e-5, axis: [0, 0, 1], frequency: 0.5}}}\n"
      "materials: {N42: {kind: permanent, remanence: 1.3, density: 7500}}\n"
      "bodies:\n"
      "  - {name: needle, shape: {box: [30, 2, 1]}, material: N42, magnetization: [1, 0, 0], damping: {angular: 0.9999}}\n"
      "joints:\n"
      "  - {type: hinge, bodies: [needle], pivot: [0, 0, 0], axis: [0, 0, 1]}\n";
  Bake r(yaml);
  double lo = 1e9, hi = -1e9;
  for (int fr = 1; fr <= 125; ++fr) {
    r.sim->advance_frame();
    if (fr <= 100) continue;
    const double t = fr / 25.0;
    const Vec3 x = r.sim->state().orientation[0] * Vec3::UnitX();
    const Vec3 field = r.scene.applied_field(t);
    const double behind = std::atan2(x.cross(field).z(), x.dot(field));  // from the needle to the field
    lo = std::min(lo, behind), hi = std::max(hi, behind);
  }
  std::printf("needle in a field turning at %.1f Hz: %.2f to %.2f degrees behind it, m B sin(lag) = gamma I Omega: %.2f\n", f,
              lo * 180 / kPi, hi * 180 / kPi, lag * 180 / kPi);
  EXPECT_NEAR(lo, lag, 0.5 * kPi / 180);
  EXPECT_NEAR(hi, lag, 0.5 * kPi / 180);
}

// Induced moments follow a keyed field: a soft steel ball (coupled induction) in a field ramped
// linearly between two keys has, halfway, the mean of its moments at the keys (the induction is
// linear in the field), and at the keys the moment of each key's field alone.
TEST(AppliedField, AnInducedMomentFollowsAKeyedRamp) {
  auto moment_at = [](const std::string& field, double t) {
    const scene::Scene s = scene::load_scene_text(
        "magbake: 1.1\nunits: {length: mm, angle: deg}\nmagnetics: {quality: draft, external_field: " + field + "}\n"
        "materials: {steel: {kind: soft, chi: 700, density: 7850}}\n"
        "bodies: [{name: ball, shape: {sphere: {radius: 5}}, material: steel, motion: static}]\n",
        "ramp.yaml");
    const magnetics::Model model = scene::build_magnetics_model(s);
    magnetics::State st;
    st.resize(model);
    scene::set_poses_at(s, t, st);
    magnetics::Settings settings = scene::magnetics_settings(s, t);
    settings.induction_tolerance = 1e-12;
    magnetics::Result res;
    magnetics::evaluate(model, settings, st, res);
    return res.moment[0];
  };
  const std::string ramp = "[{t: 0, B: [0, 0, 0.001]}, {t: 2, B: [0.003, 0, 0.002]}]";
  const Vec3 m0 = moment_at(ramp, 0), m1 = moment_at(ramp, 1), m2 = moment_at(ramp, 2);
  EXPECT_LT((m0 - moment_at("[0, 0, 0.001]", 0)).norm(), 1e-12 * m0.norm());
  EXPECT_LT((m2 - moment_at("[0.003, 0, 0.002]", 0)).norm(), 1e-12 * m2.norm());
  std::printf("steel ball on a ramp: moment halfway %.6g %.6g %.6g A m2, mean of the keys' %.6g %.6g %.6g\n", m1[0], m1[1],
              m1[2], 0.5 * (m0 + m2)[0], 0.5 * (m0 + m2)[1], 0.5 * (m0 + m2)[2]);
  EXPECT_LT((m1 - 0.5 * (m0 + m2)).norm(), 1e-8 * m1.norm());
  EXPECT_GT(m1.norm(), 0);
}

}  // namespace
}  // namespace magbake::sim
