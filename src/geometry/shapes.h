// Solid shapes of bodies and parts: primitives centred on their frame's origin (cylinder and
// torus axis = local z), and closed triangle meshes. Each is a magnetics::Solid (inside test,
// bounds, volume) and knows its mass properties.
#pragma once

#include <memory>
#include <mutex>
#include <string>
#include <vector>

#include "magnetics/solid.h"
#include "magnetics/surface_charge.h"
#include "magnetics/types.h"

namespace magbake::geometry {

using magnetics::Box3;
using magnetics::Mat3;
using magnetics::Vec3;

/// Volume, centroid and inertia of a solid of unit density (multiply by density in kg/m³).
struct MassProperties {
  double volume = 0;               ///< m³
  Vec3 centroid = Vec3::Zero();    ///< own frame, m
  Mat3 inertia = Mat3::Zero();     ///< about the centroid, own axes, m⁵ (x density -> kg·m²)
};

class MeshShape;

/// Which primitive a shape is.
enum class ShapeKind { kBox, kSphere, kCylinder, kTorus, kMesh };

/// A solid with mass properties. Points on the surface count as inside (closed sets), with a
/// relative tolerance of 1e-12 of the shape's size.
class Shape : public magnetics::Solid {
 public:
  virtual ShapeKind kind() const = 0;
  virtual MassProperties mass_properties() const = 0;
};

/// Box with full edge lengths `size` (m).
class BoxShape final : public Shape {
 public:
  explicit BoxShape(const Vec3& size) : half_(0.5 * size) {}
  Box3 bounds() const override { return Box3(-half_, half_); }
  double volume() const override { return 8.0 * half_.prod(); }
  bool contains(const Vec3& p) const override;
  bool is_box() const override { return true; }
  bool surface(double tolerance, std::vector<Vec3>& vertices, std::vector<Eigen::Vector3i>& triangles) const override;
  bool demag_tensor(const Vec3& p, Mat3& D) const override;
  ShapeKind kind() const override { return ShapeKind::kBox; }
  MassProperties mass_properties() const override;
  const Vec3& half() const { return half_; }

 private:
  Vec3 half_;
};

/// Sphere of radius r (m).
class SphereShape final : public Shape {
 public:
  explicit SphereShape(double radius) : r_(radius) {}
  Box3 bounds() const override { return Box3(Vec3::Constant(-r_), Vec3::Constant(r_)); }
  double volume() const override;
  bool contains(const Vec3& p) const override;
  bool ball(double& radius) const override {
    radius = r_;
    return true;
  }
  bool demag_tensor(const Vec3& p, Mat3& D) const override;
  ShapeKind kind() const override { return ShapeKind::kSphere; }
  MassProperties mass_properties() const override;
  double radius() const { return r_; }

 private:
  double r_;
};

/// Cylinder of radius r and height h (m), axis = local z.
class CylinderShape final : public Shape {
 public:
  CylinderShape(double radius, double height) : r_(radius), h_(height) {}
  Box3 bounds() const override { return Box3(Vec3(-r_, -r_, -0.5 * h_), Vec3(r_, r_, 0.5 * h_)); }
  double volume() const override;
  bool contains(const Vec3& p) const override;
  bool demag_tensor(const Vec3& p, Mat3& D) const override;
  ShapeKind kind() const override { return ShapeKind::kCylinder; }
  bool surface(double tolerance, std::vector<Vec3>& vertices, std::vector<Eigen::Vector3i>& triangles) const override;
  MassProperties mass_properties() const override;
  double radius() const { return r_; }
  double height() const { return h_; }
  /// Closed triangle mesh of the surface with `segments` around the axis.
  std::shared_ptr<const MeshShape> triangulate(int segments) const;

 private:
  double r_, h_;
  mutable std::shared_ptr<const MeshShape> tessellation_;  // for demag_tensor, built on first use
  mutable std::once_flag once_;
};

/// Torus with major radius R (centre of the tube) and minor radius r (tube), axis = local z.
class TorusShape final : public Shape {
 public:
  TorusShape(double major, double minor) : R_(major), r_(minor) {}
  Box3 bounds() const override;
  double volume() const override;
  bool contains(const Vec3& p) const override;
  bool demag_tensor(const Vec3& p, Mat3& D) const override;
  ShapeKind kind() const override { return ShapeKind::kTorus; }
  MassProperties mass_properties() const override;
  double major() const { return R_; }
  double minor() const { return r_; }
  /// Closed triangle mesh of the surface (`segments` around the axis, segments/2 around the tube).
  std::shared_ptr<const MeshShape> triangulate(int segments) const;

 private:
  double R_, r_;
  mutable std::shared_ptr<const MeshShape> tessellation_;
  mutable std::once_flag once_;
};

/// A closed, consistently oriented triangle mesh. Inside test by the generalized winding number,
/// evaluated hierarchically (Barill et al. 2018: far triangle clusters as one dipole term).
/// A triangle mesh of a shape's surface, for rendering and collision hulls (shape frame, m).
struct Tessellation {
  std::vector<Vec3> vertices;
  std::vector<Eigen::Vector3i> triangles;  ///< outward (counter-clockwise seen from outside)
};
/// Tessellates any shape: `segments` around curved axes (meshes are returned as they are).
Tessellation tessellate(const Shape& shape, int segments = 48);

/// The field integral of a flat triangle (magnetics/surface_charge.h); mesh demag tensors use it.
using magnetics::triangle_field;

class MeshShape final : public Shape {
 public:
  /// Builds from vertices (m) and triangles; welds identical vertices, checks that every edge
  /// is shared by exactly two triangles with opposite directions, and flips an inside-out mesh.
  /// Throws std::runtime_error describing the defect (boundary / non-manifold edges, degenerate
  /// volume) when the mesh does not enclose a volume.
  MeshShape(std::vector<Vec3> vertices, std::vector<Eigen::Vector3i> triangles);
  ~MeshShape() override;
  MeshShape(MeshShape&&) noexcept;
  MeshShape& operator=(MeshShape&&) noexcept;

  Box3 bounds() const override { return bounds_; }
  double volume() const override { return mass_.volume; }
  bool contains(const Vec3& p) const override { return winding_number(p) > 0.5; }
  bool surface(double tolerance, std::vector<Vec3>& vertices, std::vector<Eigen::Vector3i>& triangles) const override;
  /// Sum of the exact fields of the uniformly charged faces (far clusters as point charges).
  bool demag_tensor(const Vec3& p, Mat3& D) const override;
  ShapeKind kind() const override { return ShapeKind::kMesh; }
  MassProperties mass_properties() const override { return mass_; }

  /// Generalized winding number at p: ~1 inside, ~0 outside.
  double winding_number(const Vec3& p) const;
  const std::vector<Vec3>& vertices() const { return vertices_; }
  const std::vector<Eigen::Vector3i>& triangles() const { return triangles_; }

 private:
  struct Bvh;
  std::vector<Vec3> vertices_;
  std::vector<Eigen::Vector3i> triangles_;
  Box3 bounds_;
  MassProperties mass_;
  std::unique_ptr<Bvh> bvh_;
};

}  // namespace magbake::geometry
