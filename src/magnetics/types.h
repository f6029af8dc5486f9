// Basic types and physical constants of the magnetics library (SI units throughout).
#pragma once

#include <Eigen/Core>
#include <Eigen/Geometry>

#include <numbers>

namespace magbake::magnetics {

using Vec3 = Eigen::Vector3d;     ///< 3-vector, double precision
using Mat3 = Eigen::Matrix3d;     ///< 3x3 matrix, double precision
using Quat = Eigen::Quaterniond;  ///< unit quaternion (w, x, y, z), rotates local -> parent frame
using Box3 = Eigen::AlignedBox3d; ///< axis-aligned box

/// Vacuum permeability mu0 in T·m/A.
inline constexpr double kMu0 = 4.0e-7 * std::numbers::pi;
/// mu0 / (4 pi) in T·m/A: the prefactor of every dipole formula.
inline constexpr double kMu0Over4Pi = 1.0e-7;

/// A rigid transform: rotation then translation, mapping a local frame into its parent frame
/// (x_parent = rotation * x_local + position).
struct Pose {
  Quat rotation = Quat::Identity();  ///< local -> parent rotation
  Vec3 position = Vec3::Zero();      ///< origin of the local frame in the parent frame, m

  /// Maps a point from the local frame to the parent frame.
  Vec3 apply(const Vec3& x) const { return rotation * x + position; }
};

}  // namespace magbake::magnetics
