// Small magnetic setups shared by the library tests.
#pragma once

#include <memory>
#include <vector>

#include "geometry/shapes.h"
#include "magnetics/system.h"

namespace magbake::testing {

using magnetics::Material;
using magnetics::MaterialKind;
using magnetics::Pose;
using magnetics::Quat;

/// Owns the shapes a Model was built from, the model and a state sized for it.
struct Rig {
  std::vector<std::unique_ptr<geometry::Shape>> shapes;
  std::vector<magnetics::BodySpec> bodies;
  magnetics::Model model;
  magnetics::State state;
  /// BuildSettings::exact_balls: false cuts permanent spheres into lattice cells (to test the
  /// lattice on a shape with a closed-form field).
  bool exact_balls = true;
  /// BuildSettings::grading: levels of finer cells at the surface of induced parts.
  int grading = 0;

  /// Adds a one-part body; returns its index.
  int add(std::unique_ptr<geometry::Shape> shape, const Material& material, const Pose& part = Pose{});
  /// Builds the model with the given cell size and sizes the state (all poses at the origin).
  void build(double cell_size, int leaf_size = 32);
};

/// Permanent magnet material of polarization J (T) along `dir` (part frame).
Material permanent(double J, const magnetics::Vec3& dir = magnetics::Vec3::UnitZ());
/// Linear induced material of susceptibility chi (chi = -1: superconductor).
Material linear(double chi);

}  // namespace magbake::testing
