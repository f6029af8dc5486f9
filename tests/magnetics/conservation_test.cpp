// Total force and angular momentum vanish to round-off for random scenes at any theta
// (physics-notes §3): every interaction is applied with opposite signs to both bodies.
#include <gtest/gtest.h>

#include <random>

#include "support/scenes.h"

namespace magbake::testing {
namespace {

using namespace magnetics;

struct Case {
  double theta;
  KernelPrecision precision;
  InductionMode induction;
  double near;
};

void build_random_scene(Rig& s, std::mt19937& rng, bool touching) {
  std::uniform_real_distribution<double> u(-1, 1), size(0.003, 0.012);
  std::normal_distribution<double> n;
  for (int b = 0; b < 7; ++b) {
    std::unique_ptr<geometry::Shape> shape;
    switch (b % 4) {
      case 0: shape = std::make_unique<geometry::BoxShape>(Vec3(size(rng), size(rng), size(rng))); break;
      case 1: shape = std::make_unique<geometry::SphereShape>(0.5 * size(rng)); break;
      case 2: shape = std::make_unique<geometry::CylinderShape>(0.4 * size(rng), size(rng)); break;
      default: shape = std::make_unique<geometry::TorusShape>(0.6 * size(rng), 0.2 * size(rng)); break;
    }
    Material mat;
    switch (b % 5) {
      case 0:
      case 3: mat = permanent(0.5 + std::abs(u(rng)), Vec3(n(rng), n(rng), n(rng))); break;
      case 1: mat = linear(700); break;
      case 2: mat = linear(-1); break;
      default: mat = linear(-1e-5); break;
    }
    s.add(std::move(shape), mat);
  }
  s.build(0.0015, 16);
  for (int b = 0; b < 7; ++b) {
    // On a 2.5 cm lattice (no overlap), or packed at 1.3 cm so some bodies touch or interpenetrate.
    const double pitch = touching ? 0.013 : 0.025;
    s.state.body_pose[b].position = Vec3(pitch * (b % 3), pitch * ((b / 3) % 3), 0.3 * pitch * u(rng)) +
                                    Vec3(0.5, -0.2, 0.1);  // away from the origin on purpose
    s.state.body_pose[b].rotation = Quat(Eigen::AngleAxisd(3 * u(rng), Vec3(n(rng), n(rng), n(rng)).normalized()));
  }
  if (touching) {
    // Boxes 0 and 4 face to face, in contact, same orientation.
    const auto* b0 = static_cast<const geometry::BoxShape*>(s.shapes[0].get());
    const auto* b4 = static_cast<const geometry::BoxShape*>(s.shapes[4].get());
    s.state.body_pose[4].rotation = s.state.body_pose[0].rotation;
    s.state.body_pose[4].position =
        s.state.body_pose[0].position + s.state.body_pose[0].rotation * Vec3(b0->half()[0] + b4->half()[0], 0.001, 0);
  }
}

TEST(Conservation, TotalForceAndAngularMomentumVanishAtAnyTheta) {
  const Case cases[] = {
      {0.0, KernelPrecision::kDouble, InductionMode::kCoupled, 2.5},
      {0.3, KernelPrecision::kSingle, InductionMode::kCoupled, 2.5},
      {0.6, KernelPrecision::kSingle, InductionMode::kPaper, 1.5},
      {1.0, KernelPrecision::kSingle, InductionMode::kCoupled, 0.0},
      {0.5, KernelPrecision::kDouble, InductionMode::kOff, 2.5},
  };
  for (bool touching : {false, true}) {
    std::mt19937 rng(touching ? 5 : 9);
    Rig s;
    build_random_scene(s, rng, touching);
    for (const Case& c : cases) {
      Settings st;
      st.theta = c.theta;
      st.precision = c.precision;
      st.induction = c.induction;
      st.near_field = c.near;
      Result r;
      evaluate(s.model, st, s.state, r);
      Vec3 F = Vec3::Zero(), L = Vec3::Zero();
      double fmax = 0, lmax = 0;
      for (int b = 0; b < s.model.body_count; ++b) {
        const Vec3 R = s.state.body_pose[b].position;
        F += r.force[b];
        L += R.cross(r.force[b]) + r.torque[b];
        fmax = std::max(fmax, r.force[b].norm());
        lmax = std::max({lmax, R.cross(r.force[b]).norm(), r.torque[b].norm()});
      }
      ASSERT_GT(fmax, 0.0);
      EXPECT_LT(F.norm(), 1e-12 * fmax) << "theta " << c.theta << " touching " << touching;
      EXPECT_LT(L.norm(), 1e-12 * lmax) << "theta " << c.theta << " touching " << touching;
      if (touching && c.near > 0 && c.induction != InductionMode::kOff) {
        EXPECT_GT(r.stats.near_pairs, 0);
      }
      std::printf("touching %d theta %.1f: induction %d iterations, residual %.1e, near pairs %lld\n", touching,
                  c.theta, r.induction.iterations, r.induction.residual, (long long)r.stats.near_pairs);
      if (c.induction == InductionMode::kCoupled) {
        EXPECT_TRUE(r.induction.converged) << r.induction.residual;
      }
    }
  }
}

}  // namespace
}  // namespace magbake::testing
