// An OpenGL context for the renderer: a GLFW window when a display exists, else an EGL
// surfaceless context (Mesa) that renders only into framebuffer objects.
//
// The context is made current on the creating thread and stays current there; all GL
// calls must come from that thread. GL entry points come from libepoxy (no init call).
// GLFW is initialised only by createGlfwWindow() and terminated when its window is
// destroyed; bots and offscreen clients never touch it.
#pragma once

#include <memory>
#include <string>

#include <glm/glm.hpp>

#include "common/base/result.hpp"

namespace vistel {

struct ContextOptions {
  int width = 1280;  // window: initial size; offscreen: the nominal framebuffer size
  int height = 720;
  std::string title = "vistel";
  bool vsync = true;  // window only
};

// User input gathered by a window since the last takeInput().
struct InputEvents {
  glm::vec2 drag{0.0f};  // cursor movement with the left button held, pixels
  float scroll = 0.0f;   // wheel steps (positive = away from the user)
  int toggle_view = 0;   // presses of V
  int cycle_stereo = 0;  // presses of B
  std::string keys;      // other printable keys pressed, oldest first (GLFW codes: 'A'..'Z',
                         // '0'..'9', punctuation; at most 32 kept)
};

class GlContext {
 public:
  virtual ~GlContext() = default;
  virtual bool isWindow() const = 0;
  // Makes this context current on the calling thread (when several views exist).
  virtual void makeCurrent() = 0;
  // Window: the current framebuffer size in pixels; offscreen: the nominal size.
  virtual glm::ivec2 framebufferSize() const = 0;
  virtual bool shouldClose() const = 0;
  virtual void pollEvents() = 0;
  // Window: swaps buffers; offscreen: nothing.
  virtual void present() = 0;
  // "EGL surfaceless, OpenGL 4.5 (Core Profile) Mesa ..., llvmpipe ..."
  virtual std::string description() const = 0;
  InputEvents takeInput() {
    InputEvents events = input_;
    input_ = InputEvents{};
    return events;
  }

 protected:
  InputEvents input_;
};

// True when $DISPLAY or $WAYLAND_DISPLAY is set and non-empty.
bool displayAvailable();

// EGL surfaceless (EGL_MESA_platform_surfaceless, else the default display), OpenGL 4.5
// core, falling back to 3.3 core. Fails with a message naming the EGL step and error.
Result<std::unique_ptr<GlContext>> createEglContext(const ContextOptions& options);

// A visible GLFW window with a 4.5 (else 3.3) core context. Fails with GLFW's message.
Result<std::unique_ptr<GlContext>> createGlfwWindow(const ContextOptions& options);

// The GL version string, renderer string, and the numeric version (e.g. 45) of the
// current context.
std::string currentGlDescription();
int currentGlVersion();

}  // namespace vistel
