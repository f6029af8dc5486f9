// Closed triangle meshes: closedness check, orientation, mass properties, winding numbers.
#include <gtest/gtest.h>

#include <numbers>
#include <random>

#include "geometry/shapes.h"

namespace magbake::geometry {
namespace {

// Unit-edge cube centred at c with outward triangles; `drop` removes a triangle.
void cube(std::vector<Vec3>& v, std::vector<Eigen::Vector3i>& t, const Vec3& c = Vec3::Zero(), double s = 1.0) {
  const int base = static_cast<int>(v.size());
  for (int i = 0; i < 8; ++i) v.push_back(c + s * Vec3((i & 1) - 0.5, ((i >> 1) & 1) - 0.5, ((i >> 2) & 1) - 0.5));
  const int f[12][3] = {{0, 2, 1}, {1, 2, 3}, {4, 5, 6}, {5, 7, 6}, {0, 1, 4}, {1, 5, 4},
                        {2, 6, 3}, {3, 6, 7}, {0, 4, 2}, {2, 4, 6}, {1, 3, 5}, {3, 7, 5}};
  for (auto& q : f) t.emplace_back(base + q[0], base + q[1], base + q[2]);
}

TEST(Mesh, CubeHasExactVolumeCentroidAndInertia) {
  std::vector<Vec3> v;
  std::vector<Eigen::Vector3i> t;
  cube(v, t, Vec3(1, 2, 3), 2.0);
  const MeshShape m(v, t);
  const MassProperties mp = m.mass_properties();
  EXPECT_NEAR(mp.volume, 8.0, 1e-12);
  EXPECT_LT((mp.centroid - Vec3(1, 2, 3)).norm(), 1e-12);
  EXPECT_NEAR(mp.inertia(0, 0), 8.0 * 8.0 / 12.0, 1e-10);
  EXPECT_NEAR(mp.inertia(0, 1), 0.0, 1e-10);
}

TEST(Mesh, WindingNumberSeparatesInsideFromOutside) {
  std::vector<Vec3> v;
  std::vector<Eigen::Vector3i> t;
  cube(v, t);
  const MeshShape m(v, t);
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> u(-1.5, 1.5);
  for (int i = 0; i < 2000; ++i) {
    const Vec3 p(u(rng), u(rng), u(rng));
    const bool inside = p.cwiseAbs().maxCoeff() < 0.5;
    const double w = m.winding_number(p);
    EXPECT_NEAR(w, inside ? 1.0 : 0.0, 1e-9) << p.transpose();
    EXPECT_EQ(m.contains(p), inside);
  }
}

TEST(Mesh, InsideOutMeshIsFlipped) {
  std::vector<Vec3> v;
  std::vector<Eigen::Vector3i> t;
  cube(v, t);
  for (auto& tri : t) std::swap(tri[1], tri[2]);
  const MeshShape m(v, t);
  EXPECT_NEAR(m.volume(), 1.0, 1e-12);
  EXPECT_TRUE(m.contains(Vec3(0.1, 0.2, -0.3)));
}

TEST(Mesh, OpenMeshIsRejectedWithADiagnosis) {
  std::vector<Vec3> v;
  std::vector<Eigen::Vector3i> t;
  cube(v, t);
  t.pop_back();
  try {
    MeshShape m(v, t);
    FAIL() << "an open mesh was accepted";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("not closed: 3 boundary edges"), std::string::npos) << e.what();
  }
}

TEST(Mesh, DuplicatedVerticesAreWelded) {
  // STL style: three fresh vertices per triangle.
  std::vector<Vec3> v, w;
  std::vector<Eigen::Vector3i> t, u;
  cube(v, t);
  for (const auto& tri : t) {
    const int b = static_cast<int>(w.size());
    for (int k = 0; k < 3; ++k) w.push_back(v[tri[k]]);
    u.emplace_back(b, b + 1, b + 2);
  }
  const MeshShape m(w, u);
  EXPECT_EQ(m.vertices().size(), 8u);
  EXPECT_NEAR(m.volume(), 1.0, 1e-12);
}

}  // namespace
}  // namespace magbake::geometry

