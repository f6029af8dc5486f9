// An offscreen OpenGL context behind one small interface: OSMesa now (Mesa <= 25.0); an EGL
// surfaceless backend can replace it without touching the renderer.
#pragma once

#include <cstdint>
#include <memory>
#include <vector>

namespace magbake::render {

class GlContext {
 public:
  virtual ~GlContext() = default;
  int width() const { return width_; }
  int height() const { return height_; }
  /// Finishes rendering and returns the framebuffer, RGBA8, top row first.
  virtual std::vector<std::uint8_t> read_rgba() = 0;
  /// A current OpenGL 3.3+ core context rendering into a width x height RGBA buffer with depth.
  /// `threads` caps llvmpipe's rasterizer threads (0 = its default). Throws std::runtime_error.
  static std::unique_ptr<GlContext> create_offscreen(int width, int height, int threads);

 protected:
  int width_ = 0, height_ = 0;
};

}  // namespace magbake::render
