// The render meshes of a cache's bodies as previews and USD export draw them: every body's and
// part's triangles in the body frame, coloured by material, permanent magnets split into a north
// (red) and a south (blue) half across the plane through their centre normal to their
// magnetization; a body or part with a scene `color` is drawn in it.
#pragma once

#include <string>
#include <vector>

#include "io/cache.h"
#include "renderer.h"

namespace magbake::cli {

/// Material colour (linear RGB 0..1) of a material kind ("permanent", "soft", "linear",
/// "superconductor", "none"); `north` picks a permanent magnet's north (red) or south (blue) half.
render::Vec3f material_color(const std::string& kind, bool north);

struct ShotGeometry {
  /// One triangle soup per sub-mesh (body or part): 3 positions per triangle (m, body frame),
  /// one colour per position (equal within a triangle); translucent casings of bodies with parts.
  std::vector<render::Mesh> meshes;
  std::vector<std::vector<magnetics::Vec3>> body_points;  ///< body-frame vertices of every body (framing)
};

/// The meshes of every body of `cache` (its /geometry), triangles crossing a magnet's mid-plane
/// cut along it.
ShotGeometry load_geometry(const io::CacheReader& cache);

}  // namespace magbake::cli
