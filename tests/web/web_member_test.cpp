// Visible spectators without sockets: the page's messages, the member name, the
// camera-headed avatar and the posture that puts its camera at the viewer's.
#include "server/web/web_member.hpp"

#include <cmath>
#include <string>
#include <vector>

#include <gtest/gtest.h>
#include <glm/gtc/quaternion.hpp>

#include "common/avatar/avatar_io.hpp"
#include "common/scene/seat_layout.hpp"
#include "server/web/avatar_glb.hpp"

namespace vistel::server {
namespace {

TEST(WebMember, ParsesJoinPoseAndLeave) {
  auto join = parseSpectatorMessage(R"({"type":"join","name":"Ann"})");
  ASSERT_TRUE(join) << join.error().message;
  EXPECT_EQ(join->kind, SpectatorMessage::Kind::kJoin);
  EXPECT_EQ(join->name, "Ann");
  auto anonymous = parseSpectatorMessage(R"({"type":"join"})");
  ASSERT_TRUE(anonymous);
  EXPECT_TRUE(anonymous->name.empty());

  auto pose =
      parseSpectatorMessage(R"({"type":"pose","x":1.5,"y":1.7,"z":-2,"yaw":0.5,"pitch":-0.25})");
  ASSERT_TRUE(pose) << pose.error().message;
  EXPECT_EQ(pose->kind, SpectatorMessage::Kind::kPose);
  EXPECT_DOUBLE_EQ(pose->pose.x, 1.5);
  EXPECT_DOUBLE_EQ(pose->pose.y, 1.7);
  EXPECT_DOUBLE_EQ(pose->pose.z, -2.0);
  EXPECT_DOUBLE_EQ(pose->pose.yaw, 0.5);
  EXPECT_DOUBLE_EQ(pose->pose.pitch, -0.25);
  // Yaw wraps into [-pi, pi].
  auto wrapped = parseSpectatorMessage(R"({"type":"pose","x":0,"y":0,"z":0,"yaw":6.5,"pitch":0})");
  ASSERT_TRUE(wrapped);
  EXPECT_NEAR(wrapped->pose.yaw, 6.5 - 2.0 * M_PI, 1e-9);

  auto leave = parseSpectatorMessage(R"({"type":"leave"})");
  ASSERT_TRUE(leave);
  EXPECT_EQ(leave->kind, SpectatorMessage::Kind::kLeave);
}

TEST(WebMember, RefusesBadMessagesSayingWhy) {
  struct Case {
    const char* text;
    const char* says;
  };
  const std::vector<Case> cases = {
      {"", "not JSON"},
      {"{\"type\":", "not JSON"},
      {"[1,2]", "not a JSON object"},
      {R"({"name":"x"})", "type"},
      {R"({"type":7})", "type"},
      {R"({"type":"dance"})", "unknown type"},
      {R"({"type":"join","name":5})", "name"},
      {R"({"type":"pose","y":0,"z":0,"yaw":0,"pitch":0})", "\"x\" is missing"},
      {R"({"type":"pose","x":"1","y":0,"z":0,"yaw":0,"pitch":0})", "\"x\" is not a number"},
      {R"({"type":"pose","x":0,"y":1e9,"z":0,"yaw":0,"pitch":0})", "\"y\""},
      {R"({"type":"pose","x":0,"y":0,"z":0,"yaw":0,"pitch":2})", "\"pitch\""},
      {R"({"type":"pose","x":0,"y":0,"z":0,"yaw":1e300,"pitch":0})", "\"yaw\""},
  };
  for (const Case& c : cases) {
    auto parsed = parseSpectatorMessage(c.text);
    ASSERT_FALSE(parsed) << c.text;
    EXPECT_NE(parsed.error().message.find(c.says), std::string::npos)
        << c.text << " -> " << parsed.error().message;
  }
}

TEST(WebMember, NamesAreSanitisedAndBounded) {
  EXPECT_EQ(spectatorMemberName("Ann", 3), "Ann (spectator)");
  EXPECT_EQ(spectatorMemberName("", 3), "spectator-3");
  EXPECT_EQ(spectatorMemberName("  <script>\x01\xe2\x80\xae ", 9), "script (spectator)");
  EXPECT_EQ(spectatorMemberName("<>!?", 4), "spectator-4");
  EXPECT_EQ(spectatorMemberName("a  b", 1), "a b (spectator)");
  const std::string longest = spectatorMemberName(std::string(300, 'x'), 1);
  EXPECT_EQ(longest, std::string(kMaxSpectatorNameChars, 'x') + " (spectator)");
}

TEST(WebMember, TheCameraHeadedAvatarIsValidAndStable) {
  const AvatarModel avatar = makeSpectatorAvatar();
  ASSERT_TRUE(validateAvatar(avatar)) << validateAvatar(avatar).error().message;
  EXPECT_EQ(avatar.skeleton.jointCount(), 2);
  EXPECT_EQ(findHeadJoint(avatar.skeleton), 1);
  EXPECT_FALSE(avatar.implicit.has_value());
  EXPECT_EQ(avatar.look.materials.size(), 3u);
  // A closed surface of boxes: positive volume.
  EXPECT_GT(enclosedVolume(avatar.skin.positions, avatar.skin.indices), 0.01);
  // The lens (material 2) sits in front (+Z) of the head joint, at its height.
  const AvatarSubmesh& lens = avatar.look.submeshes.back();
  ASSERT_EQ(lens.material, 2);
  for (std::uint32_t i = lens.first_index; i < lens.first_index + lens.index_count; ++i) {
    const glm::vec3 p = avatar.skin.positions[avatar.skin.indices[i]];
    EXPECT_GT(p.z, 0.05f);
    EXPECT_NEAR(p.y, 1.0f + kSpectatorHeadHeightM, 0.07f);
  }
  // Same bytes every time (one content hash for every server), and a .glb for the page.
  const auto bytes = encodeAvatar(avatar);
  EXPECT_EQ(avatarContentHash(bytes), avatarContentHash(encodeAvatar(makeSpectatorAvatar())));
  auto decoded = decodeAvatar(bytes, "spectator");
  ASSERT_TRUE(decoded) << decoded.error().message;
  auto glb = avatarGlb(*decoded);
  ASSERT_TRUE(glb) << glb.error().message;
  EXPECT_GT(glb->size(), 1000u);
}

TEST(WebMember, PosturePutsTheCameraAtThePose) {
  const AvatarModel avatar = makeSpectatorAvatar();
  SeatLayout layout;
  for (int seat_index : {0, 1, 2}) {
    const SeatPlacement seat = seatPlacement(seat_index, layout);
    SpectatorPose pose{1.5, 1.7, -2.0, 0.5, 0.3};
    const Posture posture = spectatorPosture(pose, seat.x, seat.z, seat.yaw);
    ASSERT_EQ(posture.rotations.size(), 2u);
    std::vector<glm::mat4> model(2);
    poseSkeleton(avatar.skeleton, posture, model);
    const glm::mat4 room = seatTransform(seat) * model[1];
    const glm::vec3 head(room[3]);
    EXPECT_NEAR(head.x, 1.5f, 1e-4f) << "seat " << seat_index;
    EXPECT_NEAR(head.y, 1.7f, 1e-4f);
    EXPECT_NEAR(head.z, -2.0f, 1e-4f);
    // The lens looks along the pose's view direction.
    const glm::vec3 look = glm::normalize(glm::vec3(room * glm::vec4(0, 0, 1, 0)));
    const glm::vec3 want(std::sin(0.5) * std::cos(0.3), std::sin(0.3),
                         std::cos(0.5) * std::cos(0.3));
    EXPECT_NEAR(look.x, want.x, 1e-4f);
    EXPECT_NEAR(look.y, want.y, 1e-4f);
    EXPECT_NEAR(look.z, want.z, 1e-4f);
  }
}

}  // namespace
}  // namespace vistel::server
