// The surface-charge field of a uniformly magnetized polyhedron (surface_charge.h) against the
// closed-form cuboid field (cuboid.h, an independent formula: corner sums of atan and log), and
// the triangle integral against brute-force quadrature.
#include <gtest/gtest.h>

#include <numbers>
#include <random>

#include "magnetics/cuboid.h"
#include "magnetics/surface_charge.h"
#include "support/random.h"

namespace magbake::testing {
namespace {

using namespace magnetics;

// The 12 triangles of a box of half-edges h, outward, 3 corners each, and their charge M . n.
void box_surface(const Vec3& h, const Vec3& M, std::vector<Vec3>& v, std::vector<double>& sigma) {
  Vec3 c[8];
  for (int i = 0; i < 8; ++i) c[i] = Vec3((i & 1 ? 1 : -1) * h[0], (i & 2 ? 1 : -1) * h[1], (i & 4 ? 1 : -1) * h[2]);
  const int f[12][3] = {{0, 2, 1}, {1, 2, 3}, {4, 5, 6}, {5, 7, 6}, {0, 1, 4}, {1, 5, 4},
                        {2, 6, 3}, {3, 6, 7}, {0, 4, 2}, {2, 4, 6}, {1, 3, 5}, {3, 7, 5}};
  for (const auto& t : f) {
    for (int k = 0; k < 3; ++k) v.push_back(c[t[k]]);
    const Vec3 n = (c[t[1]] - c[t[0]]).cross(c[t[2]] - c[t[0]]).normalized();
    sigma.push_back(M.dot(n));
  }
}

TEST(SurfaceCharge, ABoxFromTwelveTrianglesIsTheClosedFormCuboidInsideAndOut) {
  const Vec3 h(0.004, 0.0025, 0.006);
  const Vec3 M = 1.0e6 * Vec3(0.3, -0.8, 0.5).normalized();
  std::vector<Vec3> v;
  std::vector<double> sigma;
  box_surface(h, M, v, sigma);
  std::mt19937 rng(12);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  int inside = 0;
  for (int k = 0; k < 400; ++k) {
    // Points from deep inside to 5 box sizes away, many within 0.1 mm of a face.
    Vec3 x = Vec3(u(rng), u(rng), u(rng)).cwiseProduct(h) * (k % 4 == 0 ? 5.0 : 1.05);
    const Vec3 ref = cuboid_b_field(h, M, x);
    const Vec3 B = surface_b_field(v.data(), sigma.data(), 12, M, x);
    EXPECT_LT((B - ref).norm(), 1e-10 * ref.norm() + 1e-14) << x.transpose();
    inside += (x.cwiseAbs() - h).maxCoeff() < 0;
  }
  EXPECT_GT(inside, 100);  // the inside branch (mu0 M added) was exercised
}

TEST(SurfaceCharge, TriangleIntegralMatchesQuadrature) {
  const Vec3 a(0, 0, 0), b(0.003, 0.0005, 0), c(0.001, 0.002, 0.0004);
  const Vec3 n = (b - a).cross(c - a);
  const double area = 0.5 * n.norm();
  for (const Vec3& x : {Vec3(0.001, 0.0008, 0.002), Vec3(-0.002, 0.001, -0.0005), Vec3(0.004, 0.003, 0.001)}) {
    // Midpoint rule on a fine barycentric grid (N^2 sub-triangles of equal area).
    constexpr int N = 400;
    Vec3 ref = Vec3::Zero();
    for (int i = 0; i < N; ++i) {
      for (int j = 0; i + j < N; ++j) {
        for (int up = 0; up < (i + j < N - 1 ? 2 : 1); ++up) {
          const double s = (i + (up ? 2.0 : 1.0) / 3.0) / N, t = (j + (up ? 2.0 : 1.0) / 3.0) / N;
          const Vec3 y = a + s * (b - a) + t * (c - a);
          const Vec3 r = x - y;
          ref += r / std::pow(r.norm(), 3);
        }
      }
    }
    ref *= area / (double(N) * N);
    EXPECT_LT((triangle_field(x, a, b, c) - ref).norm(), 1e-4 * ref.norm()) << x.transpose();
  }
}

// A box, and beside it a prism on an n-gon (a tessellated cylinder) whose caps are fans from
// their centres: one closed triangle soup of two surfaces, magnetization M.
void box_and_prism(const Vec3& M, int n, std::vector<Vec3>& v, std::vector<double>& sigma) {
  box_surface(Vec3(0.002, 0.003, 0.001), M, v, sigma);
  const double r = 0.004, h = 0.006;
  std::vector<Vec3> prism;
  for (int i = 0; i < n; ++i) {
    const double a0 = 2 * std::numbers::pi * i / n, a1 = 2 * std::numbers::pi * ((i + 1) % n) / n;
    const Vec3 p0(r * std::cos(a0), r * std::sin(a0), 0), p1(r * std::cos(a1), r * std::sin(a1), 0), up(0, 0, h);
    const Vec3 c0(0, 0, 0);
    for (const Vec3& q : {p0, p1, Vec3(p1 + up), p0, Vec3(p1 + up), Vec3(p0 + up), c0, p1, p0, Vec3(c0 + up), Vec3(p0 + up), Vec3(p1 + up)}) {
      prism.push_back(q + Vec3(0.01, 0, 0));  // beside the box: one soup, two closed surfaces
    }
  }
  for (std::size_t t = 0; t < prism.size() / 3; ++t) {
    v.insert(v.end(), prism.begin() + 3 * t, prism.begin() + 3 * t + 3);
    sigma.push_back(M.dot((prism[3 * t + 1] - prism[3 * t]).cross(prism[3 * t + 2] - prism[3 * t]).normalized()));
  }
}

TEST(SurfaceCharge, ThePreparedMeshIsTheTriangleSoupToRounding) {
  // A box, and a prism on a 40-gon (a tessellated cylinder): shared corners and edges give the
  // same field as triangle by triangle, inside and out.
  const Vec3 M = 9.0e5 * Vec3(0.6, 0.0, 0.8);
  std::vector<Vec3> v;
  std::vector<double> sigma;
  const int n = 40;
  box_and_prism(M, n, v, sigma);
  const Vec3 prism0 = v[36], prism1 = v[37];  // the prism's first side edge
  const int ntri = static_cast<int>(sigma.size());
  SurfaceMesh mesh;
  ASSERT_TRUE(mesh.build(v.data(), sigma.data(), ntri, M));
  EXPECT_EQ(mesh.face.size(), std::size_t(ntri));
  // Box: 6 faces of 2 triangles, 12 edges (the 6 diagonals weigh nothing). Prism: 2 caps and 40
  // side quads; 3 x 40 edges (the spokes and the quads' diagonals weigh nothing).
  EXPECT_EQ(mesh.group_begin.size(), std::size_t(6 + 2 + n + 1));
  EXPECT_EQ(mesh.edge.size(), std::size_t(12 + 3 * n));
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> u(-0.006, 0.016);
  std::vector<double> scratch;
  for (int k = 0; k < 300; ++k) {
    const Vec3 x(u(rng), 0.5 * u(rng), 0.5 * u(rng));
    const Vec3 ref = surface_b_field(v.data(), sigma.data(), ntri, M, x);
    EXPECT_LT((mesh.b_field(x, scratch) - ref).norm(), 1e-12 * ref.norm() + 1e-15) << x.transpose();
  }
  // On an edge and on a corner (a voxel grid aligned with a mesh's vertices): finite.
  for (const Vec3& x : {Vec3(0.5 * (v[0] + v[1])), v[0], Vec3(0.5 * (prism0 + prism1))}) {
    EXPECT_TRUE(mesh.b_field(x, scratch).allFinite()) << x.transpose();
  }
  // An open surface is refused.
  SurfaceMesh open;
  EXPECT_FALSE(open.build(v.data(), sigma.data(), ntri - 1, M));
}

TEST(SurfaceCharge, GradientIsTheFieldsDerivative) {
  // The analytic gradient against central differences of b_field (step 1e-4 of the distance to
  // the nearest corner scale: truncation ~1e-8, rounding ~1e-10), inside and out; outside it is
  // symmetric and traceless (curl- and divergence-free), and B agrees with b_field.
  const Vec3 M = 9.0e5 * Vec3(0.6, 0.0, 0.8);
  std::vector<Vec3> v;
  std::vector<double> sigma;
  box_and_prism(M, 40, v, sigma);
  SurfaceMesh mesh;
  ASSERT_TRUE(mesh.build(v.data(), sigma.data(), static_cast<int>(sigma.size()), M));
  std::mt19937 rng(5);
  std::uniform_real_distribution<double> u(-0.006, 0.016);
  std::vector<double> scratch;
  double worst = 0;
  for (int k = 0; k < 300; ++k) {
    const Vec3 x(u(rng), 0.5 * u(rng), 0.5 * u(rng));
    Vec3 B;
    Mat3 G;
    mesh.b_field_gradient(x, scratch, B, G);
    EXPECT_LT((B - mesh.b_field(x, scratch)).norm(), 1e-13 * B.norm() + 1e-16);
    const double h = 2e-7;
    Mat3 fd;
    for (int j = 0; j < 3; ++j) {
      const Vec3 dx = h * Vec3::Unit(j);
      fd.col(j) = (mesh.b_field(x + dx, scratch) - mesh.b_field(x - dx, scratch)) / (2 * h);
    }
    // Skip points within 10 steps of the surface, where a difference straddles it.
    bool straddles = false;
    for (int j = 0; j < 3 && !straddles; ++j) {
      for (double sgn : {-10.0, 10.0}) {
        const Vec3 B1 = mesh.b_field(x + sgn * h * Vec3::Unit(j), scratch);
        straddles = straddles || (B1 - B).norm() > 0.05 * kMu0 * M.norm();
      }
    }
    if (straddles) continue;
    const double scale = G.norm() + 1e-3;
    const double err = (G - fd).norm() / scale;
    worst = std::max(worst, err);
    EXPECT_LT(err, 1e-5) << x.transpose() << "\n" << G << "\n" << fd;
  }
  // Symmetric and traceless everywhere off the surface: H is the gradient of a harmonic
  // potential inside and out, and B = mu0 (H + M) only adds a constant inside.
  for (int k = 0; k < 100; ++k) {
    const Vec3 x(u(rng), 0.5 * u(rng), 0.5 * u(rng));
    Vec3 B;
    Mat3 G;
    mesh.b_field_gradient(x, scratch, B, G);
    EXPECT_LT((G - G.transpose()).norm(), 1e-9 * G.norm()) << x.transpose();
    EXPECT_LT(std::abs(G.trace()), 1e-9 * G.norm()) << x.transpose();
  }
  std::printf("gradient vs central differences: worst %.2e relative\n", worst);
}

}  // namespace
}  // namespace magbake::testing
