// vistel-client --record-room end to end: a server, two bots and a headless client that
// records while a third bot joins and leaves; the client is stopped with SIGINT and must
// have written the .glb (atomically, at exit): every member a named skin, their joints
// moving, the late member hidden outside its span, the props present, the file small, and
// the Khronos validator reporting no errors. Also a synthetic recording under the
// validator.
#include <algorithm>
#include <chrono>
#include <cmath>
#include <csignal>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <optional>
#include <set>
#include <string>
#include <thread>

#include <fmt/format.h>
#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "common/base/file.hpp"
#include "common/record/room_glb.hpp"
#include "tests/integration/program.hpp"
#include "tests/integration/session_scratch.hpp"
#include "tests/record/glb_reader.hpp"
#include "tests/record/synthetic_recording.hpp"
#include "tests/tool/tool_runner.hpp"

namespace vistel {
namespace {

using Child = test::Program;

using test::logOf;

using test::sleepFor;

// three.js as Debian packages it (libjs-three, r111): the GLTFLoader loads `glb` and an
// AnimationMixer plays it (tests/record/loopback/threejs_check.mjs); the boxes of each
// skinned mesh's vertices at `times`. Nothing (and `why`) without node or three.js.
std::optional<nlohmann::json> threeJsBoxes(const std::string& glb, const std::string& dir,
                                           const std::string& times, std::string& why) {
  const std::string three = "/usr/share/javascript/three";
  const std::string loader = three + "/examples/jsm/loaders/GLTFLoader.js";
  if (!std::filesystem::exists(loader) ||
      !std::filesystem::exists(three + "/build/three.module.js")) {
    why = "three.js (Debian's libjs-three) is not installed";
    return std::nullopt;
  }
  if (std::system("command -v node > /dev/null 2>&1") != 0) {
    why = "node is not installed";
    return std::nullopt;
  }
  auto text = readFileText(loader);
  if (!text) return std::nullopt;
  std::string js = *text;
  const std::string from = "../../../build/three.module.js";
  for (std::size_t at = js.find(from); at != std::string::npos; at = js.find(from, at)) {
    js.replace(at, from.size(), "./three.module.mjs");
  }
  std::error_code ec;
  std::filesystem::copy_file(three + "/build/three.module.js", dir + "/three.module.mjs",
                             std::filesystem::copy_options::overwrite_existing, ec);
  std::filesystem::copy_file("tests/record/loopback/threejs_check.mjs", dir + "/check.mjs",
                             std::filesystem::copy_options::overwrite_existing, ec);
  if (ec || !writeFileText(dir + "/GLTFLoader.mjs", js)) {
    why = "could not stage three.js in " + dir;
    return std::nullopt;
  }
  const std::string out = dir + "/three.json";
  const std::string command =
      "cd " + dir + " && node check.mjs " + glb + " " + times + " > " + out + " 2>&1";
  const int code = std::system(command.c_str());
  auto result = readFileText(out);
  const auto json = nlohmann::json::parse(result ? *result : "", nullptr, false);
  if (code != 0 || json.is_discarded()) {
    ADD_FAILURE() << "three.js could not load " << glb << ": " << (result ? *result : "");
    return std::nullopt;
  }
  return json;
}

class RecordRoom : public test::SessionScratch {};

TEST_F(RecordRoom, SyntheticRecordingPassesTheValidator) {
  auto bytes = record::encodeRoomGlb(test::syntheticRecording());
  ASSERT_TRUE(bytes) << bytes.error().message;
  const std::string path = dir_ + "/synthetic_room.glb";
  ASSERT_TRUE(writeFileBytes(path, *bytes));
  VISTEL_VALIDATE_OR_SKIP(verdict, path);
  EXPECT_EQ(verdict["errors"].get<int>(), 0) << verdict.dump();
  EXPECT_EQ(verdict["warnings"].get<int>(), 0) << verdict.dump();
}

TEST_F(RecordRoom, AnUnwritablePathIsRefusedAtStart) {
  for (const std::string& path : {dir_ + "/no/such/folder/room.glb", dir_}) {
    Child client("vistel-client",
                 {"--server", "127.0.0.1:1", "--room", "r", "--name", "n", "--avatar", avatar_path_,
                  "--headless", "--record-room", path},
                 dir_ + "/bad.log", false);
    EXPECT_EQ(client.wait(20.0).value_or(-999), 2) << logOf(dir_ + "/bad.log");
    EXPECT_NE(logOf(dir_ + "/bad.log").find("--record-room " + path), std::string::npos)
        << logOf(dir_ + "/bad.log");
  }
}

TEST_F(RecordRoom, HeadlessClientRecordsTheRoomUntilSigint) {
  Child server("vistel-server", {"--port", "0"}, dir_ + "/server.log", true);
  const std::string address = test::serverAddress(server);
  ASSERT_FALSE(address.empty());
  auto bot = [&](const std::string& name) {
    return std::make_unique<Child>(
        "vistel-bot",
        std::vector<std::string>{"--server", address, "--room", "rec", "--name", name, "--bvh",
                                 bvh_path_, "--avatar", avatar_path_, "--loop"},
        dir_ + "/" + name + ".log", false);
  };
  auto wave = bot("wave");
  auto clap = bot("clap");
  sleepFor(0.5);
  const std::string out = dir_ + "/room.glb";
  Child client("vistel-client",
               {"--server", address, "--room", "rec", "--name", "viewer", "--avatar", avatar_path_,
                "--headless", "--ball", "--record-room", out},
               dir_ + "/client.log", false);
  // A member who joins after the recording started and leaves before it ends.
  sleepFor(1.0);
  auto late = bot("late");
  sleepFor(1.5);
  late->signal(SIGINT);
  EXPECT_EQ(late->wait(10.0).value_or(-999), 0) << logOf(dir_ + "/late.log");
  sleepFor(1.5);
  EXPECT_FALSE(std::filesystem::exists(out)) << "written before the client was asked to stop";
  client.signal(SIGINT);
  const auto status = client.wait(30.0);
  ASSERT_TRUE(status.has_value()) << logOf(dir_ + "/client.log");
  EXPECT_EQ(*status, 0) << logOf(dir_ + "/client.log");
  const std::string log = logOf(dir_ + "/client.log");
  EXPECT_NE(log.find("recorded 4 members"), std::string::npos) << log;

  // The file: complete (no temporary left beside it), small.
  auto bytes = readFileBytes(out, 64u << 20);
  ASSERT_TRUE(bytes) << log;
  std::printf("[ measure  ] %s: %zu bytes\n", out.c_str(), bytes->size());
  EXPECT_LT(bytes->size(), 512u * 1024u);
  for (const auto& entry : std::filesystem::directory_iterator(dir_)) {
    EXPECT_EQ(entry.path().filename().string().find("room.glb."), std::string::npos)
        << entry.path();
  }
  const test::GlbFile f = test::readGlb(*bytes);
  ASSERT_TRUE(f.ok);
  const auto& j = f.json;
  ASSERT_TRUE(j.contains("animations"));
  const auto& anim = j["animations"][0];

  // Every member a skin named after it, over joints named member:joint; no name twice.
  std::set<std::string> skins;
  for (const auto& skin : j["skins"]) skins.insert(skin["name"].get<std::string>());
  EXPECT_EQ(skins, (std::set<std::string>{"wave", "clap", "viewer", "late"}));
  std::set<std::string> node_names;
  for (const auto& node : j["nodes"]) {
    EXPECT_TRUE(node_names.insert(node.value("name", "")).second) << "a name twice: " << node;
  }
  for (const auto& skin : j["skins"]) {
    ASSERT_EQ(skin["joints"].size(), 5u);
    EXPECT_EQ(j["nodes"][skin["joints"][0].get<std::size_t>()]["name"],
              skin["name"].get<std::string>() + ":hips");
  }

  // The bots' joints move: a rotation channel on their skeletons whose keys differ.
  auto movingRotations = [&](const std::string& member) {
    std::set<int> joints;
    for (const auto& skin : j["skins"]) {
      if (skin["name"] != member) continue;
      for (const auto& n : skin["joints"]) joints.insert(n.get<int>());
    }
    int moving = 0;
    for (const auto& ch : anim["channels"]) {
      if (ch["target"]["path"] != "rotation" || !joints.count(ch["target"]["node"].get<int>()))
        continue;
      const auto& s = anim["samplers"][ch["sampler"].get<std::size_t>()];
      const std::vector<float> q = f.floats(s["output"].get<int>());
      bool differs = false;
      for (std::size_t k = 4; k < q.size(); ++k) differs = differs || q[k] != q[k % 4];
      if (differs && q.size() >= 12) ++moving;
    }
    return moving;
  };
  EXPECT_GE(movingRotations("wave"), 2);
  EXPECT_GE(movingRotations("clap"), 2);
  EXPECT_GE(movingRotations("late"), 2);

  // The late member is hidden before it joined and after it left (STEP scale 0, 1, 0).
  const int late_node = f.node("late");
  ASSERT_GE(late_node, 0);
  bool hidden = false;
  double late_join = 0.0, late_leave = 0.0;
  for (const auto& ch : anim["channels"]) {
    if (ch["target"]["node"] != late_node || ch["target"]["path"] != "scale") continue;
    const auto& s = anim["samplers"][ch["sampler"].get<std::size_t>()];
    EXPECT_EQ(s["interpolation"], "STEP");
    const std::vector<float> t = f.floats(s["input"].get<int>());
    const std::vector<float> v = f.floats(s["output"].get<int>());
    ASSERT_EQ(t.size(), 3u);
    late_join = t[1];
    late_leave = t[2];
    EXPECT_EQ(t[0], 0.0f);
    EXPECT_GT(t[1], 0.0f);         // joined about 1 s in (later than the recording began)
    EXPECT_GT(t[2] - t[1], 0.3f);  // shown for about 1.5 s
    EXPECT_EQ(v, (std::vector<float>{0, 0, 0, 1, 1, 1, 0, 0, 0}));
    hidden = true;
  }
  EXPECT_TRUE(hidden);

  // The props: the room's ball and the one --ball asked for, as mesh nodes; one falls.
  int balls = 0, moving_balls = 0;
  for (std::size_t n = 0; n < j["nodes"].size(); ++n) {
    if (j["nodes"][n].value("name", "").rfind("ball ", 0) != 0) continue;
    ++balls;
    EXPECT_TRUE(j["nodes"][n].contains("mesh"));
    for (const auto& ch : anim["channels"]) {
      moving_balls +=
          ch["target"]["node"] == static_cast<int>(n) && ch["target"]["path"] == "translation";
    }
  }
  EXPECT_EQ(balls, 2);
  EXPECT_GE(moving_balls, 1);

  // three.js (r111, which binds animation tracks by node name) plays every member: the
  // bots stand on their hips' translation, wave their arms, and the late member is
  // collapsed to a point before it joined.
  std::string why;
  const double mid = 0.5 * (late_join + late_leave);
  if (auto three =
          threeJsBoxes(out, dir_, fmt::format("{} {} {}", 0.5 * late_join, mid, mid + 0.3), why)) {
    ASSERT_EQ((*three)["meshes"].size(), 4u) << *three;
    for (const auto& mesh : (*three)["meshes"]) {
      const std::string name = mesh["name"].get<std::string>();
      EXPECT_EQ(mesh["bones"].get<int>(), 5) << name;
      const auto& at_mid = mesh["boxes"][1];
      EXPECT_GT(at_mid[1].get<double>(), 0.5) << name << ": hips not lifted";
      EXPECT_GT(at_mid[4].get<double>() - at_mid[1].get<double>(), 0.3) << name;
      if (name.rfind("late", 0) == 0) {
        const auto& before = mesh["boxes"][0];
        EXPECT_LT(before[3].get<double>() - before[0].get<double>(), 1e-4)
            << "shown before joining";
      }
      if (name.rfind("wave", 0) == 0) {
        const auto& v1 = mesh["vertices"][1];
        const auto& v2 = mesh["vertices"][2];
        ASSERT_EQ(v1.size(), v2.size());
        double moved = 0.0;
        for (std::size_t c = 0; c < v1.size(); ++c) {
          moved = std::max(moved, std::abs(v2[c].get<double>() - v1[c].get<double>()));
        }
        EXPECT_GT(moved, 0.01) << "wave does not move in three.js";
      }
    }
  } else {
    std::printf("[ note     ] three.js check left out: %s\n", why.c_str());
  }

  // The validator.
  {
    VISTEL_VALIDATE_OR_SKIP(verdict, out);
    EXPECT_EQ(verdict["errors"].get<int>(), 0) << verdict.dump();
  }
  wave->signal(SIGINT);
  clap->signal(SIGINT);
  EXPECT_EQ(wave->wait(20.0).value_or(-999), 0);
  EXPECT_EQ(clap->wait(20.0).value_or(-999), 0);
  server.signal(SIGTERM);
  EXPECT_EQ(server.wait(10.0).value_or(-999), 0) << logOf(dir_ + "/server.log");
}

}  // namespace
}  // namespace vistel
