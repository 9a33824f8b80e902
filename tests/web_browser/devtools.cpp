#include "tests/web_browser/devtools.hpp"

#include <fcntl.h>
#include <signal.h>
#include <spawn.h>
#include <sys/socket.h>
#include <sys/time.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <cstdlib>
#include <filesystem>
#include <regex>
#include <thread>
#include <utility>

#include <boost/asio.hpp>
#include <boost/beast/core.hpp>
#include <boost/beast/http.hpp>
#include <boost/beast/websocket.hpp>

#include "common/auth/join_token.hpp"
#include "common/base/file.hpp"

extern char** environ;

namespace vistel::test {
namespace {

namespace asio = boost::asio;
namespace beast = boost::beast;
namespace http = boost::beast::http;
namespace websocket = boost::beast::websocket;
using tcp = asio::ip::tcp;

void setReceiveTimeout(tcp::socket& socket, double seconds) {
  timeval tv{static_cast<time_t>(seconds),
             static_cast<suseconds_t>((seconds - static_cast<time_t>(seconds)) * 1e6)};
  ::setsockopt(socket.native_handle(), SOL_SOCKET, SO_RCVTIMEO, &tv, sizeof tv);
}

// Standard base64 (with padding) as the DevTools protocol sends binary data.
std::vector<std::uint8_t> base64Decode(std::string text) {
  for (char& c : text) {
    if (c == '+') c = '-';
    if (c == '/') c = '_';
  }
  while (!text.empty() && text.back() == '=') text.pop_back();
  auto bytes = auth::base64UrlDecode(text);
  return bytes ? *bytes : std::vector<std::uint8_t>{};
}

}  // namespace

struct HeadlessChromium::Socket {
  asio::io_context io;
  websocket::stream<tcp::socket> ws{io};
};

std::string findChromium() {
  if (const char* env = std::getenv("VISTEL_CHROMIUM"); env != nullptr && *env != '\0') {
    return std::filesystem::exists(env) ? std::string(env) : std::string();
  }
  std::vector<std::string> dirs;
  if (const char* path = std::getenv("PATH")) {
    std::string p = path;
    for (std::size_t at = 0; at <= p.size();) {
      const std::size_t colon = p.find(':', at);
      dirs.push_back(p.substr(at, colon == std::string::npos ? std::string::npos : colon - at));
      if (colon == std::string::npos) break;
      at = colon + 1;
    }
  }
  dirs.push_back("/usr/bin");
  for (const char* name : {"chromium", "chromium-browser", "google-chrome"}) {
    for (const std::string& dir : dirs) {
      const std::string candidate = dir + "/" + name;
      if (!dir.empty() && ::access(candidate.c_str(), X_OK) == 0) return candidate;
    }
  }
  return {};
}

HeadlessChromium::HeadlessChromium(const std::string& binary, const std::string& profile_dir,
                                   const std::string& log_path)
    : log_path_(log_path) {
  // The flags of ECOSYSTEM.md, with SwiftShader picked through ANGLE (Chromium 156 refuses
  // --use-gl=swiftshader and falls back after a GPU process error).
  std::vector<std::string> args = {binary,
                                   "--headless=new",
                                   "--no-sandbox",
                                   "--use-angle=swiftshader",
                                   "--enable-unsafe-swiftshader",
                                   "--no-first-run",
                                   "--no-default-browser-check",
                                   "--disable-extensions",
                                   "--disable-background-networking",
                                   "--disable-component-update",
                                   "--disable-sync",
                                   "--mute-audio",
                                   "--hide-scrollbars",
                                   "--window-size=800,600",
                                   "--remote-debugging-address=127.0.0.1",
                                   "--remote-debugging-port=0",
                                   "--remote-allow-origins=*",
                                   "--user-data-dir=" + profile_dir,
                                   "about:blank"};
  std::vector<char*> argv;
  for (auto& a : args) argv.push_back(a.data());
  argv.push_back(nullptr);
  posix_spawn_file_actions_t actions;
  posix_spawn_file_actions_init(&actions);
  posix_spawn_file_actions_addopen(&actions, 1, log_path.c_str(), O_WRONLY | O_CREAT | O_TRUNC,
                                   0644);
  posix_spawn_file_actions_adddup2(&actions, 1, 2);
  posix_spawnattr_t attr;
  posix_spawnattr_init(&attr);
  posix_spawnattr_setflags(&attr, POSIX_SPAWN_SETPGROUP);
  posix_spawnattr_setpgroup(&attr, 0);  // its own group: stopped with all its children
  const int rc = posix_spawn(&pid_, argv[0], &actions, &attr, argv.data(), environ);
  posix_spawn_file_actions_destroy(&actions);
  posix_spawnattr_destroy(&attr);
  if (rc != 0) {
    pid_ = -1;
    error_ = "cannot start " + binary;
    return;
  }

  // "DevTools listening on ws://127.0.0.1:PORT/devtools/browser/ID" on its stderr.
  std::string port;
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(20);
  const std::regex listening("DevTools listening on ws://[^:]+:([0-9]+)/");
  while (port.empty() && std::chrono::steady_clock::now() < deadline) {
    if (auto text = readFileText(log_path)) {
      std::smatch m;
      if (std::regex_search(*text, m, listening)) port = m[1];
    }
    if (port.empty()) std::this_thread::sleep_for(std::chrono::milliseconds(50));
  }
  if (port.empty()) {
    error_ = "chromium printed no DevTools address within 20 s";
    return;
  }

  // The page target's WebSocket address, from /json/list.
  socket_ = new Socket;
  try {
    std::string page_path;
    for (int attempt = 0; attempt < 50 && page_path.empty(); ++attempt) {
      tcp::socket s(socket_->io);
      s.connect(tcp::endpoint(asio::ip::make_address("127.0.0.1"),
                              static_cast<std::uint16_t>(std::stoi(port))));
      setReceiveTimeout(s, 10.0);
      http::request<http::empty_body> req(http::verb::get, "/json/list", 11);
      req.set(http::field::host, "127.0.0.1");
      http::write(s, req);
      beast::flat_buffer buffer;
      http::response<http::string_body> res;
      http::read(s, buffer, res);
      for (const auto& target : nlohmann::json::parse(res.body())) {
        if (target.value("type", "") == "page") {
          const std::string url = target.value("webSocketDebuggerUrl", "");
          const std::size_t path_at = url.find("/devtools/");
          if (path_at != std::string::npos) page_path = url.substr(path_at);
          break;
        }
      }
      if (page_path.empty()) std::this_thread::sleep_for(std::chrono::milliseconds(100));
    }
    if (page_path.empty()) {
      error_ = "chromium lists no page target";
      return;
    }
    auto& ws = socket_->ws;
    ws.next_layer().connect(tcp::endpoint(asio::ip::make_address("127.0.0.1"),
                                          static_cast<std::uint16_t>(std::stoi(port))));
    setReceiveTimeout(ws.next_layer(), 30.0);
    ws.read_message_max(64u << 20);  // screenshots
    ws.handshake("127.0.0.1:" + port, page_path);
    connected_ = true;
  } catch (const std::exception& e) {
    error_ = std::string("DevTools connection failed: ") + e.what();
  }
}

HeadlessChromium::~HeadlessChromium() {
  if (socket_ != nullptr) {
    beast::error_code ignored;
    socket_->ws.next_layer().close(ignored);
    delete socket_;
  }
  if (pid_ > 0) {
    // The whole group (the browser and its renderer, GPU and zygote processes): asked to
    // stop, then killed if it has not within 2.5 s.
    const pid_t group = pid_;
    ::kill(-group, SIGTERM);
    bool exited = false;
    for (int i = 0; i < 50 && !exited; ++i) {
      exited = ::waitpid(pid_, nullptr, WNOHANG) == pid_;
      if (!exited) std::this_thread::sleep_for(std::chrono::milliseconds(50));
    }
    ::kill(-group, SIGKILL);  // leftovers of the group (none when it stopped cleanly)
    if (!exited) ::waitpid(pid_, nullptr, 0);
  }
}

nlohmann::json HeadlessChromium::call(const std::string& method, nlohmann::json params,
                                      double timeout_s) {
  if (!connected_) return nullptr;
  const int id = next_id_++;
  const nlohmann::json request = {{"id", id}, {"method", method}, {"params", std::move(params)}};
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::duration<double>(timeout_s);
  try {
    auto& ws = socket_->ws;
    ws.text(true);
    ws.write(asio::buffer(request.dump()));
    while (std::chrono::steady_clock::now() < deadline) {
      beast::flat_buffer buffer;
      ws.read(buffer);
      const auto message = nlohmann::json::parse(beast::buffers_to_string(buffer.data()));
      if (message.contains("id")) {
        if (message["id"] != id) continue;
        if (message.contains("error")) {
          error_ = method + ": " + message["error"].dump();
          return nullptr;
        }
        return message.value("result", nlohmann::json::object());
      }
      // An event.
      const std::string event = message.value("method", "");
      const auto& p = message.contains("params") ? message["params"] : nlohmann::json::object();
      if (event == "Runtime.consoleAPICalled") {
        std::string text;
        for (const auto& a : p.value("args", nlohmann::json::array())) {
          if (!text.empty()) text += " ";
          text += a.contains("value")
                      ? (a["value"].is_string() ? a["value"].get<std::string>() : a["value"].dump())
                      : a.value("description", "");
        }
        messages_.push_back({"console", p.value("type", ""), "", text});
      } else if (event == "Runtime.exceptionThrown") {
        const auto& d = p.value("exceptionDetails", nlohmann::json::object());
        std::string text = d.value("text", "");
        if (d.contains("exception")) text += " " + d["exception"].value("description", "");
        messages_.push_back({"exception", "error", "", text});
      } else if (event == "Log.entryAdded") {
        const auto& e = p.value("entry", nlohmann::json::object());
        messages_.push_back(
            {"log", e.value("level", ""), e.value("source", ""), e.value("text", "")});
      }
    }
    error_ = method + ": no answer within the timeout";
  } catch (const std::exception& e) {
    error_ = method + ": " + e.what();
  }
  return nullptr;
}

nlohmann::json HeadlessChromium::evaluate(const std::string& expression) {
  const auto result =
      call("Runtime.evaluate",
           {{"expression", "JSON.stringify(" + expression + ")"}, {"returnByValue", true}});
  if (result.is_null() || !result.contains("result")) return nullptr;
  const auto& value = result["result"];
  if (!value.contains("value") || !value["value"].is_string()) return nullptr;
  try {
    return nlohmann::json::parse(value["value"].get<std::string>());
  } catch (const std::exception&) {
    return nullptr;
  }
}

std::vector<std::uint8_t> HeadlessChromium::screenshot() {
  const auto result = call("Page.captureScreenshot", {{"format", "png"}});
  if (result.is_null() || !result.contains("data")) return {};
  return base64Decode(result["data"].get<std::string>());
}

}  // namespace vistel::test
