#include "shapes.h"

#include <algorithm>
#include <cmath>
#include <numbers>

#include "magnetics/cuboid.h"

namespace magbake::geometry {
namespace {
constexpr double kPi = std::numbers::pi;
constexpr double kTol = 1e-12;  // relative surface tolerance of the inside tests
}  // namespace

bool BoxShape::contains(const Vec3& p) const {
  const double t = kTol * half_.maxCoeff();
  return std::abs(p[0]) <= half_[0] + t && std::abs(p[1]) <= half_[1] + t && std::abs(p[2]) <= half_[2] + t;
}

MassProperties BoxShape::mass_properties() const {
  MassProperties mp;
  mp.volume = volume();
  const Vec3 s = 2.0 * half_;
  mp.inertia.diagonal() << s[1] * s[1] + s[2] * s[2], s[0] * s[0] + s[2] * s[2], s[0] * s[0] + s[1] * s[1];
  mp.inertia *= mp.volume / 12.0;
  return mp;
}

bool BoxShape::demag_tensor(const Vec3& p, Mat3& D) const {
  for (int a = 0; a < 3; ++a) D.col(a) = -magnetics::cuboid_h_field(half_, Vec3::Unit(a), p);
  return true;
}

bool SphereShape::demag_tensor(const Vec3& p, Mat3& D) const {
  if (p.squaredNorm() <= r_ * r_) {
    D = Mat3::Identity() / 3.0;  // uniform inside a sphere
  } else {
    // Outside: the field of the dipole V M.
    const double d2 = p.squaredNorm(), d = std::sqrt(d2);
    D = -(volume() / (4.0 * kPi * d2 * d)) * (3.0 * p * p.transpose() / d2 - Mat3::Identity());
  }
  return true;
}

double SphereShape::volume() const { return 4.0 / 3.0 * kPi * r_ * r_ * r_; }
bool SphereShape::contains(const Vec3& p) const { return p.squaredNorm() <= r_ * r_ * (1.0 + 2 * kTol); }
MassProperties SphereShape::mass_properties() const {
  MassProperties mp;
  mp.volume = volume();
  mp.inertia = Mat3::Identity() * (0.4 * mp.volume * r_ * r_);
  return mp;
}

double CylinderShape::volume() const { return kPi * r_ * r_ * h_; }
bool CylinderShape::contains(const Vec3& p) const {
  const double t = kTol * std::max(r_, h_);
  return p[0] * p[0] + p[1] * p[1] <= (r_ + t) * (r_ + t) && std::abs(p[2]) <= 0.5 * h_ + t;
}
MassProperties CylinderShape::mass_properties() const {
  MassProperties mp;
  mp.volume = volume();
  const double ixx = mp.volume * (3.0 * r_ * r_ + h_ * h_) / 12.0;
  mp.inertia.diagonal() << ixx, ixx, 0.5 * mp.volume * r_ * r_;
  return mp;
}

namespace {

// A prism of height h on the regular n-gon with corners at radius r, axis z, centred: corners
// and outward triangles (caps as fans about their centres).
void prism(double r, double h, int n, std::vector<Vec3>& v, std::vector<Eigen::Vector3i>& t) {
  v.clear();
  t.clear();
  for (int i = 0; i < n; ++i) {
    const double a = 2 * kPi * i / n;
    v.emplace_back(r * std::cos(a), r * std::sin(a), -0.5 * h);
    v.emplace_back(r * std::cos(a), r * std::sin(a), 0.5 * h);
  }
  const int bottom = static_cast<int>(v.size());
  v.emplace_back(0, 0, -0.5 * h);
  v.emplace_back(0, 0, 0.5 * h);
  for (int i = 0; i < n; ++i) {
    const int j = (i + 1) % n;
    t.emplace_back(2 * i, 2 * j, 2 * j + 1);
    t.emplace_back(2 * i, 2 * j + 1, 2 * i + 1);
    t.emplace_back(bottom, 2 * j, 2 * i);
    t.emplace_back(bottom + 1, 2 * i + 1, 2 * j + 1);
  }
}

}  // namespace

std::shared_ptr<const MeshShape> CylinderShape::triangulate(int n) const {
  std::vector<Vec3> v;
  std::vector<Eigen::Vector3i> t;
  prism(r_, h_, n, v, t);
  return std::make_shared<const MeshShape>(std::move(v), std::move(t));
}

namespace {

// Segments around a circle of radius r whose chords stay within `tolerance` of it (sagitta),
// between 12 and 1024.
int circle_segments(double r, double tolerance) {
  if (!(tolerance > 0.0) || tolerance >= r) return 12;
  const double n = std::ceil(kPi / std::acos(1.0 - tolerance / r));
  return static_cast<int>(std::clamp(n, 12.0, 1024.0));
}

}  // namespace

bool BoxShape::surface(double, std::vector<Vec3>& vertices, std::vector<Eigen::Vector3i>& triangles) const {
  Tessellation t = tessellate(*this);
  vertices = std::move(t.vertices);
  triangles = std::move(t.triangles);
  return true;
}

bool CylinderShape::surface(double tolerance, std::vector<Vec3>& vertices,
                            std::vector<Eigen::Vector3i>& triangles) const {
  // A prism on a regular n-gon whose area is the circle's (corners at r sqrt(2pi / (n sin 2pi/n))),
  // so it encloses the exact volume and carries the exact moment; the polygon then crosses the
  // circle, within half a sagitta of it on either side.
  const int n = circle_segments(r_, tolerance);
  prism(r_ * std::sqrt(2.0 * kPi / (n * std::sin(2.0 * kPi / n))), h_, n, vertices, triangles);
  return true;
}


bool CylinderShape::demag_tensor(const Vec3& p, Mat3& D) const {
  std::call_once(once_, [&] { tessellation_ = triangulate(512); });
  return tessellation_->demag_tensor(p, D);
}

std::shared_ptr<const MeshShape> TorusShape::triangulate(int n) const {
  const int m = std::max(8, n / 2);
  std::vector<Vec3> v;
  std::vector<Eigen::Vector3i> t;
  for (int i = 0; i < n; ++i) {
    const double a = 2 * kPi * i / n;
    for (int j = 0; j < m; ++j) {
      const double b = 2 * kPi * j / m;
      const double rho = R_ + r_ * std::cos(b);
      v.emplace_back(rho * std::cos(a), rho * std::sin(a), r_ * std::sin(b));
    }
  }
  auto id = [&](int i, int j) { return (i % n) * m + (j % m); };
  for (int i = 0; i < n; ++i) {
    for (int j = 0; j < m; ++j) {
      t.emplace_back(id(i, j), id(i + 1, j), id(i + 1, j + 1));
      t.emplace_back(id(i, j), id(i + 1, j + 1), id(i, j + 1));
    }
  }
  return std::make_shared<const MeshShape>(std::move(v), std::move(t));
}

bool TorusShape::demag_tensor(const Vec3& p, Mat3& D) const {
  std::call_once(once_, [&] { tessellation_ = triangulate(384); });
  return tessellation_->demag_tensor(p, D);
}

Box3 TorusShape::bounds() const { return Box3(Vec3(-R_ - r_, -R_ - r_, -r_), Vec3(R_ + r_, R_ + r_, r_)); }
double TorusShape::volume() const { return 2.0 * kPi * kPi * R_ * r_ * r_; }
bool TorusShape::contains(const Vec3& p) const {
  const double q = std::hypot(p[0], p[1]) - R_;
  return q * q + p[2] * p[2] <= r_ * r_ * (1.0 + 2 * kTol);
}
MassProperties TorusShape::mass_properties() const {
  MassProperties mp;
  mp.volume = volume();
  const double izz = mp.volume * (R_ * R_ + 0.75 * r_ * r_);
  const double ixx = mp.volume * (0.5 * R_ * R_ + 0.625 * r_ * r_);
  mp.inertia.diagonal() << ixx, ixx, izz;
  return mp;
}

}  // namespace magbake::geometry

