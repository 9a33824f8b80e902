// The spectator stream's messages, the room list pages, the avatar .glb and the
// embedded assets.
#include <cstring>
#include <string>
#include <vector>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "common/wire/bit_stream.hpp"
#include "common/wire/packets.hpp"
#include "common/wire/posture_codec.hpp"
#include "server/web/avatar_glb.hpp"
#include "server/web/spectator_stream.hpp"
#include "server/web/web_assets.hpp"
#include "server/web/web_pages.hpp"
#include "tests/net/synthetic_avatar.hpp"

namespace vistel::server {
namespace {

template <typename T>
T at(const std::vector<std::uint8_t>& bytes, std::size_t offset) {
  T v;
  std::memcpy(&v, bytes.data() + offset, sizeof(T));
  return v;
}

std::vector<std::uint8_t> recordBytes(const Posture& posture, std::uint16_t sequence) {
  wire::PostureRecord record;
  EXPECT_TRUE(wire::encodePostureRecord(posture, sequence, posture.time, record));
  std::vector<std::uint8_t> bytes;
  wire::writeRecord(record, bytes);
  return bytes;
}

TEST(SpectatorStream, FrameLayout) {
  SpectatorFrame frame;
  frame.now = 12.5;
  const Posture posture = test::syntheticPosture(12.25);
  frame.postures.push_back({7, recordBytes(posture, 42)});
  frame.postures.push_back({9, {1, 2, 3}});  // not a record: sent without a posture
  frame.props.push_back({3, {0.5f, 1.25f, -2.0f}, {0.0f, -1.0f, 0.0f}, 0.11f});
  std::vector<std::uint8_t> out;
  encodeSpectatorFrame(frame, out);

  const std::size_t joints = posture.rotations.size();
  ASSERT_EQ(out.size(), kSpectatorFrameHeaderBytes + 2 * kSpectatorMemberHeaderBytes + joints * 8 +
                            kSpectatorPropBytes);
  EXPECT_EQ(out[0], kSpectatorFrameType);
  EXPECT_EQ(out[1], kSpectatorFrameVersion);
  EXPECT_EQ(at<std::uint16_t>(out, 2), 2);
  EXPECT_EQ(at<std::uint16_t>(out, 4), 1);
  EXPECT_DOUBLE_EQ(at<double>(out, 8), 12.5);

  std::size_t o = kSpectatorFrameHeaderBytes;
  EXPECT_EQ(at<std::uint32_t>(out, o), 7u);
  EXPECT_NEAR(at<double>(out, o + 4), 12.25, 1e-4);
  EXPECT_EQ(at<std::uint16_t>(out, o + 12), 42);
  EXPECT_EQ(out[o + 14], joints);
  for (int c = 0; c < 3; ++c) {
    EXPECT_NEAR(at<float>(out, o + 16 + 4 * static_cast<std::size_t>(c)),
                posture.root_translation[c], 1e-3);
  }
  o += kSpectatorMemberHeaderBytes;
  for (std::size_t j = 0; j < joints; ++j) {
    const glm::quat sent(
        at<std::int16_t>(out, o + 6) / 32767.0f, at<std::int16_t>(out, o) / 32767.0f,
        at<std::int16_t>(out, o + 2) / 32767.0f, at<std::int16_t>(out, o + 4) / 32767.0f);
    EXPECT_GT(std::abs(glm::dot(glm::normalize(sent), posture.rotations[j])), 0.9999f) << j;
    o += 8;
  }
  EXPECT_EQ(at<std::uint32_t>(out, o), 9u);
  EXPECT_EQ(out[o + 14], 0);  // no posture
  o += kSpectatorMemberHeaderBytes;
  EXPECT_EQ(at<std::uint32_t>(out, o), 3u);
  EXPECT_FLOAT_EQ(at<float>(out, o + 4), 0.5f);
  EXPECT_FLOAT_EQ(at<float>(out, o + 8), 1.25f);
  EXPECT_FLOAT_EQ(at<float>(out, o + 12), -2.0f);
  EXPECT_FLOAT_EQ(at<float>(out, o + 20), -1.0f);
  EXPECT_FLOAT_EQ(at<float>(out, o + 28), 0.11f);
}

TEST(SpectatorStream, RosterStatusAndHello) {
  LobbyRoomView room;
  room.name = "lab";
  room.created_at = 3.0;
  room.members.push_back({5, "ann \"<x>\"", std::string(64, 'c'), true, 0, 4.0});
  room.members.push_back({6, "bob", std::string(64, 'd'), false, 1, 5.0});
  const SeatLayout layout;
  const auto roster = nlohmann::json::parse(rosterJson(room, layout));
  EXPECT_EQ(roster["type"], "roster");
  EXPECT_EQ(roster["room"], "lab");
  ASSERT_EQ(roster["members"].size(), 2u);
  EXPECT_EQ(roster["members"][0]["name"], "ann \"<x>\"");
  EXPECT_EQ(roster["members"][0]["avatar"], std::string(64, 'c'));
  EXPECT_TRUE(roster["members"][1]["avatar"].is_null());  // not uploaded yet
  const SeatPlacement seat = seatPlacement(1, layout);
  EXPECT_FLOAT_EQ(roster["members"][1]["seat"]["x"].get<float>(), seat.x);
  EXPECT_FLOAT_EQ(roster["members"][1]["seat"]["z"].get<float>(), seat.z);
  EXPECT_FLOAT_EQ(roster["members"][1]["seat"]["yaw"].get<float>(), seat.yaw);

  const auto status = nlohmann::json::parse(statusJson("closed", "everyone left"));
  EXPECT_EQ(status["state"], "closed");
  const auto hello = nlohmann::json::parse(helloJson("lab", 60.0));
  EXPECT_EQ(hello["type"], "hello");
  EXPECT_EQ(hello["rate_hz"], 60.0);
}

TEST(WebPages, RoomListEscapesNamesAndShowsAges) {
  LobbyRoomView room;
  room.name = "lab";
  room.created_at = 10.0;
  room.members.push_back({5, "<script>alert(1)</script>", std::string(64, 'c'), true, 0, 40.0});
  const std::string html = roomListHtml({room}, 100.0, false);
  EXPECT_EQ(html.find("<script>"), std::string::npos);
  EXPECT_NE(html.find("&lt;script&gt;"), std::string::npos);
  EXPECT_NE(html.find("href=\"/room/lab\""), std::string::npos);
  EXPECT_NE(html.find("1 min"), std::string::npos);    // the room: 90 s
  EXPECT_NE(html.find("(1 min)"), std::string::npos);  // the member: 60 s
  EXPECT_NE(roomListHtml({}, 0.0, false).find("No rooms are open"), std::string::npos);
  const std::string hidden = roomListHtml({room}, 100.0, true);
  EXPECT_EQ(hidden.find("/room/lab"), std::string::npos);

  const auto json = nlohmann::json::parse(roomListJson({room}, 100.0, false));
  ASSERT_EQ(json["rooms"].size(), 1u);
  EXPECT_DOUBLE_EQ(json["rooms"][0]["age_s"].get<double>(), 90.0);
  EXPECT_EQ(json["rooms"][0]["members"][0]["name"], "<script>alert(1)</script>");
  EXPECT_TRUE(nlohmann::json::parse(roomListJson({room}, 100.0, true))["rooms"].empty());
  EXPECT_EQ(ageText(3725.0), "1 h 2 min");
  EXPECT_EQ(ageText(-5.0), "0 s");
}

TEST(AvatarGlb, ASkinnedBinaryGltf) {
  const AvatarModel avatar = test::makeSyntheticAvatar("box");
  auto glb = avatarGlb(avatar);
  ASSERT_TRUE(glb) << glb.error().message;
  const std::vector<std::uint8_t>& b = *glb;
  ASSERT_GE(b.size(), 28u);
  EXPECT_EQ(std::memcmp(b.data(), "glTF", 4), 0);
  EXPECT_EQ(at<std::uint32_t>(b, 4), 2u);
  EXPECT_EQ(at<std::uint32_t>(b, 8), b.size());
  const std::uint32_t json_bytes = at<std::uint32_t>(b, 12);
  EXPECT_EQ(json_bytes % 4, 0u);
  EXPECT_EQ(std::memcmp(b.data() + 16, "JSON", 4), 0);
  const auto doc = nlohmann::json::parse(std::string(b.begin() + 20, b.begin() + 20 + json_bytes));
  const std::size_t bin_at = 20 + json_bytes;
  EXPECT_EQ(std::memcmp(b.data() + bin_at + 4, "BIN\0", 4), 0);
  EXPECT_EQ(at<std::uint32_t>(b, bin_at), doc["buffers"][0]["byteLength"].get<std::uint32_t>());

  const int njoint = avatar.skeleton.jointCount();
  ASSERT_EQ(doc["nodes"].size(), static_cast<std::size_t>(njoint + 1));
  EXPECT_EQ(doc["nodes"][0]["skin"], 0);
  ASSERT_EQ(doc["skins"][0]["joints"].size(), static_cast<std::size_t>(njoint));
  for (int j = 0; j < njoint; ++j) {
    EXPECT_EQ(doc["skins"][0]["joints"][static_cast<std::size_t>(j)], j + 1);
    EXPECT_EQ(doc["nodes"][static_cast<std::size_t>(j + 1)]["name"],
              avatar.skeleton.names[static_cast<std::size_t>(j)]);
  }
  // The spine (joint 1) is the hips' child; its children are head and arms.
  EXPECT_EQ(doc["nodes"][1]["children"], nlohmann::json::array({2}));
  EXPECT_EQ(doc["nodes"][2]["children"], nlohmann::json::array({3, 4, 5}));
  const auto& attributes = doc["meshes"][0]["primitives"][0]["attributes"];
  for (const char* a : {"POSITION", "NORMAL", "JOINTS_0", "WEIGHTS_0"}) {
    ASSERT_TRUE(attributes.contains(a)) << a;
    EXPECT_EQ(doc["accessors"][attributes[a].get<std::size_t>()]["count"].get<std::size_t>(),
              avatar.skin.positions.size());
  }
  const auto& ibm = doc["accessors"][doc["skins"][0]["inverseBindMatrices"].get<std::size_t>()];
  EXPECT_EQ(ibm["type"], "MAT4");
  EXPECT_EQ(ibm["count"], njoint);

  AvatarModel empty = avatar;
  empty.skin.indices.clear();
  EXPECT_FALSE(avatarGlb(empty));
  AvatarModel broken = avatar;
  broken.skin.joints[0] = 99;
  EXPECT_FALSE(avatarGlb(broken));
}

TEST(WebAssets, ThePageAndThreeJsAreEmbedded) {
  for (const char* name : {"spectator.html", "spectator.js", "style.css", "three.min.js",
                           "GLTFLoader.js", "OrbitControls.js"}) {
    const WebAsset* asset = findWebAsset(name);
    ASSERT_NE(asset, nullptr) << name;
    EXPECT_GT(asset->bytes.size(), 0u) << name;
    EXPECT_EQ(asset->sha256.size(), 64u);
  }
  EXPECT_EQ(findWebAsset("nope.js"), nullptr);
  EXPECT_EQ(findWebAsset("spectator.js")->content_type, "text/javascript; charset=utf-8");
  const WebAsset* page = findWebAsset("spectator.html");
  const std::string html(page->bytes.begin(), page->bytes.end());
  EXPECT_NE(html.find("/assets/spectator.js"), std::string::npos);
}

}  // namespace
}  // namespace vistel::server
