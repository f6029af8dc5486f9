// Loading triangle meshes from files (OBJ, STL, PLY, glTF and the other formats assimp reads).
#pragma once

#include <string>

#include "shapes.h"

namespace magbake::geometry {

/// Largest mesh file read (bytes).
inline constexpr unsigned long long kMaxMeshFileBytes = 2ull << 30;

/// Vertices and triangles of every mesh in a file, concatenated, coordinates multiplied by
/// `scale`. Throws std::runtime_error with the reason when the file cannot be read (missing,
/// not a regular file, e.g. a FIFO, over kMaxMeshFileBytes) or has no triangles.
struct TriangleSoup {
  std::vector<Vec3> vertices;
  std::vector<Eigen::Vector3i> triangles;
};
TriangleSoup load_triangles(const std::string& path, double scale);

}  // namespace magbake::geometry
