#include <dlfcn.h>

#include <cstring>
#include <string_view>

#include <epoxy/egl.h>
#include <epoxy/gl.h>

#include "client/render/gl_context.hpp"

namespace vistel {

namespace {

bool hasExtension(const char* list, std::string_view name) {
  if (list == nullptr) return false;
  std::string_view all(list);
  std::size_t pos = 0;
  while (pos < all.size()) {
    std::size_t end = all.find(' ', pos);
    if (end == std::string_view::npos) end = all.size();
    if (all.substr(pos, end - pos) == name) return true;
    pos = end + 1;
  }
  return false;
}

// Displays stay initialised while any context uses them (EGL displays are per-process
// singletons, so terminating one would break a second view).
int g_live_contexts = 0;

class EglContext final : public GlContext {
 public:
  EglContext(EGLDisplay display, EGLContext context, const ContextOptions& options,
             std::string platform)
      : display_(display),
        context_(context),
        size_(options.width, options.height),
        platform_(std::move(platform)) {
    ++g_live_contexts;
  }
  ~EglContext() override {
    eglMakeCurrent(display_, EGL_NO_SURFACE, EGL_NO_SURFACE, EGL_NO_CONTEXT);
    eglDestroyContext(display_, context_);
    if (--g_live_contexts == 0) eglTerminate(display_);
  }
  bool isWindow() const override { return false; }
  void makeCurrent() override {
    if (eglGetCurrentContext() != context_) {
      eglMakeCurrent(display_, EGL_NO_SURFACE, EGL_NO_SURFACE, context_);
    }
  }
  glm::ivec2 framebufferSize() const override { return size_; }
  bool shouldClose() const override { return false; }
  void pollEvents() override {}
  void present() override {}
  std::string description() const override {
    return "EGL " + platform_ + ", " + currentGlDescription();
  }

 private:
  EGLDisplay display_;
  EGLContext context_;
  glm::ivec2 size_;
  std::string platform_;
};

Error eglFailure(std::string_view step) {
  return fail("offscreen GL (EGL): {} failed (EGL error 0x{:04x})", step,
              static_cast<unsigned>(eglGetError()));
}

}  // namespace

Result<std::unique_ptr<GlContext>> createEglContext(const ContextOptions& options) {
  // libepoxy aborts when no EGL library exists; check for one first.
  void* lib = dlopen("libEGL.so.1", RTLD_LAZY | RTLD_LOCAL);
  if (lib == nullptr) {
    return fail(
        "offscreen GL (EGL): libEGL.so.1 not found (install libegl1 and "
        "libegl-mesa0)");
  }
  dlclose(lib);

  // The Mesa surfaceless platform needs no X server or GPU; else the default display.
  const char* client_ext = eglQueryString(EGL_NO_DISPLAY, EGL_EXTENSIONS);
  EGLDisplay display = EGL_NO_DISPLAY;
  std::string platform = "default display";
  if (hasExtension(client_ext, "EGL_MESA_platform_surfaceless") &&
      hasExtension(client_ext, "EGL_EXT_platform_base")) {
    display = eglGetPlatformDisplayEXT(EGL_PLATFORM_SURFACELESS_MESA, EGL_DEFAULT_DISPLAY, nullptr);
    platform = "surfaceless";
  }
  if (display == EGL_NO_DISPLAY) display = eglGetDisplay(EGL_DEFAULT_DISPLAY);
  if (display == EGL_NO_DISPLAY) return eglFailure("eglGetDisplay");
  EGLint major = 0;
  EGLint minor = 0;
  if (eglInitialize(display, &major, &minor) == EGL_FALSE) return eglFailure("eglInitialize");
  auto give_up = [&](std::string_view step) {
    Error error = eglFailure(step);
    if (g_live_contexts == 0) eglTerminate(display);
    return error;
  };
  if (eglBindAPI(EGL_OPENGL_API) == EGL_FALSE) return give_up("eglBindAPI(OpenGL)");

  // A config without surfaces when the display allows it.
  const char* display_ext = eglQueryString(display, EGL_EXTENSIONS);
  EGLConfig config = EGL_NO_CONFIG_KHR;
  if (!hasExtension(display_ext, "EGL_KHR_no_config_context")) {
    const EGLint config_attribs[] = {EGL_SURFACE_TYPE, EGL_PBUFFER_BIT, EGL_RENDERABLE_TYPE,
                                     EGL_OPENGL_BIT, EGL_NONE};
    EGLint count = 0;
    if (eglChooseConfig(display, config_attribs, &config, 1, &count) == EGL_FALSE || count < 1) {
      return give_up("eglChooseConfig");
    }
  }
  const bool surfaceless = hasExtension(display_ext, "EGL_KHR_surfaceless_context");
  if (!surfaceless) {
    if (g_live_contexts == 0) eglTerminate(display);
    return fail("offscreen GL (EGL): the display lacks EGL_KHR_surfaceless_context");
  }

  // OpenGL 4.5 core, else 3.3 core.
  EGLContext context = EGL_NO_CONTEXT;
  for (const auto& version : {std::pair{4, 5}, std::pair{3, 3}}) {
    const EGLint attribs[] = {EGL_CONTEXT_MAJOR_VERSION,
                              version.first,
                              EGL_CONTEXT_MINOR_VERSION,
                              version.second,
                              EGL_CONTEXT_OPENGL_PROFILE_MASK,
                              EGL_CONTEXT_OPENGL_CORE_PROFILE_BIT,
                              EGL_NONE};
    context = eglCreateContext(display, config, EGL_NO_CONTEXT, attribs);
    if (context != EGL_NO_CONTEXT) break;
  }
  if (context == EGL_NO_CONTEXT) return give_up("eglCreateContext(OpenGL 3.3+ core)");
  if (eglMakeCurrent(display, EGL_NO_SURFACE, EGL_NO_SURFACE, context) == EGL_FALSE) {
    Error error = eglFailure("eglMakeCurrent");
    eglDestroyContext(display, context);
    if (g_live_contexts == 0) eglTerminate(display);
    return error;
  }
  return std::unique_ptr<GlContext>(
      new EglContext(display, context, options,
                     platform + " " + std::to_string(major) + "." + std::to_string(minor)));
}

}  // namespace vistel
