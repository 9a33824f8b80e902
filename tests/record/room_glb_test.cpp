// encodeRoomGlb on a synthetic recording: the GLB container, one skin per member over
// joint nodes named as the skeleton's, a shared avatar mesh, members and props as named
// nodes, moving joints as LINEAR channels and constant ones as static transforms, and a
// STEP scale channel that hides a member outside its spans.
#include "common/record/room_glb.hpp"

#include <algorithm>
#include <string>

#include <gtest/gtest.h>

#include "tests/record/glb_reader.hpp"
#include "tests/record/synthetic_recording.hpp"

namespace vistel::record {
namespace {

// The channels of the (single) animation that target `node` with `path`.
std::vector<nlohmann::json> channelsOf(const test::GlbFile& f, int node, const std::string& path) {
  std::vector<nlohmann::json> out;
  for (const auto& ch : f.json["animations"][0]["channels"]) {
    if (ch["target"]["node"] == node && ch["target"]["path"] == path) out.push_back(ch);
  }
  return out;
}

TEST(RoomGlb, MembersAsSkinsPropsAsNodesAndSpansAsScale) {
  const RoomRecording rec = test::syntheticRecording();
  RecordingSummary summary;
  auto bytes = encodeRoomGlb(rec, &summary);
  ASSERT_TRUE(bytes) << bytes.error().message;
  EXPECT_EQ(summary.members, 2);
  EXPECT_EQ(summary.props, 1);
  EXPECT_GT(summary.keys, 0);
  const test::GlbFile f = test::readGlb(*bytes);
  ASSERT_TRUE(f.ok);
  const auto& j = f.json;
  EXPECT_EQ(j["asset"]["version"], "2.0");

  // Skins and the shared mesh (the avatar's and the ball's).
  ASSERT_EQ(j["skins"].size(), 2u);
  EXPECT_EQ(j["skins"][0]["name"], "alice");
  EXPECT_EQ(j["skins"][1]["name"], "bob");
  EXPECT_EQ(j["meshes"].size(), 2u);
  EXPECT_EQ(j["skins"][0]["inverseBindMatrices"], j["skins"][1]["inverseBindMatrices"]);
  for (const char* name : {"alice", "bob"}) {
    const int seat = f.node(name);
    ASSERT_GE(seat, 0) << name;
    const int mesh_node = f.node(std::string(name) + " avatar");
    ASSERT_GE(mesh_node, 0);
    EXPECT_EQ(j["nodes"][mesh_node]["mesh"], j["nodes"][f.node("alice avatar")]["mesh"]);
    // The joints: under the seat node, named "member:joint", in skeleton order.
    const auto& skin = j["skins"][j["nodes"][mesh_node]["skin"].get<std::size_t>()];
    ASSERT_EQ(skin["joints"].size(), 5u);
    EXPECT_EQ(j["nodes"][seat]["children"][0], skin["joints"][0]);
    EXPECT_EQ(j["nodes"][skin["joints"][0].get<std::size_t>()]["name"],
              std::string(name) + ":hips");
    EXPECT_EQ(j["nodes"][skin["joints"][2].get<std::size_t>()]["name"],
              std::string(name) + ":head");
  }

  // alice: always shown (no scale channel), seated (static translation), her head moving,
  // her spine never rotating (a static rotation, no channel).
  const int alice = f.node("alice");
  EXPECT_TRUE(channelsOf(f, alice, "scale").empty());
  EXPECT_TRUE(channelsOf(f, alice, "translation").empty());
  EXPECT_FLOAT_EQ(j["nodes"][alice]["translation"][0].get<float>(), -1.0f);
  const auto& alice_joints = j["skins"][0]["joints"];
  const int head = alice_joints[2].get<int>();
  const int spine = alice_joints[1].get<int>();
  const auto head_rot = channelsOf(f, head, "rotation");
  ASSERT_EQ(head_rot.size(), 1u);
  EXPECT_TRUE(channelsOf(f, spine, "rotation").empty());
  const auto& sampler = j["animations"][0]["samplers"][head_rot[0]["sampler"].get<std::size_t>()];
  EXPECT_EQ(sampler["interpolation"], "LINEAR");
  const std::vector<float> times = f.floats(sampler["input"].get<int>());
  const std::vector<float> quats = f.floats(sampler["output"].get<int>());
  ASSERT_EQ(quats.size(), times.size() * 4);
  EXPECT_LT(times.size(), 241u / 2) << "the head's keys are reduced";
  EXPECT_GT(times.size(), 4u);
  EXPECT_TRUE(std::is_sorted(times.begin(), times.end()));
  for (std::size_t k = 0; k < times.size(); ++k) {
    const float n = quats[4 * k] * quats[4 * k] + quats[4 * k + 1] * quats[4 * k + 1] +
                    quats[4 * k + 2] * quats[4 * k + 2] + quats[4 * k + 3] * quats[4 * k + 3];
    EXPECT_NEAR(n, 1.0f, 1e-5f);
  }

  // bob: hidden before 1 s, between 2 and 2.5 s and from 3 s (STEP scale 0/1).
  const auto bob_scale = channelsOf(f, f.node("bob"), "scale");
  ASSERT_EQ(bob_scale.size(), 1u);
  const auto& step = j["animations"][0]["samplers"][bob_scale[0]["sampler"].get<std::size_t>()];
  EXPECT_EQ(step["interpolation"], "STEP");
  EXPECT_EQ(f.floats(step["input"].get<int>()), (std::vector<float>{0.0f, 1.0f, 2.0f, 2.5f, 3.0f}));
  const std::vector<float> scales = f.floats(step["output"].get<int>());
  ASSERT_EQ(scales.size(), 15u);
  EXPECT_EQ(scales[0], 0.0f);
  EXPECT_EQ(scales[3], 1.0f);
  EXPECT_EQ(scales[6], 0.0f);
  EXPECT_EQ(scales[9], 1.0f);
  EXPECT_EQ(scales[12], 0.0f);

  // The ball: a mesh node with a translation channel, hidden before 0.5 s.
  const int ball = f.node("ball 1");
  ASSERT_GE(ball, 0);
  EXPECT_TRUE(j["nodes"][ball].contains("mesh"));
  EXPECT_FALSE(j["nodes"][ball].contains("skin"));
  EXPECT_EQ(channelsOf(f, ball, "translation").size(), 1u);
  EXPECT_EQ(channelsOf(f, ball, "scale").size(), 1u);
}

TEST(RoomGlb, MembersWithoutAnAvatarAreLeftOutWithAWarning) {
  RoomRecording rec = test::syntheticRecording();
  rec.members[1].avatar = nullptr;
  RecordingSummary summary;
  auto bytes = encodeRoomGlb(rec, &summary);
  ASSERT_TRUE(bytes) << bytes.error().message;
  EXPECT_EQ(summary.members, 1);
  EXPECT_EQ(summary.members_skipped, 1);
  ASSERT_EQ(summary.warnings.size(), 1u);
  EXPECT_NE(summary.warnings[0].find("'bob'"), std::string::npos) << summary.warnings[0];
  EXPECT_EQ(test::readGlb(*bytes).json["skins"].size(), 1u);

  // A joint count other than the avatar's: left out too.
  rec.members[0].rotations.pop_back();
  rec.props.clear();
  auto none = encodeRoomGlb(rec, &summary);
  ASSERT_FALSE(none);
  EXPECT_NE(none.error().message.find("nothing to write"), std::string::npos)
      << none.error().message;
}

TEST(RoomGlb, NonFiniteTrackIsRefused) {
  RoomRecording rec = test::syntheticRecording();
  rec.props[0].position.add(10.0, glm::vec3(std::nanf(""), 0.0f, 0.0f));
  rec.props[0].position.finish();
  auto bytes = encodeRoomGlb(rec);
  ASSERT_FALSE(bytes);
  EXPECT_NE(bytes.error().message.find("ball 1"), std::string::npos) << bytes.error().message;
}

}  // namespace
}  // namespace vistel::record
