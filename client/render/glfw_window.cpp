#include <epoxy/gl.h>  // before GLFW
#define GLFW_INCLUDE_NONE
#include <GLFW/glfw3.h>

#include "client/render/gl_context.hpp"

namespace vistel {

namespace {

// GLFW reports errors through a callback; keep the last message for our Error.
std::string& lastGlfwError() {
  static std::string message;
  return message;
}

void onGlfwError(int code, const char* description) {
  lastGlfwError() = "GLFW error " + std::to_string(code) + ": " + (description ? description : "");
}

class GlfwWindow final : public GlContext {
 public:
  explicit GlfwWindow(GLFWwindow* window) : window_(window) {
    glfwSetWindowUserPointer(window_, this);
    glfwSetCursorPosCallback(window_, onCursor);
    glfwSetScrollCallback(window_, onScroll);
    glfwSetKeyCallback(window_, onKey);
  }
  ~GlfwWindow() override {
    glfwDestroyWindow(window_);
    glfwTerminate();
  }
  bool isWindow() const override { return true; }
  void makeCurrent() override {
    if (glfwGetCurrentContext() != window_) glfwMakeContextCurrent(window_);
  }
  glm::ivec2 framebufferSize() const override {
    int w = 0;
    int h = 0;
    glfwGetFramebufferSize(window_, &w, &h);
    return {w, h};
  }
  bool shouldClose() const override { return glfwWindowShouldClose(window_) != 0; }
  void pollEvents() override { glfwPollEvents(); }
  void present() override { glfwSwapBuffers(window_); }
  std::string description() const override { return "GLFW window, " + currentGlDescription(); }

 private:
  static GlfwWindow* self(GLFWwindow* window) {
    return static_cast<GlfwWindow*>(glfwGetWindowUserPointer(window));
  }
  static void onCursor(GLFWwindow* window, double x, double y) {
    GlfwWindow* me = self(window);
    const glm::vec2 pos(static_cast<float>(x), static_cast<float>(y));
    if (glfwGetMouseButton(window, GLFW_MOUSE_BUTTON_LEFT) == GLFW_PRESS && me->has_cursor_) {
      me->input_.drag += pos - me->cursor_;
    }
    me->cursor_ = pos;
    me->has_cursor_ = true;
  }
  static void onScroll(GLFWwindow* window, double /*dx*/, double dy) {
    self(window)->input_.scroll += static_cast<float>(dy);
  }
  static void onKey(GLFWwindow* window, int key, int /*scancode*/, int action, int /*mods*/) {
    if (action != GLFW_PRESS) return;
    GlfwWindow* me = self(window);
    if (key == GLFW_KEY_ESCAPE) glfwSetWindowShouldClose(window, GLFW_TRUE);
    if (key == GLFW_KEY_V) ++me->input_.toggle_view;
    if (key == GLFW_KEY_B) ++me->input_.cycle_stereo;
    const bool printable = key >= GLFW_KEY_SPACE && key <= GLFW_KEY_GRAVE_ACCENT;
    if (printable && key != GLFW_KEY_V && key != GLFW_KEY_B && me->input_.keys.size() < 32)
      me->input_.keys.push_back(static_cast<char>(key));
  }

  GLFWwindow* window_;
  glm::vec2 cursor_{0.0f};
  bool has_cursor_ = false;
};

}  // namespace

Result<std::unique_ptr<GlContext>> createGlfwWindow(const ContextOptions& options) {
  glfwSetErrorCallback(onGlfwError);
  if (glfwInit() != GLFW_TRUE) return fail("window: glfwInit failed ({})", lastGlfwError());
  // OpenGL 4.5 core, else 3.3 core. Our own framebuffer is multisampled, the window's not.
  GLFWwindow* window = nullptr;
  for (const auto& version : {std::pair{4, 5}, std::pair{3, 3}}) {
    glfwDefaultWindowHints();
    glfwWindowHint(GLFW_CLIENT_API, GLFW_OPENGL_API);
    glfwWindowHint(GLFW_CONTEXT_VERSION_MAJOR, version.first);
    glfwWindowHint(GLFW_CONTEXT_VERSION_MINOR, version.second);
    glfwWindowHint(GLFW_OPENGL_PROFILE, GLFW_OPENGL_CORE_PROFILE);
    glfwWindowHint(GLFW_OPENGL_FORWARD_COMPAT, GLFW_TRUE);
    glfwWindowHint(GLFW_SAMPLES, 0);
    window =
        glfwCreateWindow(options.width, options.height, options.title.c_str(), nullptr, nullptr);
    if (window != nullptr) break;
  }
  if (window == nullptr) {
    std::string why = lastGlfwError();
    glfwTerminate();
    return fail("window: no OpenGL 3.3+ core window ({})", why);
  }
  glfwMakeContextCurrent(window);
  glfwSwapInterval(options.vsync ? 1 : 0);
  return std::unique_ptr<GlContext>(new GlfwWindow(window));
}

}  // namespace vistel
