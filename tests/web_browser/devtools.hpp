// A headless Chromium for tests, driven over the DevTools protocol (a WebSocket): started
// in its own process group with a scratch profile, stopped (the whole group) when the
// object goes. Synchronous: each call waits for its answer (at most timeout_s) and keeps
// the events that arrived meanwhile (console messages, exceptions, log entries).
#pragma once

#include <sys/types.h>

#include <optional>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

namespace vistel::test {

// The chromium binary: $VISTEL_CHROMIUM, else the first of chromium, chromium-browser,
// google-chrome on PATH or in /usr/bin; empty when there is none.
std::string findChromium();

// What the page said on its console or the browser logged, one line each.
struct BrowserMessage {
  std::string kind;    // "console", "exception", "log"
  std::string level;   // console type ("error", "warning", "log", ...) or log level
  std::string source;  // log entries: "network", "javascript", "rendering", ...
  std::string text;
};

class HeadlessChromium {
 public:
  // Starts chromium (800 x 600, SwiftShader WebGL) on about:blank with its log in
  // log_path, and connects to its page. ok() says whether that worked; error() why.
  HeadlessChromium(const std::string& binary, const std::string& profile_dir,
                   const std::string& log_path);
  ~HeadlessChromium();
  HeadlessChromium(const HeadlessChromium&) = delete;
  HeadlessChromium& operator=(const HeadlessChromium&) = delete;

  bool ok() const { return connected_; }
  const std::string& error() const { return error_; }

  // A DevTools command; its "result" (null with error() set on failure).
  nlohmann::json call(const std::string& method, nlohmann::json params = nlohmann::json::object(),
                      double timeout_s = 20.0);
  // A JavaScript expression's value (JSON-serialisable), or null.
  nlohmann::json evaluate(const std::string& expression);
  // The page as PNG bytes (empty on failure).
  std::vector<std::uint8_t> screenshot();

  const std::vector<BrowserMessage>& messages() const { return messages_; }

 private:
  struct Socket;
  pid_t pid_ = -1;
  std::string log_path_;
  std::string error_;
  bool connected_ = false;
  int next_id_ = 1;
  Socket* socket_ = nullptr;
  std::vector<BrowserMessage> messages_;
};

}  // namespace vistel::test
