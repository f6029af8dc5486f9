// The preview renderer: shaded triangle meshes, a ground grid and polylines (field lines),
// drawn with OpenGL 3.3 core into a GlContext.
#pragma once

#include <Eigen/Core>
#include <Eigen/Geometry>

#include <cstdint>
#include <vector>

#include "gl_context.h"

namespace magbake::render {

using Vec3f = Eigen::Vector3f;
using Mat4f = Eigen::Matrix4f;

/// Triangles of one body, in the body frame, three vertices per triangle, with a colour each.
struct Mesh {
  int body = 0;
  float alpha = 1.0f;            ///< < 1: drawn translucent after the opaque meshes (casings)
  std::vector<Vec3f> positions;  ///< m, body frame
  std::vector<Vec3f> colors;     ///< linear RGB 0..1
};

/// A polyline in world coordinates with per-point colours.
struct Polyline {
  std::vector<Vec3f> points;
  std::vector<Vec3f> colors;
};

/// A pinhole camera, world frame, z up.
struct View {
  Eigen::Vector3d eye, target, up{0, 0, 1};
  double fov = 0.698;    ///< vertical, rad
  double near_plane = 0.001, far_plane = 10;
  /// world -> clip for a width x height image.
  Mat4f view_projection(int width, int height) const;
};

class Renderer {
 public:
  /// The context must stay current and outlive the renderer.
  explicit Renderer(GlContext& context);
  ~Renderer();
  Renderer(const Renderer&) = delete;
  Renderer& operator=(const Renderer&) = delete;

  /// Uploads the meshes (once per shot).
  void set_meshes(const std::vector<Mesh>& meshes);
  /// A square grid in the plane z = height, centred at (cx, cy), half-size `extent`, lines every `spacing`.
  void set_ground(double cx, double cy, double height, double extent, double spacing);
  /// Draws one frame: body_transforms[b] maps body b's frame to world. Returns RGBA8, top row first.
  std::vector<std::uint8_t> draw(const View& view, const std::vector<Mat4f>& body_transforms,
                                 const std::vector<Polyline>& lines);

  /// The background colour (for tests and compositing).
  static Vec3f background() { return Vec3f(0.93f, 0.94f, 0.96f); }

 private:
  struct Gl;
  GlContext& context_;
  Gl* gl_;
};

}  // namespace magbake::render
