// Posture from sensors through the real programs on loopback: a client driven by the
// simulated rig records its raw stream (--source sim:CLIP --record), a bot replays the
// recording through the solver (--recording, --count) and a headless observer receives
// both; a truncated recording replays up to its last good record and says where it broke;
// a FASTRAK-class tracker emulated on a pseudo-terminal drives `vistel-client --sensors`,
// calibrates after a delay, and its unplugging is reported while the client keeps going.
#include <fcntl.h>
#include <poll.h>
#include <pty.h>
#include <signal.h>
#include <termios.h>
#include <unistd.h>

#include <atomic>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <initializer_list>
#include <optional>
#include <string>
#include <thread>
#include <vector>

#include <gtest/gtest.h>
#include <glm/glm.hpp>
#include <nlohmann/json.hpp>

#include "client/net/data_dir.hpp"
#include "common/base/file.hpp"
#include "tests/integration/program.hpp"
#include "tests/support/test_support.hpp"

namespace vistel {
namespace {

using test::Program;

using Clock = std::chrono::steady_clock;

// A FASTRAK-class tracker on a pseudo-terminal: answers the status request, streams binary
// records (position in inches, quaternion w x y z, a space: output list 2,11,0) for
// stations 1..4 in turn at 120 Hz once told `C`, stops on `c`; unplug() closes the master
// side, as pulling the cable of a USB serial adapter would. The participant stands in the
// calibration pose for the first second, then raises the right wrist and waves it.
class FakeFastrak {
 public:
  FakeFastrak() {
    termios raw{};
    cfmakeraw(&raw);
    char name[256] = {};
    if (openpty(&master_, &slave_, name, &raw, nullptr) != 0) {
      ADD_FAILURE() << "openpty: " << std::strerror(errno);
      return;
    }
    path_ = name;
    // Not inherited by the programs the test starts (else closing ours would not hang up).
    fcntl(master_, F_SETFD, FD_CLOEXEC);
    fcntl(slave_, F_SETFD, FD_CLOEXEC);
    fcntl(master_, F_SETFL, fcntl(master_, F_GETFL) | O_NONBLOCK);
    thread_ = std::thread([this] { run(); });
  }
  ~FakeFastrak() {
    stop_ = true;
    if (thread_.joinable()) thread_.join();
    if (master_ >= 0) close(master_);
    if (slave_ >= 0) close(slave_);
  }
  const std::string& path() const { return path_; }
  void unplug() { unplug_ = true; }
  int recordsSent() const { return records_; }

 private:
  void run() {
    const auto start = Clock::now();
    std::string pending;
    bool streaming = false;
    double next = 0.0;
    int station = 1;
    while (!stop_) {
      if (unplug_) {
        close(master_);
        close(slave_);
        master_ = slave_ = -1;
        return;
      }
      pollfd p{master_, POLLIN, 0};
      poll(&p, 1, 2);
      const double now = std::chrono::duration<double>(Clock::now() - start).count();
      // Commands: a letter, or a letter with parameters up to CR.
      char buf[256];
      for (ssize_t n; (n = read(master_, buf, sizeof buf)) > 0;) pending.append(buf, n);
      while (!pending.empty()) {
        const char c = pending[0];
        if (std::strchr("OlxvHRA", c) != nullptr) {
          const std::size_t cr = pending.find('\r');
          if (cr == std::string::npos) break;
          pending.erase(0, cr + 1);
          continue;
        }
        pending.erase(0, 1);
        if (c == 'S') write("21S" + std::string(40, ' ') + "status: OK\r\n");
        if (c == 'C') {
          streaming = true;
          next = now;
        }
        if (c == 'c') streaming = false;
      }
      // Continuous output: one record every 1/120 s, the stations in turn.
      for (; streaming && next <= now; next += 1.0 / 120.0) {
        write(record(station, next));
        station = station % 4 + 1;
      }
    }
  }

  void write(const std::string& bytes) {
    if (::write(master_, bytes.data(), bytes.size()) > 0) ++records_;
  }

