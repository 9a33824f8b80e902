// Camera math (no GL): framing, stereo eyes, projection to pixels.
#include "client/render/camera.hpp"

#include <gtest/gtest.h>

namespace vistel {
namespace {

TEST(Camera, FrameSphereSeesTheWholeSphere) {
  const Sphere sphere = sphereAroundBox(glm::vec3(-2.0f, 0.0f, -1.0f), glm::vec3(3.0f, 1.9f, 1.5f));
  for (const float aspect : {0.5f, 1.0f, 16.0f / 9.0f}) {
    Lens lens;
    const CameraPose pose =
        frameSphere(sphere, orbitDirection(0.4f, 0.3f), glm::radians(50.0f), aspect, 0.9f, lens);
    const int height = 400;
    const int width = static_cast<int>(static_cast<float>(height) * aspect);
    const EyeCamera eye = makeEye(pose, lens, 0.0f, 1.0f, glm::ivec4(0, 0, width, height));
    // Points on the sphere in many directions project inside the viewport and depth range.
    for (int i = 0; i < 200; ++i) {
      const float z = -1.0f + 2.0f * static_cast<float>(i) / 199.0f;
      const float phi = static_cast<float>(i) * 2.399963f;  // golden angle
      const float r = std::sqrt(1.0f - z * z);
      const glm::vec3 p =
          sphere.center + sphere.radius * glm::vec3(r * std::cos(phi), z, r * std::sin(phi));
      glm::vec3 px;
      ASSERT_TRUE(projectToPixel(eye, p, px));
      EXPECT_GE(px.x, 0.0f);
      EXPECT_LE(px.x, static_cast<float>(width));
      EXPECT_GE(px.y, 0.0f);
      EXPECT_LE(px.y, static_cast<float>(height));
      EXPECT_GT(px.z, -1.0f);
      EXPECT_LT(px.z, 1.0f);
    }
    // The centre lands in the middle of the image.
    glm::vec3 c;
    ASSERT_TRUE(projectToPixel(eye, sphere.center, c));
    EXPECT_NEAR(c.x, width * 0.5f, 0.5f);
    EXPECT_NEAR(c.y, height * 0.5f, 0.5f);
  }
}

TEST(Camera, OrbitDirectionLooksFromTheFrontAndDown) {
  const glm::vec3 d = orbitDirection(0.0f, 0.3f);
  EXPECT_NEAR(glm::length(d), 1.0f, 1e-6f);
  EXPECT_LT(d.z, 0.0f);  // looking along -Z: the camera stands on the +Z side
  EXPECT_LT(d.y, 0.0f);  // and looks down
  EXPECT_NEAR(d.x, 0.0f, 1e-6f);
}

TEST(Camera, StereoEyesAgreeAtTheFocalDistanceAndDisagreeElsewhere) {
  const CameraPose pose =
      makePose(glm::vec3(0, 1.5f, 4.0f), glm::vec3(0, 0, -1), glm::vec3(0, 1, 0));
  Lens lens;
  const float focal = 3.0f;
  const glm::ivec4 viewport(0, 0, 300, 200);
  const EyeCamera left = makeEye(pose, lens, -0.05f, focal, viewport);
  const EyeCamera right = makeEye(pose, lens, 0.05f, focal, viewport);
  EXPECT_NEAR(glm::distance(left.position, right.position), 0.1f, 1e-6f);
  EXPECT_LT(left.position.x, right.position.x);
  glm::vec3 a, b;
  // On the convergence plane: the same pixel in both eyes.
  ASSERT_TRUE(projectToPixel(left, glm::vec3(0.3f, 1.7f, 1.0f), a));
  ASSERT_TRUE(projectToPixel(right, glm::vec3(0.3f, 1.7f, 1.0f), b));
  EXPECT_NEAR(a.x, b.x, 1e-3f);
  EXPECT_NEAR(a.y, b.y, 1e-3f);
  // Behind it: the left eye sees the point further left (uncrossed disparity).
  ASSERT_TRUE(projectToPixel(left, glm::vec3(0.0f, 1.5f, -3.0f), a));
  ASSERT_TRUE(projectToPixel(right, glm::vec3(0.0f, 1.5f, -3.0f), b));
  EXPECT_LT(a.x + 1.0f, b.x);
  // Behind the eye: not projected.
  EXPECT_FALSE(projectToPixel(left, glm::vec3(0.0f, 1.5f, 6.0f), a));
}

TEST(Camera, MakePoseRepairsDegenerateAxes) {
  const CameraPose straight_down = makePose(glm::vec3(0), glm::vec3(0, -2, 0), glm::vec3(0, 1, 0));
  EXPECT_NEAR(glm::length(straight_down.forward), 1.0f, 1e-6f);
  EXPECT_NEAR(glm::length(straight_down.up), 1.0f, 1e-6f);
  EXPECT_NEAR(glm::dot(straight_down.forward, straight_down.up), 0.0f, 1e-6f);
  const CameraPose zero = makePose(glm::vec3(0), glm::vec3(0), glm::vec3(0));
  EXPECT_EQ(zero.forward, glm::vec3(0, 0, -1));
  EXPECT_NEAR(glm::length(zero.up), 1.0f, 1e-6f);
}

}  // namespace
}  // namespace vistel
