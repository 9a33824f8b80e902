// A client of the Agones SDK sidecar's REST gateway (Agones runs one beside every game
// server process in its Pod; https://agones.dev, "REST Game Server Client API"). It
// listens on localhost at $AGONES_SDK_HTTP_PORT (default 9358) and takes JSON bodies:
//   POST /ready      {}                        the server accepts players
//   POST /health     {}                        a health ping (at least every periodSeconds)
//   POST /shutdown   {}                        the server is done; Agones deletes the Pod
//   POST /allocate   {}                        mark itself Allocated (not scaled down)
//   PUT  /metadata/label       {"key","value"} label "agones.dev/sdk-<key>" on the GameServer
//   PUT  /metadata/annotation  {"key","value"} annotation "agones.dev/sdk-<key>"
//   POST /v1beta1/lists/<list>:addValue     {"value"}  (Counters and Lists, Beta since 1.41)
//   POST /v1beta1/lists/<list>:removeValue  {"value"}
//
// Every call is asynchronous on the io_context the server already runs; completion
// callbacks run on one of its threads. Health pings come from a timer on that io_context,
// so they stop when the event loop stalls and Agones marks the GameServer Unhealthy.
// ready() retries (the sidecar may start after the server), the rest try once.
// Every method may be called from any thread (each posts to the io_context). Destroy the
// AgonesSdk before the io_context; call stop() before expecting io.run() to return, since
// the health timer (and ready() retries) keep it busy; requests in flight end within
// request_timeout_s.
#pragma once

#include <cstdint>
#include <functional>
#include <memory>
#include <string>
#include <string_view>

#include "common/base/result.hpp"
#include "server/shell/asio.hpp"

namespace vistel::server {

struct AgonesSdkOptions {
  std::string host = "127.0.0.1";
  std::uint16_t port = 9358;       // $AGONES_SDK_HTTP_PORT
  double health_interval_s = 2.0;  // below the GameServer's health.periodSeconds (fleet: 5)
  double request_timeout_s = 2.0;  // per request
  int ready_attempts = 20;         // tries of POST /ready, 0.25 s doubling to 2 s apart
};

// Options with the port from $AGONES_SDK_HTTP_PORT when set (an error names a bad value).
Result<AgonesSdkOptions> agonesOptionsFromEnvironment();

// Parses a port number "1".."65535" (no sign, no spaces).
Result<std::uint16_t> parsePort(std::string_view text);

// Checks key and value against what Agones will store: the label key becomes
// "agones.dev/sdk-<key>", whose name part (after the '/') must be at most 63 characters
// of [A-Za-z0-9-_.] beginning and ending with an alphanumeric; the value at most 63 such
// characters, or empty.
Status validateAgonesLabel(std::string_view key, std::string_view value);

class AgonesSdk {
 public:
  using Done = std::function<void(Status)>;

  AgonesSdk(asio::io_context& io, AgonesSdkOptions options);
  ~AgonesSdk();  // stop(); requests in flight still complete
  AgonesSdk(const AgonesSdk&) = delete;
  AgonesSdk& operator=(const AgonesSdk&) = delete;

  // POST /ready, retried up to options.ready_attempts times on failure.
  void ready(Done done = {});
  // POST /health now and every options.health_interval_s until stopHealth().
  void startHealth();
  void stopHealth();
  // Stops health pings and ready() retries for good (a pending ready() completes with its
  // last error). For a graceful exit: call on SIGTERM beside ServerShell::stop().
  void stop();
  // POST /shutdown (stops the health pings first).
  void shutdown(Done done = {});
  // POST /allocate: the GameServer becomes Allocated, so a scale-down cannot remove it
  // (for a room opened without a GameServerAllocation).
  void allocate(Done done = {});
  // PUT /metadata/label; an invalid key or value fails without a request.
  void setLabel(std::string key, std::string value, Done done = {});
  // PUT /metadata/annotation (the key is checked like a label key; any value).
  void setAnnotation(std::string key, std::string value, Done done = {});
  // POST /v1beta1/lists/<list>:addValue / :removeValue (the list must be declared in the
  // GameServer spec; see deploy/agones/fleet.yaml; the name is checked like a label).
  void addListValue(std::string list, std::string value, Done done = {});
  void removeListValue(std::string list, std::string value, Done done = {});

  std::uint64_t healthPingsSent() const;    // answered 2xx
  std::uint64_t healthPingsFailed() const;  // errors and non-2xx answers

  struct Impl;

 private:
  void failLater(std::string message, const Done& done);  // done(Error) on the strand
  std::shared_ptr<Impl> impl_;
};

}  // namespace vistel::server
