// Primitive shapes: inside tests agree with their volumes, mass properties with closed forms.
#include <gtest/gtest.h>

#include <numbers>
#include <random>

#include "geometry/shapes.h"

namespace magbake::geometry {
namespace {

// Monte Carlo volume from the inside test (fixed seed: deterministic).
double sampled_volume(const Shape& s, int n) {
  std::mt19937 rng(17);
  const Box3 b = s.bounds();
  std::uniform_real_distribution<double> u(0, 1);
  int in = 0;
  for (int i = 0; i < n; ++i) {
    const Vec3 p = b.min() + b.sizes().cwiseProduct(Vec3(u(rng), u(rng), u(rng)));
    in += s.contains(p);
  }
  return b.volume() * in / n;
}

TEST(Shapes, InsideTestsAgreeWithExactVolumes) {
  const BoxShape box(Vec3(0.01, 0.02, 0.03));
  const SphereShape sphere(0.004);
  const CylinderShape cyl(0.002, 0.01);
  const TorusShape torus(0.01, 0.003);
  const double pi = std::numbers::pi;
  EXPECT_DOUBLE_EQ(box.volume(), 6e-6);
  EXPECT_DOUBLE_EQ(sphere.volume(), 4.0 / 3.0 * pi * 6.4e-8);
  EXPECT_DOUBLE_EQ(cyl.volume(), pi * 4e-6 * 0.01);
  EXPECT_DOUBLE_EQ(torus.volume(), 2 * pi * pi * 0.01 * 9e-6);
  for (const Shape* s : std::initializer_list<const Shape*>{&box, &sphere, &cyl, &torus}) {
    EXPECT_NEAR(sampled_volume(*s, 200000), s->volume(), 0.01 * s->volume());
  }
}

TEST(Shapes, SurfacePointsCountAsInside) {
  EXPECT_TRUE(BoxShape(Vec3(2, 2, 2)).contains(Vec3(1, 1, 1)));
  EXPECT_TRUE(CylinderShape(1, 2).contains(Vec3(1, 0, 1)));
  EXPECT_TRUE(SphereShape(1).contains(Vec3(0, 0, 1)));
  EXPECT_FALSE(SphereShape(1).contains(Vec3(0, 0, 1.000001)));
  EXPECT_TRUE(TorusShape(2, 0.5).contains(Vec3(2.5, 0, 0)));
  EXPECT_FALSE(TorusShape(2, 0.5).contains(Vec3(0, 0, 0)));
}

TEST(Shapes, MassPropertiesMatchClosedForms) {
  const MassProperties b = BoxShape(Vec3(1, 2, 3)).mass_properties();
  EXPECT_DOUBLE_EQ(b.inertia(0, 0), 6.0 * (4 + 9) / 12);
  EXPECT_DOUBLE_EQ(b.inertia(2, 2), 6.0 * (1 + 4) / 12);
  const MassProperties s = SphereShape(2).mass_properties();
  EXPECT_DOUBLE_EQ(s.inertia(1, 1), 0.4 * s.volume * 4);
  const MassProperties c = CylinderShape(1, 3).mass_properties();
  EXPECT_DOUBLE_EQ(c.inertia(2, 2), 0.5 * c.volume);
  EXPECT_DOUBLE_EQ(c.inertia(0, 0), c.volume * (3 + 9) / 12.0);
}

}  // namespace
}  // namespace magbake::geometry