  // Metres in tracker space (+Y up, the transmitter 1 m above the floor).
  static std::string record(int station, double t) {
    glm::vec3 p{0.0f};
    if (station == 1) p = {0.0f, 0.68f, 0.4f};     // head
    if (station == 2) p = {0.0f, 0.38f, 0.47f};    // sternum
    if (station == 3) p = {0.22f, -0.12f, 0.4f};   // left wrist
    if (station == 4) p = {-0.22f, -0.12f, 0.4f};  // right wrist
    if (station == 4 && t > 1.0) {
      const float a = static_cast<float>(std::min(1.0, t - 1.0));
      p += a * glm::vec3(-0.1f, 0.55f, 0.25f) +
           glm::vec3(0.12f * static_cast<float>(std::sin(6.0 * t)) * a, 0.0f, 0.0f);
    }
    const float values[7] = {p.x / 0.0254f, p.y / 0.0254f, p.z / 0.0254f, 1.0f, 0.0f, 0.0f, 0.0f};
    std::string out = {'0', static_cast<char>('0' + station), ' '};
    out.append(reinterpret_cast<const char*>(values), sizeof values);  // little-endian float32
    out.push_back(' ');
    return out;
  }

  int master_ = -1;
  int slave_ = -1;
  std::string path_;
  std::thread thread_;
  std::atomic<bool> stop_{false};
  std::atomic<bool> unplug_{false};
  std::atomic<int> records_{0};
};

// A sensors config for the emulated tracker: four stations, no gloves, device axes =
// tracker space, calibration in the "facing" alignment.
std::string ptyConfig(const std::string& port) {
  std::string toml =
      "participant = \"pty\"\n[tracker]\nkind = \"fastrak\"\n"
      "transport = \"serial\"\nport = \"" +
      port +
      "\"\nbaud = 115200\nencoding = \"binary\"\nmode = \"continuous\"\n"
      "units = \"inches\"\noutput_list = [2, 11, 0]\nreply_timeout_s = 1.0\n"
      "check_status = true\ntransmitter_angle_deg = 0.0\n";
  const char* sites[] = {"head", "chest", "left_wrist", "right_wrist"};
  for (int i = 0; i < 4; ++i) {
    toml += "[[station]]\nnumber = " + std::to_string(i + 1) + "\nsite = \"" + sites[i] + "\"\n";
  }
  toml += "[calibration]\nalignment = \"facing\"\nfloor_height = -1.0\nwindow_s = 0.3\n";
  return toml;
}

void append(std::vector<std::string>& args, std::initializer_list<std::string> more) {
  args.insert(args.end(), more);
}

nlohmann::json readJson(const std::string& path) {
  auto text = readFileText(path);
  if (!text) return nlohmann::json::object();
  return nlohmann::json::parse(*text, nullptr, false);
}

class SensorsCli : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = test::scratchDir();
    setenv("XDG_CACHE_HOME", (dir_ + "/cache").c_str(), 1);
    // The build's default avatar (canonical joints, so the solver can drive it) and a
    // bundled gesture clip; the shared wave clip when the build made no clips.
    const std::string data = net::findDataDir();
    avatar_ = data + "/default.vavatar";
    if (!std::filesystem::exists(avatar_)) {
      GTEST_SKIP() << "no default avatar at " << avatar_ << " (build the vistel_assets target)";
    }
    clip_ = data + "/gestures/wave.bvh";
    if (!std::filesystem::exists(clip_)) {
      clip_ = test::sharedDataPath("mocap/gestures/dataset-2_wave-right-hand_normal_001.bvh");
    }
  }
  bool haveClip() const { return std::filesystem::exists(clip_); }

  std::vector<std::string> clientArgs(const std::string& address, const std::string& name) {
    return {"--server", address,    "--room", "sensors",   "--name",
            name,       "--avatar", avatar_,  "--headless"};
  }

  // Records `seconds` of the simulated rig on the clip through a client into path.
  void recordSim(const std::string& address, const std::string& path, const std::string& seconds) {
    auto args = clientArgs(address, "sim");
    append(args, {"--source", "sim:" + clip_, "--record", path, "--duration", seconds,
                  "--stats-json", dir_ + "/sim.json"});
    Program sim("vistel-client", args, dir_ + "/sim.log");
    ASSERT_EQ(sim.wait(60.0).value_or(-999), 0) << sim.log();
    std::printf("[ client   ] %s", sim.log().c_str());
    EXPECT_NE(sim.log().find("recording the raw stream to " + path), std::string::npos);
    EXPECT_NE(sim.log().find("sensors: calibrated on"), std::string::npos) << sim.log();
    EXPECT_GT(readJson(dir_ + "/sim.json").value("postures_sent", 0), 30);
    ASSERT_TRUE(std::filesystem::exists(path));
  }

  std::string dir_;
  std::string avatar_;
  std::string clip_;
};

