// Finding an avatar's head by joint names, and measuring its eye and top.
#include "client/view/head_landmarks.hpp"

#include <gtest/gtest.h>

#include "test_avatar.hpp"

namespace vistel {
namespace {

Skeleton chain(std::initializer_list<const char*> names, float step = 0.1f) {
  Skeleton skeleton;
  for (const char* name : names) {
    skeleton.names.emplace_back(name);
    skeleton.parents.push_back(skeleton.jointCount() - 2);
    Transform local;
    local.translation = glm::vec3(0.0f, step, 0.0f);
    skeleton.rest_local.push_back(local);
  }
  computeInverseBind(skeleton);
  return skeleton;
}

TEST(HeadLandmarks, FindsTheHeadByNameThenByHeight) {
  EXPECT_EQ(findHeadJoint(chain({"hips", "neck", "head", "head_end"})), 2);
  EXPECT_EQ(findHeadJoint(chain({"Hips", "Neck", "Head", "HeadTop_End"})), 2);
  EXPECT_EQ(
      findHeadJoint(chain({"root", "mixamorig:Neck", "mixamorig:Head", "mixamorig:HeadTop_End"})),
      2);
  // No name mentions a head: the topmost joint.
  EXPECT_EQ(findHeadJoint(chain({"a", "b", "c"})), 2);
  EXPECT_EQ(findHeadJoint(chain({"a", "b", "c"}, -0.1f)), 0);
  EXPECT_EQ(findHeadJoint(Skeleton{}), -1);
}

TEST(HeadLandmarks, EyeAndTopComeFromTheHeadsSkin) {
  const test::TestAvatar avatar = test::makeTestAvatar();
  const int head = findHeadJoint(avatar.model->skeleton);
  ASSERT_EQ(avatar.model->skeleton.names[static_cast<std::size_t>(head)], "head");
  const HeadLandmarks landmarks = measureHead(*avatar.model, head);
  const test::TestCapsule& capsule = avatar.capsules[3];
  // The head capsule spans y 1.62..1.87 and z -0.09..0.11 at rest.
  EXPECT_NEAR(landmarks.top_rest.y, capsule.b.y + capsule.radius, 1e-4f);
  EXPECT_GT(landmarks.eye_rest.y, 1.70f);
  EXPECT_LT(landmarks.eye_rest.y, 1.80f);
  EXPECT_GT(landmarks.eye_rest.z, 0.0f);                          // towards the face
  EXPECT_LT(landmarks.eye_rest.z, capsule.a.z + capsule.radius);  // still inside
  EXPECT_NEAR(landmarks.rest_model[3].y, 1.62f, 1e-5f);
}

TEST(HeadLandmarks, WithoutHeadVerticesFixedOffsetsAreUsed) {
  AvatarModel avatar;
  avatar.skeleton = chain({"hips", "head"});
  const HeadLandmarks landmarks = measureHead(avatar, 1);
  EXPECT_NEAR(landmarks.eye_rest.y, 0.2f + 0.08f, 1e-5f);
  EXPECT_NEAR(landmarks.top_rest.y, 0.2f + 0.20f, 1e-5f);
}

}  // namespace
}  // namespace vistel
