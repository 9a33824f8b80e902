#include "client/render/gl_context.hpp"

#include <cstdlib>

#include <epoxy/gl.h>

namespace vistel {

bool displayAvailable() {
  for (const char* var : {"DISPLAY", "WAYLAND_DISPLAY"}) {
    const char* value = std::getenv(var);
    if (value != nullptr && value[0] != '\0') return true;
  }
  return false;
}

std::string currentGlDescription() {
  const auto* version = reinterpret_cast<const char*>(glGetString(GL_VERSION));
  const auto* renderer = reinterpret_cast<const char*>(glGetString(GL_RENDERER));
  return std::string("OpenGL ") + (version ? version : "?") + ", " + (renderer ? renderer : "?");
}

int currentGlVersion() { return epoxy_gl_version(); }

}  // namespace vistel
