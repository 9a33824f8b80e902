// vistel-server --record-room end to end: a room whose only member leaves is written while
// the server runs; a room of two bots is written when the server gets SIGTERM. Each file is
// a GLB with one skin per member, the room's ball as a node, and an animation whose joints
// move, no longer than the cap (--record-max-s); it passes the Khronos validator with no
// errors (skipped, saying so, where the validator is absent).
#include <algorithm>
#include <chrono>
#include <csignal>
#include <cstdio>
#include <filesystem>
#include <memory>
#include <set>
#include <string>
#include <thread>
#include <vector>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "common/base/file.hpp"
#include "server/record/server_recorder.hpp"
#include "tests/integration/program.hpp"
#include "tests/integration/session_scratch.hpp"
#include "tests/record/glb_reader.hpp"
#include "tests/tool/tool_runner.hpp"

namespace vistel {
namespace {

using Child = test::Program;

using test::logOf;

using test::sleepFor;

// The .glb files in `dir` whose name starts with `room` + "-".
std::vector<std::string> recordingsOf(const std::string& dir, const std::string& room) {
  std::vector<std::string> out;
  for (const auto& entry : std::filesystem::directory_iterator(dir)) {
    const std::string name = entry.path().filename().string();
    if (name.rfind(room + "-", 0) == 0 && name.ends_with(".glb")) out.push_back(entry.path());
  }
  return out;
}

// The skins' names of a recording, and how many of its rotation channels have keys that
// differ (joints that move).
struct Summary {
  std::set<std::string> skins;
  int balls = 0;          // nodes named "ball N"
  float last_key = 0.0f;  // the animation's latest key time (s)
  int animations = 0;
  int moving_rotations = 0;
  bool ok = false;
};
Summary summarize(const std::string& path) {
  Summary s;
  auto bytes = readFileBytes(path, 64u << 20);
  if (!bytes) return s;
  std::printf("[ measure  ] %s: %zu bytes\n", path.c_str(), bytes->size());
  const test::GlbFile f = test::readGlb(*bytes);
  if (!f.ok) return s;
  s.ok = true;
  for (const auto& skin : f.json.value("skins", nlohmann::json::array()))
    s.skins.insert(skin.value("name", ""));
  for (const auto& node : f.json["nodes"]) s.balls += node.value("name", "").rfind("ball ", 0) == 0;
  const auto animations = f.json.value("animations", nlohmann::json::array());
  s.animations = static_cast<int>(animations.size());
  if (animations.empty()) return s;
  const auto& anim = animations[0];
  for (const auto& ch : anim["channels"]) {
    if (ch["target"]["path"] != "rotation") continue;
    const auto& sampler = anim["samplers"][ch["sampler"].get<std::size_t>()];
    const std::vector<float> q = f.floats(sampler["output"].get<int>());
    for (float t : f.floats(sampler["input"].get<int>())) s.last_key = std::max(s.last_key, t);
    bool differs = false;
    for (std::size_t k = 4; k < q.size(); ++k) differs = differs || q[k] != q[k % 4];
    s.moving_rotations += differs;
  }
  return s;
}

class ServerRecord : public test::SessionScratch {};

TEST(ServerRecordPath, NamesTheRoomAndTheUtcStartAndNeverOverwrites) {
  const std::string dir = test::scratchDir();
  const std::string first = server::recordingPath(dir, "hall", 1764333296);  // 2025-11-28
  EXPECT_EQ(first, dir + "/hall-20251128T123456Z.glb");
  ASSERT_TRUE(writeFileText(first, "x"));
  EXPECT_EQ(server::recordingPath(dir, "hall", 1764333296), dir + "/hall-20251128T123456Z-2.glb");
}

TEST_F(ServerRecord, WritesEachRoomWhenItEmptiesOrTheServerStops) {
  const std::string out = dir_ + "/recordings";
  std::filesystem::create_directories(out);
  // "rec" lives ~3 s but is recorded for 2 s at most; "short" ~1.5 s, all of it.
  Child server("vistel-server",
               {"--port", "0", "--record-room", out, "--record-rate", "30", "--record-max-s", "2"},
               dir_ + "/server.log", true);
  const std::string address = test::serverAddress(server);
  ASSERT_FALSE(address.empty()) << logOf(dir_ + "/server.log");
  auto bot = [&](const std::string& room, const std::string& name) {
    return std::make_unique<Child>(
        "vistel-bot",
        std::vector<std::string>{"--server", address, "--room", room, "--name", name, "--bvh",
                                 bvh_path_, "--avatar", avatar_path_, "--loop"},
        dir_ + "/" + name + ".log", false);
  };
  auto wave = bot("rec", "wave");
  auto clap = bot("rec", "clap");
  auto alone = bot("short", "alone");
  sleepFor(1.5);
  // The room "short" empties: its file is written while the server runs.
  alone->signal(SIGINT);
  EXPECT_EQ(alone->wait(10.0).value_or(-999), 0) << logOf(dir_ + "/alone.log");
  std::vector<std::string> short_files;
  for (int i = 0; i < 50 && short_files.empty(); ++i) {
    sleepFor(0.1);
    short_files = recordingsOf(out, "short");
  }
  ASSERT_EQ(short_files.size(), 1u) << logOf(dir_ + "/server.log");
  EXPECT_TRUE(recordingsOf(out, "rec").empty()) << "written before its room emptied";
  sleepFor(1.5);

  // SIGTERM: the room still open is written as the server stops.
  server.signal(SIGTERM);
  EXPECT_EQ(server.wait(20.0).value_or(-999), 0) << logOf(dir_ + "/server.log");
  wave->signal(SIGINT);
  clap->signal(SIGINT);
  wave->wait(10.0);
  clap->wait(10.0);
  const std::vector<std::string> rec_files = recordingsOf(out, "rec");
  ASSERT_EQ(rec_files.size(), 1u) << logOf(dir_ + "/server.log");
  const std::string log = logOf(dir_ + "/server.log");
  EXPECT_NE(log.find("record: wrote"), std::string::npos) << log;
  EXPECT_NE(log.find("room 'rec' reached the recording limit of 2 s"), std::string::npos) << log;
  EXPECT_EQ(log.find("room 'short' reached"), std::string::npos) << log;

  const Summary rec = summarize(rec_files[0]);
  ASSERT_TRUE(rec.ok) << rec_files[0];
  EXPECT_EQ(rec.skins, (std::set<std::string>{"wave", "clap"}));
  EXPECT_EQ(rec.animations, 1);
  EXPECT_GE(rec.moving_rotations, 4);  // two or more moving joints per bot
  EXPECT_EQ(rec.balls, 1);             // the room's ball ([props])
  EXPECT_GE(rec.last_key, 1.9f);
  EXPECT_LE(rec.last_key, 2.1f);  // the cap
  const Summary alone_summary = summarize(short_files[0]);
  ASSERT_TRUE(alone_summary.ok) << short_files[0];
  EXPECT_EQ(alone_summary.skins, (std::set<std::string>{"alone"}));
  EXPECT_EQ(alone_summary.animations, 1);
  EXPECT_GT(alone_summary.last_key, 1.0f);  // recorded until it left (~1.5 s)
  EXPECT_LT(alone_summary.last_key, 2.0f);
  // No temporary file is left beside them.
  for (const auto& entry : std::filesystem::directory_iterator(out)) {
    EXPECT_TRUE(entry.path().filename().string().ends_with(".glb")) << entry.path();
  }

  VISTEL_VALIDATE_OR_SKIP(verdict, rec_files[0]);
  EXPECT_EQ(verdict["errors"].get<int>(), 0) << verdict.dump();
  VISTEL_VALIDATE_OR_SKIP(verdict_alone, short_files[0]);
  EXPECT_EQ(verdict_alone["errors"].get<int>(), 0) << verdict_alone.dump();
}

TEST_F(ServerRecord, AMissingFolderIsRefusedAtStart) {
  Child server("vistel-server", {"--port", "0", "--record-room", dir_ + "/no/such/folder"},
               dir_ + "/bad.log", false);
  EXPECT_EQ(server.wait(20.0).value_or(-999), 1) << logOf(dir_ + "/bad.log");
  EXPECT_NE(logOf(dir_ + "/bad.log").find("no/such/folder"), std::string::npos)
      << logOf(dir_ + "/bad.log");
}

}  // namespace
}  // namespace vistel
