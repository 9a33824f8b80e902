// The spectator view in a real browser: vistel-server --web-port on loopback with two
// bots waving in room "it", and a headless Chromium (DevTools protocol) on the room's
// page. It checks, through the page's window.vistelScene and two screenshots, that both
// avatars are loaded and move, that the pictures change where they stand, that WebGL
// renders without errors, and that the page comes back by itself after the server
// restarts. Skips, saying so, only where no chromium is installed.
#include <chrono>
#include <csignal>
#include <cstdio>
#include <string>
#include <thread>
#include <vector>

#include <gtest/gtest.h>
#include <stb_image.h>
#include <nlohmann/json.hpp>

#include "common/base/file.hpp"
#include "tests/integration/http_get.hpp"
#include "tests/integration/program.hpp"
#include "tests/integration/session_scratch.hpp"
#include "tests/web_browser/devtools.hpp"

namespace vistel {
namespace {

using Clock = std::chrono::steady_clock;

using test::logOf;

// "vistel-server web on http://127.0.0.1:PORT/" -> "127.0.0.1:PORT".
std::string webAddress(test::Program& server) {
  for (int i = 0; i < 5; ++i) {
    auto line = server.readLine(20.0);
    if (!line) return {};
    const std::string prefix = "vistel-server web on http://";
    if (line->rfind(prefix, 0) == 0) {
      std::string a = line->substr(prefix.size());
      if (!a.empty() && a.back() == '/') a.pop_back();
      return a;
    }
  }
  return {};
}

// Polls the page's scene summary until `done` holds (true) or timeout_s passes (false).
template <typename Done>
bool waitForScene(test::HeadlessChromium& browser, double timeout_s, nlohmann::json& scene,
                  Done done) {
  const auto deadline = Clock::now() + std::chrono::duration<double>(timeout_s);
  while (Clock::now() < deadline) {
    scene = browser.evaluate("window.vistelScene || null");
    if (!scene.is_null() && done(scene)) return true;
    std::this_thread::sleep_for(std::chrono::milliseconds(200));
  }
  return false;
}

int loadedMembers(const nlohmann::json& scene) {
  int n = 0;
  for (const auto& m : scene["members"])
    n += m.value("loaded", false) && m.value("samples", 0) >= 2;
  return n;
}

double motionOf(const nlohmann::json& scene, const std::string& name) {
  for (const auto& m : scene["members"]) {
    if (m.value("name", "") == name) return m.value("motion", 0.0);
  }
  return -1.0;
}

struct Image {
  int width = 0, height = 0;
  std::vector<std::uint8_t> rgba;
};
Image decodePng(const std::vector<std::uint8_t>& png) {
  Image image;
  int channels = 0;
  stbi_uc* pixels = stbi_load_from_memory(png.data(), static_cast<int>(png.size()), &image.width,
                                          &image.height, &channels, 4);
  if (pixels == nullptr) return {};
  image.rgba.assign(pixels, pixels + static_cast<std::size_t>(image.width) * image.height * 4);
  stbi_image_free(pixels);
  return image;
}

// Pixels that differ (by more than 24 in a channel) within a box (CSS pixels = image
// pixels at scale 1), grown by `margin`.
int changedPixels(const Image& a, const Image& b, const nlohmann::json& box, int margin) {
  if (a.width != b.width || a.height != b.height || box.is_null()) return 0;
  const int x0 = std::max(0, static_cast<int>(box["x0"].get<double>()) - margin);
  const int y0 = std::max(0, static_cast<int>(box["y0"].get<double>()) - margin);
  const int x1 = std::min(a.width - 1, static_cast<int>(box["x1"].get<double>()) + margin);
  const int y1 = std::min(a.height - 1, static_cast<int>(box["y1"].get<double>()) + margin);
  int changed = 0;
  for (int y = y0; y <= y1; ++y) {
    for (int x = x0; x <= x1; ++x) {
      const std::size_t i = (static_cast<std::size_t>(y) * a.width + x) * 4;
      for (int c = 0; c < 3; ++c) {
        if (std::abs(int(a.rgba[i + c]) - int(b.rgba[i + c])) > 24) {
          ++changed;
          break;
        }
      }
    }
  }
  return changed;
}

// Console and log lines that are errors of the page or of WebGL. Network errors (the
// WebSocket's failed reconnects while the server is down) are left out when asked, and
// the GPU driver's performance notes always.
std::vector<std::string> pageErrors(const std::vector<test::BrowserMessage>& messages,
                                    bool skip_network) {
  std::vector<std::string> errors;
  for (const auto& m : messages) {
    const bool webgl =
        m.text.find("WebGL") != std::string::npos || m.text.find("GL_INVALID") != std::string::npos;
    if (webgl && m.text.find("Performance") != std::string::npos) continue;
    const bool error = m.kind == "exception" || m.level == "error" || webgl;
    if (!error) continue;
    if (skip_network && (m.source == "network" || m.text.find("WebSocket") != std::string::npos)) {
      continue;
    }
    errors.push_back(m.kind + "/" + m.level + "/" + m.source + ": " + m.text);
  }
  return errors;
}

class SpectatorBrowser : public test::SessionScratch {};

TEST_F(SpectatorBrowser, WatchesTwoBotsAndRecoversAfterARestart) {
  const std::string chromium = test::findChromium();
  if (chromium.empty()) {
    GTEST_SKIP() << "no chromium found (install Debian's chromium: scripts/setup; or set "
                    "VISTEL_CHROMIUM): the spectator page is not tested in a browser";
  }
  auto server = std::make_unique<test::Program>(
      "vistel-server", std::vector<std::string>{"--port", "0", "--web-port", "0"},
      dir_ + "/server.log", true);
  const std::string address = test::serverAddress(*server);
  ASSERT_FALSE(address.empty()) << logOf(dir_ + "/server.log");
  const std::string web = webAddress(*server);
  ASSERT_FALSE(web.empty()) << logOf(dir_ + "/server.log");
  test::Program bots("vistel-bot",
                     {"--server", address, "--room", "it", "--name", "b", "--count", "2", "--bvh",
                      bvh_path_, "--avatar", avatar_path_, "--loop"},
                     dir_ + "/bots.log", false);

  test::HeadlessChromium browser(chromium, dir_ + "/profile", dir_ + "/chromium.log");
  ASSERT_TRUE(browser.ok()) << browser.error() << "\n" << logOf(dir_ + "/chromium.log");
  ASSERT_FALSE(browser.call("Runtime.enable").is_null()) << browser.error();
  ASSERT_FALSE(browser.call("Log.enable").is_null()) << browser.error();
  ASSERT_FALSE(browser.call("Page.enable").is_null()) << browser.error();
  ASSERT_FALSE(browser.call("Page.navigate", {{"url", "http://" + web + "/room/it"}}).is_null())
      << browser.error();

  // Both avatars loaded and playing.
  nlohmann::json scene;
  ASSERT_TRUE(waitForScene(browser, 20.0, scene,
                           [](const nlohmann::json& s) {
                             return s.value("state", "") == "live" && loadedMembers(s) == 2;
                           }))
      << "scene: " << scene.dump() << "\n"
      << logOf(dir_ + "/server.log");
  const nlohmann::json first = scene;
  const auto shot1 = browser.screenshot();
  ASSERT_FALSE(shot1.empty()) << browser.error();
  std::this_thread::sleep_for(std::chrono::milliseconds(700));
  const auto shot2 = browser.screenshot();
  ASSERT_FALSE(shot2.empty()) << browser.error();
  const nlohmann::json second = browser.evaluate("window.vistelScene");
  std::printf("[ measure  ] scene: %s\n", second.dump().c_str());
  EXPECT_TRUE(writeFileBytes(dir_ + "/shot1.png", shot1));
  EXPECT_TRUE(writeFileBytes(dir_ + "/shot2.png", shot2));

  EXPECT_TRUE(second["webgl"]["ok"].get<bool>());
  EXPECT_FALSE(second["webgl"]["contextLost"].get<bool>());
  EXPECT_EQ(second["webgl"]["glErrors"].get<int>(), 0);
  EXPECT_TRUE(second["errors"].empty()) << second["errors"].dump();
  EXPECT_GT(second["framesRendered"].get<int>(), first["framesRendered"].get<int>());
  EXPECT_GT(second["framesReceived"].get<int>(), first["framesReceived"].get<int>());
  ASSERT_EQ(second["members"].size(), 2u);
  const Image a = decodePng(shot1), b = decodePng(shot2);
  ASSERT_GT(a.width, 0);
  for (const auto& m : second["members"]) {
    const std::string name = m["name"];
    EXPECT_TRUE(name == "b-1" || name == "b-2") << name;
    EXPECT_TRUE(m["loaded"].get<bool>()) << name;
    EXPECT_GT(m["motion"].get<double>(), motionOf(first, name)) << name << " does not move";
    const int changed = changedPixels(a, b, m["screen"], 4);
    std::printf("[ measure  ] %s: %d pixels changed in its screen box %s\n", name.c_str(), changed,
                m["screen"].dump().c_str());
    EXPECT_GT(changed, 20) << name << ": the screenshots do not differ where it stands";
  }
  EXPECT_FALSE(second["props"].empty()) << "the room's ball";
  const auto errors = pageErrors(browser.messages(), false);
  EXPECT_TRUE(errors.empty()) << errors.front();

  // The follow-member camera: behind b-2, which then fills more of the picture.
  const int b2 = second["members"][0]["name"] == "b-2" ? second["members"][0]["id"].get<int>()
                                                       : second["members"][1]["id"].get<int>();
  browser.evaluate("window.vistelScene.setCamera('follow:" + std::to_string(b2) + "')");
  ASSERT_TRUE(waitForScene(
      browser, 5.0, scene,
      [](const nlohmann::json& s) {
        for (const auto& m : s["members"]) {
          if (m["name"] == "b-2" && !m["screen"].is_null()) {
            return m["screen"]["y1"].get<double>() - m["screen"]["y0"].get<double>() > 100.0;
          }
        }
        return false;
      }))
      << "following b-2: " << scene.dump();
  EXPECT_EQ(scene["camera"], "follow:" + std::to_string(b2));
  browser.evaluate("window.vistelScene.setCamera('orbit')");

  // The server restarts on the same ports: the page says so, reconnects, and shows the
  // bots again once they have rejoined.
  const std::string port = address.substr(address.rfind(':') + 1);
  const std::string web_port = web.substr(web.rfind(':') + 1);
  server->signal(SIGTERM);
  EXPECT_EQ(server->wait(10.0).value_or(-999), 0) << logOf(dir_ + "/server.log");
  ASSERT_TRUE(waitForScene(browser, 10.0, scene, [](const nlohmann::json& s) {
    return !s.value("connected", true);
  })) << scene.dump();
  EXPECT_EQ(scene["state"], "reconnecting");
  server = std::make_unique<test::Program>(
      "vistel-server", std::vector<std::string>{"--port", port, "--web-port", web_port},
      dir_ + "/server2.log", true);
  ASSERT_FALSE(test::serverAddress(*server).empty()) << logOf(dir_ + "/server2.log");
  ASSERT_TRUE(waitForScene(browser, 25.0, scene,
                           [](const nlohmann::json& s) {
                             return s.value("connected", false) && s.value("connects", 0) >= 2 &&
                                    s.value("state", "") == "live" && loadedMembers(s) == 2;
                           }))
      << "scene: " << scene.dump() << "\n"
      << logOf(dir_ + "/bots.log");
  const double motion = motionOf(scene, "b-1");
  std::this_thread::sleep_for(std::chrono::milliseconds(500));
  const nlohmann::json after = browser.evaluate("window.vistelScene");
  EXPECT_GT(motionOf(after, "b-1"), motion) << after.dump();
  EXPECT_TRUE(after["errors"].empty()) << after["errors"].dump();
  EXPECT_EQ(after["webgl"]["glErrors"].get<int>(), 0);
  const auto later_errors = pageErrors(browser.messages(), true);
  EXPECT_TRUE(later_errors.empty()) << later_errors.front();

  bots.signal(SIGINT);
  bots.wait(10.0);
  server->signal(SIGTERM);
  EXPECT_EQ(server->wait(10.0).value_or(-999), 0) << logOf(dir_ + "/server2.log");
}

// A page opened with ?visible=1 on a server with --web-members joins as a member: the
// room then lists it beside the bot (at its camera, a camera-headed avatar), the page hides
// its own avatar, and the member goes with the page.
TEST_F(SpectatorBrowser, VisiblePageJoinsTheRoomAndLeavesWithIt) {
  const std::string chromium = test::findChromium();
  if (chromium.empty()) {
    GTEST_SKIP() << "no chromium found (install Debian's chromium: scripts/setup; or set "
                    "VISTEL_CHROMIUM): the visible spectator is not tested in a browser";
  }
  test::Program server("vistel-server", {"--port", "0", "--web-port", "0", "--web-members"},
                       dir_ + "/server.log", true);
  const std::string address = test::serverAddress(server);
  ASSERT_FALSE(address.empty()) << logOf(dir_ + "/server.log");
  const std::string web = webAddress(server);
  ASSERT_FALSE(web.empty()) << logOf(dir_ + "/server.log");
  const auto web_port = static_cast<std::uint16_t>(std::stoi(web.substr(web.rfind(':') + 1)));
  test::Program bots("vistel-bot",
                     {"--server", address, "--room", "it", "--name", "b", "--bvh", bvh_path_,
                      "--avatar", avatar_path_, "--loop"},
                     dir_ + "/bots.log", false);

  test::HeadlessChromium browser(chromium, dir_ + "/profile", dir_ + "/chromium.log");
  ASSERT_TRUE(browser.ok()) << browser.error() << "\n" << logOf(dir_ + "/chromium.log");
  ASSERT_FALSE(browser.call("Runtime.enable").is_null()) << browser.error();
  ASSERT_FALSE(browser.call("Page.enable").is_null()) << browser.error();
  ASSERT_FALSE(
      browser.call("Page.navigate", {{"url", "http://" + web + "/room/it?visible=1&name=Cam"}})
          .is_null())
      << browser.error();
  nlohmann::json scene;
  ASSERT_TRUE(waitForScene(browser, 20.0, scene,
                           [](const nlohmann::json& s) {
                             return s["visible"].value("state", "") == "live" &&
                                    s["visible"].value("posesSent", 0) >= 3 &&
                                    s["members"].size() == 2 && loadedMembers(s) >= 1;
                           }))
      << "scene: " << scene.dump() << "\n"
      << logOf(dir_ + "/server.log");
  std::printf("[ measure  ] visible: %s\n", scene["visible"].dump().c_str());
  EXPECT_EQ(scene["visible"]["name"], "Cam (spectator)");
  EXPECT_TRUE(scene["errors"].empty()) << scene["errors"].dump();
  const int self = scene["visible"]["id"].get<int>();
  // The page does not draw its own member (it stands at the camera); the bot it does.
  for (const auto& m : scene["members"]) {
    const bool own = m["id"].get<int>() == self;
    EXPECT_EQ(m["name"], own ? "Cam (spectator)" : "b");
    EXPECT_EQ(m.value("hidden", false), own) << m.dump();
  }
  // The room, as the server lists it: the bot and the page's member.
  const std::string rooms = test::httpGet(web_port, "/api/rooms");
  EXPECT_NE(rooms.find("Cam (spectator)"), std::string::npos) << rooms;
  EXPECT_NE(rooms.find("\"b\""), std::string::npos) << rooms;

  // Until `present` says whether the member is listed, or 5 s pass: the room list.
  const auto listedUntil = [&](bool present) {
    std::string list;
    for (int i = 0; i < 50; ++i) {
      list = test::httpGet(web_port, "/api/rooms");
      if ((list.find("Cam (spectator)") != std::string::npos) == present) break;
      std::this_thread::sleep_for(std::chrono::milliseconds(100));
    }
    return list;
  };
  // The toggle: off leaves the room (the bot stays), on joins again.
  browser.evaluate("document.getElementById('visible').click(), 1");
  std::string after = listedUntil(false);
  EXPECT_EQ(after.find("Cam (spectator)"), std::string::npos)
      << after << logOf(dir_ + "/server.log");
  EXPECT_NE(after.find("\"b\""), std::string::npos) << after;
  browser.evaluate("document.getElementById('visible').click(), 1");
  after = listedUntil(true);
  EXPECT_NE(after.find("Cam (spectator)"), std::string::npos)
      << after << logOf(dir_ + "/server.log");
  // The page goes: so does its member.
  browser.evaluate("location.href = 'about:blank', 1");
  after = listedUntil(false);
  EXPECT_EQ(after.find("Cam (spectator)"), std::string::npos)
      << after << logOf(dir_ + "/server.log");
  bots.signal(SIGINT);
  bots.wait(10.0);
  server.signal(SIGTERM);
  EXPECT_EQ(server.wait(10.0).value_or(-999), 0) << logOf(dir_ + "/server.log");
}

}  // namespace
}  // namespace vistel
