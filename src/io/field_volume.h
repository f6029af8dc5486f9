// Field volumes for renderers: B sampled on a voxel grid, written as OpenVDB files.
#pragma once

#include <string>
#include <vector>

#include "magnetics/types.h"

namespace magbake::io {

using magnetics::Vec3;

/// A dense block of voxel samples: B (tesla, world) at voxel centres min + (i, j, k) * voxel.
struct FieldSamples {
  Vec3 origin = Vec3::Zero();    ///< centre of voxel (0, 0, 0), world, m
  double voxel = 0;              ///< m
  Eigen::Vector3i dims{0, 0, 0}; ///< voxels along x, y, z
  std::vector<float> bx, by, bz; ///< (nx * ny * nz), index (k * ny + j) * nx + i; NaN = not evaluated
  std::size_t index(int i, int j, int k) const { return (std::size_t(k) * dims[1] + j) * dims[0] + i; }
};

/// Metadata written with every volume.
struct VolumeInfo {
  int frame = 0;
  double time = 0;          ///< s
  std::string scene_hash;
  std::string scene_name;
  double threshold = 1e-5;  ///< T: voxels with |B| below it stay inactive
};

/// The display density of a field magnitude: log10(|B| / 1e-5 T) / 5 clamped to [0, 1]
/// (10 µT -> 0, 1 T -> 1), so default volume shaders show both strong and weak fields.
float display_density(float magnitude_tesla);

/// Writes `path` atomically (a temporary name, renamed when complete): a Vec3SGrid "B" (tesla,
/// world space, VEC_CONTRAVARIANT_RELATIVE, voxels below the threshold inactive) and a FloatGrid
/// "density" (display_density of |B| on the same voxels). Returns the number of active voxels.
/// Throws std::runtime_error when the file cannot be written.
std::size_t write_field_volume(const std::string& path, const FieldSamples& samples, const VolumeInfo& info);

}  // namespace magbake::io