namespace magbake::geometry {
namespace {

TEST(TriangleField, MatchesFineQuadrature) {
  const Vec3 a(0, 0, 0), b(1, 0, 0), c(0.3, 0.8, 0);
  for (const Vec3& x : {Vec3(0.3, 0.2, 0.5), Vec3(1.5, -0.4, 0.2), Vec3(0.2, 0.3, -0.3)}) {
    // Midpoint rule on a fine subdivision of the triangle.
    const int n = 400;
    Vec3 ref = Vec3::Zero();
    const double area = 0.5 * (b - a).cross(c - a).norm();
    for (int i = 0; i < n; ++i) {
      for (int j = 0; i + j < n; ++j) {
        for (int up = 0; up < (i + j < n - 1 ? 2 : 1); ++up) {
          const double u = (i + (up ? 2.0 : 1.0) / 3.0) / n, v = (j + (up ? 2.0 : 1.0) / 3.0) / n;
          const Vec3 r = x - (a + u * (b - a) + v * (c - a));
          ref += r / std::pow(r.norm(), 3);
        }
      }
    }
    ref *= area / (double(n) * n);
    EXPECT_LT((triangle_field(x, a, b, c) - ref).norm(), 2e-4 * ref.norm()) << x.transpose();
  }
  // Just above the interior the normal part tends to 2 pi (half the solid angle of a sheet),
  // just below to -2 pi; the in-plane part stays finite.
  const Vec3 above = triangle_field(Vec3(0.4, 0.3, 1e-9), a, b, c);
  const Vec3 below = triangle_field(Vec3(0.4, 0.3, -1e-9), a, b, c);
  EXPECT_NEAR(above[2], 2 * std::numbers::pi, 1e-6);
  EXPECT_NEAR(below[2], -2 * std::numbers::pi, 1e-6);
  EXPECT_LT((above.head<2>() - below.head<2>()).norm(), 1e-6);
}

TEST(DemagTensor, MeshCubeMatchesTheCuboidClosedFormAndTracesToOne) {
  std::vector<Vec3> v;
  std::vector<Eigen::Vector3i> t;
  cube(v, t, Vec3::Zero(), 2.0);
  const MeshShape m(v, t);
  const BoxShape box(Vec3(2, 2, 2));
  for (const Vec3& p : {Vec3(0, 0, 0), Vec3(0.5, 0.2, -0.7), Vec3(0.95, 0.9, 0.99)}) {
    Mat3 Dm, Db;
    ASSERT_TRUE(m.demag_tensor(p, Dm));
    ASSERT_TRUE(box.demag_tensor(p, Db));
    EXPECT_LT((Dm - Db).norm(), 1e-9) << p.transpose();
    EXPECT_NEAR(Db.trace(), 1.0, 1e-9);  // inside: N_xx + N_yy + N_zz = 1
  }
  Mat3 D;
  box.demag_tensor(Vec3::Zero(), D);
  EXPECT_NEAR(D(2, 2), 1.0 / 3.0, 1e-12);
}

TEST(DemagTensor, TessellatedPrimitivesAreAccurate) {
  // Long cylinder: centre demag factors -> (1/2, 1/2, 0); sphere-like torus checks the trace.
  const CylinderShape cyl(0.01, 1.0);
  Mat3 D;
  ASSERT_TRUE(cyl.demag_tensor(Vec3::Zero(), D));
  EXPECT_NEAR(D(0, 0), 0.5, 2e-3);
  EXPECT_NEAR(D(2, 2), 0.0, 2e-3);
  const TorusShape torus(0.02, 0.005);
  ASSERT_TRUE(torus.demag_tensor(Vec3(0.021, 0.001, 0.001), D));
  EXPECT_NEAR(D.trace(), 1.0, 1e-3);
  const SphereShape s(1.0);
  ASSERT_TRUE(s.demag_tensor(Vec3(0.3, 0.2, 0.1), D));
  EXPECT_EQ(D, Mat3::Identity() / 3.0);
}

}  // namespace
}  // namespace magbake::geometry