namespace magbake::geometry {

Tessellation tessellate(const Shape& shape, int n) {
  Tessellation t;
  switch (shape.kind()) {
    case ShapeKind::kBox: {
      const Vec3 h = static_cast<const BoxShape&>(shape).half();
      for (int i = 0; i < 8; ++i) t.vertices.emplace_back((i & 1 ? 1 : -1) * h[0], (i & 2 ? 1 : -1) * h[1], (i & 4 ? 1 : -1) * h[2]);
      const int f[12][3] = {{0, 2, 1}, {1, 2, 3}, {4, 5, 6}, {5, 7, 6}, {0, 1, 4}, {1, 5, 4},
                            {2, 6, 3}, {3, 6, 7}, {0, 4, 2}, {2, 4, 6}, {1, 3, 5}, {3, 7, 5}};
      for (auto& q : f) t.triangles.emplace_back(q[0], q[1], q[2]);
      break;
    }
    case ShapeKind::kSphere: {
      const double r = static_cast<const SphereShape&>(shape).radius();
      const int nu = n, nv = std::max(4, n / 2);
      t.vertices.emplace_back(0, 0, -r);
      for (int j = 1; j < nv; ++j) {
        const double th = kPi * j / nv;
        for (int i = 0; i < nu; ++i) {
          const double ph = 2 * kPi * i / nu;
          t.vertices.emplace_back(r * std::sin(th) * std::cos(ph), r * std::sin(th) * std::sin(ph), -r * std::cos(th));
        }
      }
      t.vertices.emplace_back(0, 0, r);
      auto id = [&](int j, int i) { return 1 + (j - 1) * nu + (i % nu); };
      for (int i = 0; i < nu; ++i) t.triangles.emplace_back(0, id(1, i + 1), id(1, i));
      for (int j = 1; j < nv - 1; ++j) {
        for (int i = 0; i < nu; ++i) {
          t.triangles.emplace_back(id(j, i), id(j, i + 1), id(j + 1, i + 1));
          t.triangles.emplace_back(id(j, i), id(j + 1, i + 1), id(j + 1, i));
        }
      }
      const int top = static_cast<int>(t.vertices.size()) - 1;
      for (int i = 0; i < nu; ++i) t.triangles.emplace_back(top, id(nv - 1, i), id(nv - 1, i + 1));
      break;
    }
    case ShapeKind::kCylinder:
    case ShapeKind::kTorus:
    case ShapeKind::kMesh: {
      std::shared_ptr<const MeshShape> m;
      if (shape.kind() == ShapeKind::kCylinder) m = static_cast<const CylinderShape&>(shape).triangulate(n);
      if (shape.kind() == ShapeKind::kTorus) m = static_cast<const TorusShape&>(shape).triangulate(n);
      const MeshShape& mesh = m ? *m : static_cast<const MeshShape&>(shape);
      t.vertices = mesh.vertices();
      t.triangles = mesh.triangles();
      break;
    }
  }
  return t;
}

}  // namespace magbake::geometry
