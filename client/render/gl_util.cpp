#include "client/render/gl_util.hpp"

#include <cassert>
#include <string>

namespace vistel {

namespace {

std::string infoLog(GLuint object, bool is_program) {
  GLint length = 0;
  if (is_program) {
    glGetProgramiv(object, GL_INFO_LOG_LENGTH, &length);
  } else {
    glGetShaderiv(object, GL_INFO_LOG_LENGTH, &length);
  }
  std::string log(static_cast<std::size_t>(std::max(length, 1)), '\0');
  GLsizei written = 0;
  if (is_program) {
    glGetProgramInfoLog(object, length, &written, log.data());
  } else {
    glGetShaderInfoLog(object, length, &written, log.data());
  }
  log.resize(static_cast<std::size_t>(written));
  return log;
}

Result<GLuint> compileStage(std::string_view name, GLenum stage, const char* source) {
  const GLuint shader = glCreateShader(stage);
  glShaderSource(shader, 1, &source, nullptr);
  glCompileShader(shader);
  GLint ok = GL_FALSE;
  glGetShaderiv(shader, GL_COMPILE_STATUS, &ok);
  if (ok != GL_TRUE) {
    std::string log = infoLog(shader, false);
    glDeleteShader(shader);
    return fail("shader '{}' ({} stage) does not compile: {}", name,
                stage == GL_VERTEX_SHADER ? "vertex" : "fragment", log);
  }
  return shader;
}

}  // namespace

Result<GLuint> buildProgram(std::string_view name, const char* vertex_source,
                            const char* fragment_source) {
  auto vs = compileStage(name, GL_VERTEX_SHADER, vertex_source);
  if (!vs) return vs.error();
  auto fs = compileStage(name, GL_FRAGMENT_SHADER, fragment_source);
  if (!fs) {
    glDeleteShader(*vs);
    return fs.error();
  }
  const GLuint program = glCreateProgram();
  glAttachShader(program, *vs);
  glAttachShader(program, *fs);
  glLinkProgram(program);
  glDeleteShader(*vs);
  glDeleteShader(*fs);
  GLint ok = GL_FALSE;
  glGetProgramiv(program, GL_LINK_STATUS, &ok);
  if (ok != GL_TRUE) {
    std::string log = infoLog(program, true);
    glDeleteProgram(program);
    return fail("shader program '{}' does not link: {}", name, log);
  }
  return program;
}

GLint uniformLocation(GLuint program, const char* name) {
  const GLint location = glGetUniformLocation(program, name);
  assert(location >= 0 && "uniform missing (or optimised out)");
  return location;
}

std::string_view takeGlError() {
  const GLenum error = glGetError();
  switch (error) {
    case GL_NO_ERROR:
      return {};
    case GL_INVALID_ENUM:
      return "GL_INVALID_ENUM";
    case GL_INVALID_VALUE:
      return "GL_INVALID_VALUE";
    case GL_INVALID_OPERATION:
      return "GL_INVALID_OPERATION";
    case GL_INVALID_FRAMEBUFFER_OPERATION:
      return "GL_INVALID_FRAMEBUFFER_OPERATION";
    case GL_OUT_OF_MEMORY:
      return "GL_OUT_OF_MEMORY";
    default:
      return "GL error";
  }
}

}  // namespace vistel
