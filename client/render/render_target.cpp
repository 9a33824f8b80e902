#include "client/render/render_target.hpp"

#include <algorithm>

namespace vistel {

RenderTarget::~RenderTarget() { release(); }

void RenderTarget::release() {
  const GLuint fbos[] = {draw_fbo_, resolve_fbo_};
  const GLuint rbos[] = {draw_color_, draw_depth_, resolve_color_, resolve_depth_};
  for (GLuint fbo : fbos) {
    if (fbo != 0) glDeleteFramebuffers(1, &fbo);
  }
  for (GLuint rbo : rbos) {
    if (rbo != 0) glDeleteRenderbuffers(1, &rbo);
  }
  draw_fbo_ = draw_color_ = draw_depth_ = resolve_fbo_ = resolve_color_ = resolve_depth_ = 0;
  width_ = height_ = samples_ = 0;
}

namespace {

GLuint makeRenderbuffer(GLenum format, int width, int height, int samples) {
  GLuint rbo = 0;
  glGenRenderbuffers(1, &rbo);
  glBindRenderbuffer(GL_RENDERBUFFER, rbo);
  if (samples > 1) {
    glRenderbufferStorageMultisample(GL_RENDERBUFFER, samples, format, width, height);
  } else {
    glRenderbufferStorage(GL_RENDERBUFFER, format, width, height);
  }
  return rbo;
}

}  // namespace

Status RenderTarget::resize(int width, int height, int samples) {
  width = std::max(width, 1);
  height = std::max(height, 1);
  GLint max_samples = 1;
  glGetIntegerv(GL_MAX_SAMPLES, &max_samples);
  samples = samples <= 1 ? 0 : std::min(samples, static_cast<int>(max_samples));
  if (width == width_ && height == height_ && samples == samples_ && resolve_fbo_ != 0) return {};
  release();

  // The resolve target: what screenshots read (with its own depth when it is drawn into).
  glGenFramebuffers(1, &resolve_fbo_);
  glBindFramebuffer(GL_FRAMEBUFFER, resolve_fbo_);
  resolve_color_ = makeRenderbuffer(GL_SRGB8_ALPHA8, width, height, 0);
  glFramebufferRenderbuffer(GL_FRAMEBUFFER, GL_COLOR_ATTACHMENT0, GL_RENDERBUFFER, resolve_color_);
  if (samples == 0) {
    resolve_depth_ = makeRenderbuffer(GL_DEPTH24_STENCIL8, width, height, 0);
    glFramebufferRenderbuffer(GL_FRAMEBUFFER, GL_DEPTH_STENCIL_ATTACHMENT, GL_RENDERBUFFER,
                              resolve_depth_);
  }
  if (glCheckFramebufferStatus(GL_FRAMEBUFFER) != GL_FRAMEBUFFER_COMPLETE) {
    release();
    return fail("offscreen framebuffer {}x{} is incomplete", width, height);
  }

  // The multisampled target that frames are drawn into.
  if (samples > 0) {
    glGenFramebuffers(1, &draw_fbo_);
    glBindFramebuffer(GL_FRAMEBUFFER, draw_fbo_);
    draw_color_ = makeRenderbuffer(GL_SRGB8_ALPHA8, width, height, samples);
    draw_depth_ = makeRenderbuffer(GL_DEPTH24_STENCIL8, width, height, samples);
    glFramebufferRenderbuffer(GL_FRAMEBUFFER, GL_COLOR_ATTACHMENT0, GL_RENDERBUFFER, draw_color_);
    glFramebufferRenderbuffer(GL_FRAMEBUFFER, GL_DEPTH_STENCIL_ATTACHMENT, GL_RENDERBUFFER,
                              draw_depth_);
    if (glCheckFramebufferStatus(GL_FRAMEBUFFER) != GL_FRAMEBUFFER_COMPLETE) {
      release();
      return fail("multisampled framebuffer {}x{} ({} samples) is incomplete", width, height,
                  samples);
    }
  }
  glBindFramebuffer(GL_FRAMEBUFFER, 0);
  width_ = width;
  height_ = height;
  samples_ = samples;
  return {};
}

void RenderTarget::bindForDrawing() const {
  glBindFramebuffer(GL_FRAMEBUFFER, draw_fbo_ != 0 ? draw_fbo_ : resolve_fbo_);
  glEnable(GL_FRAMEBUFFER_SRGB);  // shaders write linear light; blending happens in linear
}

void RenderTarget::resolve() const {
  if (draw_fbo_ == 0) {
    glDisable(GL_FRAMEBUFFER_SRGB);
    return;
  }
  // Both buffers are sRGB and GL_FRAMEBUFFER_SRGB is on: the samples are decoded to linear,
  // averaged, and encoded again, so an edge half covered is half as bright in light, not in
  // encoded values.
  glEnable(GL_FRAMEBUFFER_SRGB);
  glBindFramebuffer(GL_READ_FRAMEBUFFER, draw_fbo_);
  glBindFramebuffer(GL_DRAW_FRAMEBUFFER, resolve_fbo_);
  glBlitFramebuffer(0, 0, width_, height_, 0, 0, width_, height_, GL_COLOR_BUFFER_BIT, GL_NEAREST);
  glBindFramebuffer(GL_FRAMEBUFFER, 0);
  glDisable(GL_FRAMEBUFFER_SRGB);
}

void RenderTarget::readPixels(Image& out) const {
  out.width = width_;
  out.height = height_;
  out.rgba.resize(static_cast<std::size_t>(width_) * static_cast<std::size_t>(height_) * 4);
  glDisable(GL_FRAMEBUFFER_SRGB);  // the stored (sRGB-encoded) bytes, unconverted
  glBindFramebuffer(GL_READ_FRAMEBUFFER, resolve_fbo_);
  glPixelStorei(GL_PACK_ALIGNMENT, 1);
  glReadPixels(0, 0, width_, height_, GL_RGBA, GL_UNSIGNED_BYTE, out.rgba.data());
  glBindFramebuffer(GL_READ_FRAMEBUFFER, 0);
  flipRows(out);
}

void RenderTarget::blitToDefault(int window_width, int window_height) const {
  glDisable(GL_FRAMEBUFFER_SRGB);  // copies the encoded bytes as they are
  glBindFramebuffer(GL_READ_FRAMEBUFFER, resolve_fbo_);
  glBindFramebuffer(GL_DRAW_FRAMEBUFFER, 0);
  const bool same = window_width == width_ && window_height == height_;
  glBlitFramebuffer(0, 0, width_, height_, 0, 0, window_width, window_height, GL_COLOR_BUFFER_BIT,
                    same ? GL_NEAREST : GL_LINEAR);
  glBindFramebuffer(GL_FRAMEBUFFER, 0);
}

}  // namespace vistel
