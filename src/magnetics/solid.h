// The one thing the cell builder needs to know about a shape: where it is.
#pragma once

#include <vector>

#include "types.h"

namespace magbake::magnetics {

/// A closed region of space in its own (part) frame. Implemented by src/geometry shapes;
/// the magnetics library knows no concrete shape.
class Solid {
 public:
  virtual ~Solid() = default;
  /// Axis-aligned bounds of the region in its own frame, m.
  virtual Box3 bounds() const = 0;
  /// Exact volume of the region, m³ (cell moments are rescaled to it, paper §4.2).
  virtual double volume() const = 0;
  /// True when point p (own frame, m) lies inside the region. Must be thread-safe.
  virtual bool contains(const Vec3& p) const = 0;
  /// True when the region is exactly its bounding box (lets the builder skip inside tests).
  virtual bool is_box() const { return false; }
  /// True when the region is a ball centred on its frame's origin; `radius` receives its radius
  /// (m). A uniformly magnetized ball is exactly a point dipole for everything outside it, so
  /// the builder gives a permanent ball one exact cell (BuildSettings::exact_balls).
  virtual bool ball(double& radius) const {
    (void)radius;
    return false;
  }
  /// A closed triangulation of the region's boundary in its own frame (m): triangle t has the
  /// corners vertices[triangles[t][k]], counter-clockwise seen from outside. A curved solid is
  /// tessellated so that its true surface stays within `tolerance` (m) of the triangles, with the
  /// exact volume enclosed where that is cheap. A permanent part with a surface gets the exact
  /// field of its surface charge near it (surface_charge.h, BuildSettings::surface_tolerance).
  /// Returns false when the solid has none (its field is then its cells' alone).
  virtual bool surface(double tolerance, std::vector<Vec3>& vertices, std::vector<Eigen::Vector3i>& triangles) const {
    (void)tolerance;
    (void)vertices;
    (void)triangles;
    return false;
  }
  /// Demagnetizing tensor D at p inside the region (own frame): when the whole region is
  /// uniformly magnetized with M, its own field there is H = -D M. Returns false when the solid
  /// cannot compute it (the induction solve then skips its boundary consistency correction).
  virtual bool demag_tensor(const Vec3& p, Mat3& D) const {
    (void)p;
    (void)D;
    return false;
  }
};

}  // namespace magbake::magnetics
