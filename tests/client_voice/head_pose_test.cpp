// Heads for the spatialiser and lip sync (client/voice/head_pose.hpp, voice_scene.hpp): the
// head joint in the room at its seat, facing where the seat faces and turning with the
// head; the chin (or jaw) moving with the voice heard.
#include <cmath>
#include <vector>

#include <gtest/gtest.h>
#include <glm/gtc/matrix_transform.hpp>
#include <glm/gtc/quaternion.hpp>

#include "client/voice/head_pose.hpp"
#include "client/voice/voice_scene.hpp"

namespace vistel {
namespace {

constexpr float kPi = 3.14159265f;

// hips (1 m) -> spine (+0.3) -> head (+0.3): the head at 1.6 m, its joint's rest turned
// about Y so that a joint's own axes are not the model's.
Skeleton skeleton() {
  Skeleton s;
  s.names = {"hips", "spine", "Head", "l_arm"};
  s.parents = {kNoParent, 0, 1, 1};
  s.rest_local.resize(4);
  s.rest_local[0].translation = {0.0f, 1.0f, 0.0f};
  s.rest_local[1].translation = {0.0f, 0.3f, 0.0f};
  s.rest_local[2].translation = {0.0f, 0.3f, 0.0f};
  s.rest_local[2].rotation = glm::angleAxis(0.7f, glm::vec3(0, 1, 0));
  s.rest_local[3].translation = {0.25f, 0.2f, 0.0f};
  computeInverseBind(s);
  return s;
}

glm::mat4 seatAt(float x, float z, float yaw) {
  return glm::rotate(glm::translate(glm::mat4(1.0f), glm::vec3(x, 0.0f, z)), yaw,
                     glm::vec3(0.0f, 1.0f, 0.0f));
}

void expectNear(const glm::vec3& a, const glm::vec3& b, float tolerance = 1e-4f) {
  EXPECT_NEAR(a.x, b.x, tolerance);
  EXPECT_NEAR(a.y, b.y, tolerance);
  EXPECT_NEAR(a.z, b.z, tolerance);
}

TEST(HeadPose, FindsTheHeadJointByNameElseTheHighest) {
  const Skeleton s = skeleton();
  EXPECT_EQ(findHeadJoint(s), 2);  // "Head": any case
  Skeleton unnamed = s;
  unnamed.names = {"a", "b", "c", "d"};
  EXPECT_EQ(findHeadJoint(unnamed), 2);  // the highest at rest
  EXPECT_EQ(findHeadJoint(Skeleton{}), -1);
}

TEST(HeadPose, AtRestTheHeadStandsAboveTheSeatFacingWhereTheSeatFaces) {
  const Skeleton s = skeleton();
  HeadPoser poser(s);
  // A seat at (0, 1.5) turned to face -Z (yaw pi), as the ring's seats face the centre.
  const HeadPose head = poser.pose(s, restPosture(s), seatAt(0.0f, 1.5f, kPi));
  expectNear(head.position, {0.0f, 1.6f, 1.5f});
  expectNear(head.orientation * glm::vec3(0, 0, 1), {0, 0, -1});  // facing the centre
  expectNear(head.orientation * glm::vec3(1, 0, 0), {-1, 0, 0});  // its left ear
  // The seat alone gives the same at the default height.
  const HeadPose seat = seatHeadPose(seatAt(0.0f, 1.5f, kPi));
  expectNear(seat.position, head.position);
  expectNear(seat.orientation * glm::vec3(0, 0, 1), {0, 0, -1});
}

TEST(HeadPose, TurningTheHeadTurnsWhereItFaces) {
  const Skeleton s = skeleton();
  HeadPoser poser(s);
  Posture p = restPosture(s);
  // The head joint turned 90 degrees to the avatar's left (about model +Y), on top of its
  // own rest rotation.
  p.rotations[2] = glm::angleAxis(kPi / 2, glm::vec3(0, 1, 0)) * p.rotations[2];
  const HeadPose head = poser.pose(s, p, glm::mat4(1.0f));
  expectNear(head.orientation * glm::vec3(0, 0, 1), {1, 0, 0});
  // A posture of another joint count: the rest head.
  Posture wrong;
  wrong.rotations.resize(2);
  const HeadPose rest = poser.pose(s, wrong, glm::mat4(1.0f));
  expectNear(rest.orientation * glm::vec3(0, 0, 1), {0, 0, 1});
  expectNear(rest.position, {0.0f, 1.6f, 0.0f});
}

TEST(LipSync, TheMouthOpensWithTheLevelHeard) {
  EXPECT_EQ(mouthOpening(0.0f), 0.0f);
  EXPECT_EQ(mouthOpening(std::pow(10.0f, -60.0f / 20.0f)), 0.0f);
  EXPECT_NEAR(mouthOpening(std::pow(10.0f, -35.0f / 20.0f)), 0.5f, 1e-4f);
  EXPECT_EQ(mouthOpening(0.5f), 1.0f);

  const Skeleton s = skeleton();
  HeadPoser poser(s);
  Posture p = restPosture(s);
  EXPECT_EQ(applyVoiceToPosture(s, 0.0f, p), 0.0f);  // silent: nothing moves
  expectNear(poser.pose(s, p, glm::mat4(1.0f)).orientation * glm::vec3(0, 0, 1), {0, 0, 1});
  // No jaw joint: the chin lifts (the face turns up), by at most 6 degrees.
  EXPECT_EQ(applyVoiceToPosture(s, 1.0f, p), 1.0f);
  const glm::vec3 face = poser.pose(s, p, glm::mat4(1.0f)).orientation * glm::vec3(0, 0, 1);
  EXPECT_GT(face.y, 0.05f);
  EXPECT_LT(face.y, std::sin(0.11f));
  EXPECT_NEAR(face.x, 0.0f, 1e-4f);
}

TEST(LipSync, AJawJointOpensDownwards) {
  Skeleton s = skeleton();
  s.names[3] = "jaw";
  s.rest_local[3].translation = {0.0f, -0.05f, 0.05f};
  s.parents[3] = 2;
  computeInverseBind(s);
  Posture p = restPosture(s);
  EXPECT_EQ(applyVoiceToPosture(s, 1.5f, p), 1.0f);        // clamped to 0..1
  EXPECT_EQ(p.rotations[2], restPosture(s).rotations[2]);  // the head stays
  std::vector<glm::mat4> model(4);
  poseSkeleton(s, p, model);
  const std::vector<glm::mat4> rest = restModelTransforms(s);
  // The jaw's forward axis (model +Z at rest) now points down.
  const glm::vec3 forward =
      glm::mat3(model[3]) * glm::inverse(glm::mat3(rest[3])) * glm::vec3(0, 0, 1);
  EXPECT_LT(forward.y, -0.3f);
}

TEST(LipSync, APostureOfAnotherSkeletonIsLeftAsItIs) {
  const Skeleton s = skeleton();
  Posture p;
  p.rotations.assign(2, glm::quat(1, 0, 0, 0));
  EXPECT_EQ(applyVoiceToPosture(s, 1.0f, p), 0.0f);
  EXPECT_EQ(p.rotations[0], glm::quat(1, 0, 0, 0));
}

TEST(LipSync, TheJawTimelineGoesNextToTheWavWritten) {
  EXPECT_EQ(jawTimelinePath("out/frames/heard.wav"), "out/frames/heard.jaw.csv");
  EXPECT_EQ(jawTimelinePath("heard"), "heard.jaw.csv");
  EXPECT_EQ(jawTimelinePath("a.b/heard"), "a.b/heard.jaw.csv");
}

}  // namespace
}  // namespace vistel
