// Small OpenGL helpers: shader programs with errors that say which stage failed and why.
// GL calls need a current context (see gl_context.hpp).
#pragma once

#include <string_view>

#include <epoxy/gl.h>

#include "common/base/result.hpp"

namespace vistel {

// Compiles and links a vertex + fragment program; the Error carries the driver's log and
// the program's name. The caller owns the returned program (glDeleteProgram).
Result<GLuint> buildProgram(std::string_view name, const char* vertex_source,
                            const char* fragment_source);

// Location of a uniform that must exist (asserts in debug builds when absent).
GLint uniformLocation(GLuint program, const char* name);

// The first pending GL error as text ("GL_INVALID_OPERATION"), or empty; clears it.
std::string_view takeGlError();

}  // namespace vistel