TEST_F(SensorsCli, SimulatedRigRecordedByAClientAndReplayedByBots) {
  if (!haveClip()) GTEST_SKIP() << "no gesture clip (bundled or shared): " << clip_;
  Program server("vistel-server", {"--port", "0"}, dir_ + "/server.log", true);
  const std::string address = test::serverAddress(server);
  ASSERT_FALSE(address.empty()) << server.log();
  auto observer_args = clientArgs(address, "observer");
  append(observer_args, {"--duration", "6", "--stats-json", dir_ + "/observer.json"});
  Program observer("vistel-client", observer_args, dir_ + "/observer.log");

  // The client on the simulated rig streams and records; then two bots replay the file.
  const std::string recording = dir_ + "/wave.vrec";
  recordSim(address, recording, "2");
  Program bots("vistel-bot",
               {"--server", address, "--room", "sensors", "--name", "rec", "--avatar", avatar_,
                "--recording", recording, "--count", "2", "--loop"},
               dir_ + "/bots.log");

  ASSERT_EQ(observer.wait(60.0).value_or(-999), 0) << observer.log();
  nlohmann::json stats = readJson(dir_ + "/observer.json");
  std::printf("[ measure  ] observer stats: %s\n", stats.dump().c_str());
  for (const char* member : {"sim", "rec-1", "rec-2"}) {
    ASSERT_TRUE(stats["members"].contains(member)) << member << "\n" << stats.dump();
    EXPECT_GE(stats["members"][member]["postures_received"].get<int>(), 60) << member;
    // Sent at the room's tick rate (60 Hz) from 120 Hz sensor frames; loopback, a busy machine.
    EXPECT_GE(stats["members"][member]["rate_hz"].get<double>(), 30.0) << member;
  }
  bots.signal(SIGINT);
  EXPECT_EQ(bots.wait(20.0).value_or(-999), 0) << bots.log();
  std::printf("[ bots     ] %s", bots.log().c_str());
  EXPECT_NE(bots.log().find("replaying " + recording + ": "), std::string::npos) << bots.log();
  EXPECT_EQ(bots.log().find("damaged"), std::string::npos) << bots.log();
  server.signal(SIGTERM);
  EXPECT_EQ(server.wait(10.0).value_or(-999), 0) << server.log();
}

TEST_F(SensorsCli, TruncatedRecordingReplaysUpToTheLastGoodRecord) {
  if (!haveClip()) GTEST_SKIP() << "no gesture clip (bundled or shared): " << clip_;
  Program server("vistel-server", {"--port", "0"}, dir_ + "/server.log", true);
  const std::string address = test::serverAddress(server);
  ASSERT_FALSE(address.empty()) << server.log();
  const std::string recording = dir_ + "/take.vrec";
  recordSim(address, recording, "1.5");

  // Cut the file in the middle of its last record (a process killed mid-write).
  auto bytes = readFileBytes(recording, 1u << 30);
  ASSERT_TRUE(bytes);
  ASSERT_GT(bytes->size(), 100u);
  bytes->resize(bytes->size() - 9);
  const std::string cut = dir_ + "/cut.vrec";
  ASSERT_TRUE(writeFileBytes(cut, *bytes));

  Program bot("vistel-bot",
              {"--server", address, "--room", "sensors", "--name", "cut", "--avatar", avatar_,
               "--recording", cut},
              dir_ + "/bot.log");
  EXPECT_EQ(bot.wait(30.0).value_or(-999), 0) << bot.log();
  const std::string log = bot.log();
  std::printf("[ bot      ] %s", log.c_str());
  EXPECT_NE(log.find("damaged, replaying up to its last good record"), std::string::npos) << log;
  EXPECT_NE(log.find("at byte"), std::string::npos) << log;
  EXPECT_NE(log.find("replay finished after"), std::string::npos) << log;
  EXPECT_EQ(log.find("cut sent 0 postures"), std::string::npos) << log;
  server.signal(SIGTERM);
  EXPECT_EQ(server.wait(10.0).value_or(-999), 0) << server.log();
}

