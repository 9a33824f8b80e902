// The offscreen framebuffer every frame is drawn into: a multisampled colour + depth
// target resolved into a single-sample one, which screenshots read and a window shows.
// Colour is sRGB-encoded (GL_SRGB8_ALPHA8) with GL_FRAMEBUFFER_SRGB on while drawing and
// resolving: shaders write linear light, blending and the MSAA resolve average in linear
// light, and the stored bytes (what readPixels returns and the window shows) are sRGB.
// Depth has 24 bits and a stencil of 8 (the shadows mark the pixels they darkened).
#pragma once

#include <epoxy/gl.h>

#include "client/render/image.hpp"
#include "common/base/result.hpp"

namespace vistel {

class RenderTarget {
 public:
  RenderTarget() = default;
  ~RenderTarget();  // needs the context current (owners destroy targets before contexts)
  RenderTarget(const RenderTarget&) = delete;
  RenderTarget& operator=(const RenderTarget&) = delete;

  // (Re)creates the buffers for this size (pixels, >= 1) and sample count (<= 1 = no
  // multisampling; clamped to GL_MAX_SAMPLES). No-op when nothing changed. Fails when
  // the framebuffer is incomplete.
  Status resize(int width, int height, int samples);

  // Binds the framebuffer to draw into and enables GL_FRAMEBUFFER_SRGB (so clear colours
  // and fragment outputs are linear; resolve() turns it off again).
  void bindForDrawing() const;
  // Resolves the multisampled colour into the single-sample framebuffer.
  void resolve() const;
  // Reads the resolved colour into `out` (resized once), rows from the top.
  void readPixels(Image& out) const;
  // Copies the resolved colour to the default framebuffer (a window), scaled to its size.
  void blitToDefault(int window_width, int window_height) const;

  int width() const { return width_; }
  int height() const { return height_; }
  int samples() const { return samples_; }

 private:
  void release();

  int width_ = 0;
  int height_ = 0;
  int samples_ = 0;
  GLuint draw_fbo_ = 0;  // multisampled (or the resolve FBO itself when samples <= 1)
  GLuint draw_color_ = 0;
  GLuint draw_depth_ = 0;
  GLuint resolve_fbo_ = 0;
  GLuint resolve_color_ = 0;
  GLuint resolve_depth_ = 0;  // only when there is no multisampled FBO
};

}  // namespace vistel
