// Field volumes for renderers: B sampled on a voxel grid, written as OpenVDB files.
#pragma once

#include <string>
#include <vector>

#include "magnetics/types.h"

namespace magbake::io {

using magnetics::Vec3;

/// A dense block of voxel samples at voxel centres min + (i, j, k) * voxel: the field of the
/// bodies (tesla, world), and the uniform applied field, kept apart so that the applied field
/// neither makes voxels active nor shows in the display density.
struct FieldSamples {
  Vec3 origin = Vec3::Zero();    ///< centre of voxel (0, 0, 0), world, m
  double voxel = 0;              ///< m
  Eigen::Vector3i dims{0, 0, 0}; ///< voxels along x, y, z
  std::vector<float> bx, by, bz; ///< bodies' B, (nx * ny * nz), index (k * ny + j) * nx + i; NaN = not evaluated
  Vec3 applied = Vec3::Zero();   ///< uniform applied B, tesla, world: added to every voxel's value
  std::size_t index(int i, int j, int k) const { return (std::size_t(k) * dims[1] + j) * dims[0] + i; }
};

/// The auto threshold as a fraction of the reference field (the strongest remanence or applied
/// field; bake/field_command.cpp, docs/field-volumes.md), and the display density's lower end
/// when every voxel is active.
inline constexpr double kAutoThresholdFraction = 0.003;

/// Metadata written with every volume.
struct VolumeInfo {
  int frame = 0;
  double time = 0;          ///< s
  std::string scene_hash;
  std::string scene_name;
  double threshold = 1e-5;  ///< T: voxels where the bodies' |B| is below it stay inactive (0: all evaluated ones active)
  double reference = 1.0;   ///< T: the bodies' |B| at which the display density reaches 1 (field_command.cpp)
};

/// The display density of the bodies' field magnitude `b`: 0 at and below `low`, 1 at and above
/// `high`, log10(b / low) / log10(high / low) between (all tesla), so a default volume shader
/// shows weak and strong field alike and fades to nothing at the edge of the active region.
/// With high <= low: 0 below low, 1 from it.
float display_density(float b, double low, double high);

/// The lower end of the display density for a volume: the threshold, or kAutoThresholdFraction
/// of the reference when the threshold is 0 (every voxel active).
double density_floor(const VolumeInfo& info);

/// Writes `path` atomically (a temporary name, renamed when complete): a Vec3SGrid "B" (tesla,
/// world space, VEC_CONTRAVARIANT_RELATIVE; the bodies' field plus the applied field; voxels
/// where the bodies' |B| is below the threshold inactive, background the applied field) and a
/// FloatGrid "density" (display_density of the bodies' |B| from density_floor to the reference,
/// background 0) on the same voxels. Returns the number of active voxels. Throws
/// std::runtime_error when the file cannot be written.
std::size_t write_field_volume(const std::string& path, const FieldSamples& samples, const VolumeInfo& info);

}  // namespace magbake::io
