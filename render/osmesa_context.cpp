// GlContext on OSMesa (software rendering with llvmpipe, no display, no GPU).
#include <GL/osmesa.h>

#include <cstdlib>
#include <stdexcept>
#include <string>

#include "gl_context.h"

namespace magbake::render {
namespace {

class OsMesaContext final : public GlContext {
 public:
  OsMesaContext(int w, int h) {
    width_ = w, height_ = h;
    const int core[] = {OSMESA_FORMAT, OSMESA_RGBA, OSMESA_DEPTH_BITS, 24, OSMESA_PROFILE, OSMESA_CORE_PROFILE,
                        OSMESA_CONTEXT_MAJOR_VERSION, 3, OSMESA_CONTEXT_MINOR_VERSION, 3, 0};
    ctx_ = OSMesaCreateContextAttribs(core, nullptr);
    if (!ctx_) throw std::runtime_error("OSMesa: cannot create an OpenGL 3.3 core context");
    buffer_.resize(std::size_t(w) * h * 4);
    if (!OSMesaMakeCurrent(ctx_, buffer_.data(), GL_UNSIGNED_BYTE, w, h)) {
      OSMesaDestroyContext(ctx_);
      throw std::runtime_error("OSMesa: cannot make the context current");
    }
    OSMesaPixelStore(OSMESA_Y_UP, 0);  // row 0 at the top
  }
  ~OsMesaContext() override {
    OSMesaMakeCurrent(nullptr, nullptr, 0, 0, 0);  // release the framebuffer before the context
    OSMesaDestroyContext(ctx_);
  }
  std::vector<std::uint8_t> read_rgba() override {
    glFinish();
    return buffer_;
  }

 private:
  OSMesaContext ctx_ = nullptr;
  std::vector<std::uint8_t> buffer_;
};

}  // namespace

std::unique_ptr<GlContext> GlContext::create_offscreen(int width, int height, int threads) {
  // llvmpipe reads its thread count when the first context is created.
  if (threads > 0) setenv("LP_NUM_THREADS", std::to_string(threads).c_str(), 1);
  return std::make_unique<OsMesaContext>(width, height);
}

}  // namespace magbake::render
