// RenderTarget: colour is stored sRGB-encoded, clears and fragments are linear light, and
// the MSAA resolve averages samples in linear light (an edge pixel half covered by white
// on black is sRGB(0.5) = 188, not 128).
#include "client/render/render_target.hpp"

#include <cmath>
#include <cstdio>
#include <map>
#include <memory>

#include <gtest/gtest.h>

#include "client/render/gl_context.hpp"
#include "client/render/gl_util.hpp"

namespace vistel {
namespace {

constexpr const char* kVertex = R"(#version 330 core
const vec2 corners[3] = vec2[3](vec2(-1.0, -1.0), vec2(1.0, -1.0), vec2(-1.0, 1.0));
void main() { gl_Position = vec4(corners[gl_VertexID], 0.0, 1.0); }
)";
constexpr const char* kFragment = R"(#version 330 core
out vec4 o_color;
void main() { o_color = vec4(1.0); }
)";

int encode(double linear) {
  const double s = linear <= 0.0031308 ? 12.92 * linear : 1.055 * std::pow(linear, 1 / 2.4) - 0.055;
  return static_cast<int>(std::lround(255.0 * s));
}

class RenderTargetTest : public ::testing::Test {
 protected:
  void SetUp() override {
    ContextOptions options;
    options.width = 64;
    options.height = 64;
    auto context = createEglContext(options);
    if (!context) GTEST_SKIP() << "no EGL context: " << context.error().message;
    context_ = std::move(*context);
    context_->makeCurrent();
  }
  std::unique_ptr<GlContext> context_;
};

TEST_F(RenderTargetTest, ClearsAreLinearAndStoredEncoded) {
  RenderTarget target;
  ASSERT_TRUE(target.resize(16, 16, 4));
  target.bindForDrawing();
  glClearColor(0.5f, 0.2f, 0.0f, 1.0f);
  glClear(GL_COLOR_BUFFER_BIT);
  target.resolve();
  Image image;
  target.readPixels(image);
  ASSERT_EQ(image.width, 16);
  EXPECT_NEAR(image.rgba[0], encode(0.5), 1);
  EXPECT_NEAR(image.rgba[1], encode(0.2), 1);
  EXPECT_EQ(image.rgba[2], 0);
  EXPECT_TRUE(takeGlError().empty());
}

TEST_F(RenderTargetTest, MsaaEdgesAverageInLinearLight) {
  RenderTarget target;
  ASSERT_TRUE(target.resize(64, 64, 4));
  if (target.samples() < 2) GTEST_SKIP() << "no multisampling here";
  auto program = buildProgram("white", kVertex, kFragment);
  ASSERT_TRUE(program) << program.error().message;
  GLuint vao = 0;
  glGenVertexArrays(1, &vao);
  target.bindForDrawing();
  glViewport(0, 0, 64, 64);
  glClearColor(0.0f, 0.0f, 0.0f, 1.0f);
  glClear(GL_COLOR_BUFFER_BIT | GL_DEPTH_BUFFER_BIT);
  glDisable(GL_DEPTH_TEST);
  glUseProgram(*program);
  glBindVertexArray(vao);
  glDrawArrays(GL_TRIANGLES, 0, 3);  // white below the diagonal: edge pixels partly covered
  glBindVertexArray(0);
  target.resolve();
  Image image;
  target.readPixels(image);
  glDeleteVertexArrays(1, &vao);
  glDeleteProgram(*program);
  ASSERT_TRUE(takeGlError().empty());

  // Every partly covered pixel holds the encoding of its coverage k / samples, never the
  // average of encoded values (k / samples * 255).
  const int n = target.samples();
  std::map<int, int> edge_values;
  int edges = 0, matched = 0;
  for (std::size_t i = 0; i < image.rgba.size(); i += 4) {
    const int v = image.rgba[i];
    if (v == 0 || v == 255) continue;
    ++edges;
    ++edge_values[v];
    for (int k = 1; k < n; ++k) {
      if (std::abs(v - encode(static_cast<double>(k) / n)) <= 2) {
        ++matched;
        break;
      }
    }
  }
  for (const auto& [v, count] : edge_values)
    std::printf("[ measure  ] edge value %d: %d\n", v, count);
  EXPECT_GE(edges, 32) << "the diagonal crosses 64 pixels";
  EXPECT_EQ(matched, edges);
  // Half coverage is sRGB(0.5), not 128.
  if (n % 2 == 0) {
    const int half = encode(0.5);
    EXPECT_GT(edge_values[half - 1] + edge_values[half] + edge_values[half + 1], 0);
  }
  EXPECT_EQ(edge_values.count(128), 0u);
}

}  // namespace
}  // namespace vistel