TEST_F(SensorsCli, EmulatedFastrakDrivesTheClientAndItsUnpluggingIsReported) {
  FakeFastrak tracker;
  ASSERT_FALSE(tracker.path().empty());
  const std::string config = dir_ + "/pty.toml";
  ASSERT_TRUE(writeFileText(config, ptyConfig(tracker.path())));

  Program server("vistel-server", {"--port", "0"}, dir_ + "/server.log", true);
  const std::string address = test::serverAddress(server);
  ASSERT_FALSE(address.empty()) << server.log();
  auto observer_args = clientArgs(address, "observer");
  append(observer_args, {"--duration", "30", "--stats-json", dir_ + "/observer.json"});
  Program observer("vistel-client", observer_args, dir_ + "/observer.log");

  auto args = clientArgs(address, "tracked");
  append(args, {"--sensors", config, "--calibrate-after", "0.5", "--duration", "30", "--stats-json",
                dir_ + "/tracked.json"});
  Program client("vistel-client", args, dir_ + "/tracked.log");

  // Calibrated in the pose, then streaming the wave; then the cable is pulled.
  ASSERT_TRUE(client.waitForLog("sensors: calibrated on", 15.0)) << client.log();
  std::this_thread::sleep_for(std::chrono::milliseconds(1500));
  tracker.unplug();
  ASSERT_TRUE(client.waitForLog("unplugged", 5.0)) << client.log();
  // The client keeps running (holding the last posture) until told to stop.
  std::this_thread::sleep_for(std::chrono::milliseconds(500));
  client.signal(SIGINT);
  EXPECT_EQ(client.wait(20.0).value_or(-999), 0) << client.log();
  std::printf("[ client   ] %s", client.log().c_str());
  EXPECT_NE(client.log().find("holding the last posture"), std::string::npos);
  nlohmann::json own = readJson(dir_ + "/tracked.json");
  std::printf("[ measure  ] emulated tracker wrote %d records; tracked client sent %d postures\n",
              tracker.recordsSent(), own.value("postures_sent", 0));
  EXPECT_GT(own.value("postures_sent", 0), 60);

  observer.signal(SIGINT);
  ASSERT_EQ(observer.wait(20.0).value_or(-999), 0) << observer.log();
  nlohmann::json stats = readJson(dir_ + "/observer.json");
  std::printf("[ measure  ] observer stats: %s\n", stats.dump().c_str());
  ASSERT_TRUE(stats["members"].contains("tracked")) << stats.dump();
  EXPECT_GE(stats["members"]["tracked"]["postures_received"].get<int>(), 60);
  EXPECT_GE(stats["members"]["tracked"]["rate_hz"].get<double>(), 20.0);
  server.signal(SIGTERM);
  EXPECT_EQ(server.wait(10.0).value_or(-999), 0) << server.log();
}

TEST_F(SensorsCli, SensorOptionsRefuseBadUsageWithAClearMessage) {
  struct Case {
    std::vector<std::string> extra;
    int status;
    std::string message;
  };
  const std::string garbage = dir_ + "/garbage.vrec";
  ASSERT_TRUE(writeFileText(garbage, "not a recording"));
  const std::vector<Case> cases = {
      {{"--record", dir_ + "/x.vrec"}, 2, "--record"},
      {{"--calibrate-after", "1"}, 2, "--calibrate-after"},
      {{"--sensors", "config/sensors/fastrak.toml", "--source", "sim:" + clip_}, 2, "use one"},
      {{"--source", "kinect:0"}, 2, "expected bvh:FILE, sim:CLIP.bvh or recording:FILE.vrec"},
      {{"--source", "sim:no/such/clip.bvh"}, 1, "no/such/clip.bvh"},
      {{"--sensors", dir_ + "/none.toml"}, 1, "none.toml"},
  };
  for (std::size_t i = 0; i < cases.size(); ++i) {
    std::vector<std::string> args = {"--server", "127.0.0.1:1", "--room", "r",         "--name",
                                     "n",        "--avatar",    avatar_,  "--headless"};
    args.insert(args.end(), cases[i].extra.begin(), cases[i].extra.end());
    Program client("vistel-client", args, dir_ + "/case" + std::to_string(i) + ".log");
    EXPECT_EQ(client.wait(20.0).value_or(-999), cases[i].status) << client.log();
    EXPECT_NE(client.log().find(cases[i].message), std::string::npos) << client.log();
  }
  Program bot("vistel-bot",
              {"--server", "127.0.0.1:1", "--room", "r", "--name", "n", "--avatar", avatar_,
               "--recording", garbage},
              dir_ + "/bot.log");
  EXPECT_EQ(bot.wait(20.0).value_or(-999), 1) << bot.log();
  EXPECT_NE(bot.log().find("garbage.vrec"), std::string::npos) << bot.log();
}

}  // namespace
}  // namespace vistel
