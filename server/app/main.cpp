// vistel-server: the session server (DESIGN.md §6).
//   vistel-server [--port 7400] [--config config/server.toml] [--bind ADDRESS]
//                 [--log-level LEVEL] [--stats-json FILE] [--metrics-port P] [--agones]
//   vistel-server --version   (the project version and the protocol versions it speaks)
// Prints "vistel-server listening on ADDRESS:PORT" on stdout once both sockets are
// bound (port 0 picks a free one), logs to stderr, and shuts down cleanly on SIGINT or
// SIGTERM (every client is told, sockets close, exit status 0). --stats-json writes the
// server's load since the start (LoadStats::totalsJson) to FILE when it stops.
// --metrics-port serves /healthz, /readyz and Prometheus /metrics on that TCP port of the
// bind address (0: a free one, printed as "vistel-server metrics on ADDRESS:PORT");
// --agones reports to the Agones SDK sidecar (ready, health pings, shutdown; deploy/).
// --secret-file F (or [auth] secret_file) requires a join token in every Join, signed with
// the secret in F (at least 32 bytes; proto/SESSION.md §2.3); without one the server says
// at start that rooms are open. `vistel-server token --secret-file F --room R --name N
// [--ttl 1h]` prints such a token on stdout (ttl: seconds, or with a unit s, m, h, d).
// --tls-cert F --tls-key F (or [tls] cert_file, key_file) runs the control channel over
// TLS 1.2+ with that certificate chain and key (PEM); clients then need --tls.
// --web-port P (or [web] port) serves the room list, spectator pages and avatars over HTTP
// and WebSocket on that TCP port (0: a free one, printed as "vistel-server web on
// http://ADDRESS:PORT/"); server/web/web_server.hpp. --web-members (or [web] members) lets
// those pages join their room as visible members (server/web/web_member.hpp).
// --record-room DIR records every room as a skinned glTF animation DIR/<room>-<start>.glb,
// written when the room empties or the server stops (server/record/server_recorder.hpp);
// --record-rate HZ samples per second (default 30), --record-max-s S caps each room's
// recording (default 1800 s; a warning when reached).
#include <atomic>
#include <cstdio>
#include <memory>
#include <thread>
#include <vector>

#include <spdlog/sinks/stdout_color_sinks.h>
#include <spdlog/spdlog.h>
#include <CLI/CLI.hpp>

#include "common/auth/secret_file.hpp"
#include "common/auth/token_command.hpp"
#include "common/base/embedded.hpp"
#include "common/base/file.hpp"
#include "common/wire/packets.hpp"
#include "server/core/server_config.hpp"
#include "server/http/agones_sdk.hpp"
#include "server/http/http_endpoint.hpp"
#include "server/http/prometheus.hpp"
#include "server/record/server_recorder.hpp"
#include "server/shell/asio.hpp"
#include "server/shell/server_shell.hpp"
#include "server/web/web_config.hpp"
#include "server/web/web_server.hpp"
#include "vistel_version.hpp"

int main(int argc, char** argv) {
  using namespace vistel;
  using namespace vistel::server;

  // Command line (explicit options override the config file).
  CLI::App app{"vistel session server: rooms, postures over UDP, control over TCP"};
  std::string config_path = "config/server.toml";
  int port = -1;
  std::string bind;
  std::string log_level;
  std::string stats_json;
  int metrics_port = -1;
  bool agones = false;
  app.add_option("--config", config_path, "server settings (TOML); built-in defaults if absent");
  app.add_option("--port", port, "TCP and UDP port (0: any free port; default from config: 7400)")
      ->check(CLI::Range(0, 65535));
  app.add_option("--bind", bind, "listen address (default from config: 127.0.0.1)");
  app.add_option("--log-level", log_level, "trace, debug, info, warn, error, off");
  app.add_option("--stats-json", stats_json,
                 "write the load (ticks, CPU, datagrams) as JSON to this file at shutdown");
  app.add_option("--metrics-port", metrics_port,
                 "serve /healthz, /readyz and /metrics on this TCP port (0: a free port)")
      ->check(CLI::Range(0, 65535));
  int web_port = -2;
  app.add_option("--web-port", web_port,
                 "serve the room list, spectator pages (3D, in a browser) and avatars over "
                 "HTTP and WebSocket on this TCP port (0: a free port; default from config "
                 "[web] port: none)")
      ->check(CLI::Range(0, 65535));
  bool web_members = false;
  app.add_flag("--web-members", web_members,
               "let spectator pages join their room as visible members (a camera-headed "
               "avatar at the viewer's camera; default from config [web] members: off)");
  ServerRecordOptions record_options;
  app.add_option("--record-room", record_options.dir,
                 "record every room as a skinned glTF animation DIR/<room>-<start>.glb, "
                 "written when the room empties or the server stops (DIR must exist)");
  app.add_option("--record-rate", record_options.rate_hz,
                 "--record-room samples per second (default 30)")
      ->check(CLI::Range(1.0, 240.0));
  app.add_option("--record-max-s", record_options.max_duration_s,
                 "--record-room: seconds recorded per room at most (default 1800; a warning "
                 "when reached)")
      ->check(CLI::PositiveNumber);
  app.add_flag("--agones", agones,
               "report to the Agones SDK sidecar at localhost:$AGONES_SDK_HTTP_PORT");
  std::string secret_file;
  app.add_option("--secret-file", secret_file,
                 "require a join token signed with the secret in this file in every Join "
                 "(at least 32 bytes; default from config [auth] secret_file: none, rooms open)");
  std::string tls_cert, tls_key;
  auto* cert_opt = app.add_option("--tls-cert", tls_cert,
                                  "serve the control channel over TLS with this certificate "
                                  "chain (PEM; with --tls-key; default from config [tls])");
  auto* key_opt = app.add_option("--tls-key", tls_key, "the private key of --tls-cert (PEM)");
  cert_opt->needs(key_opt);
  key_opt->needs(cert_opt);
  auth::TokenRequest token_request;
  CLI::App* token_cmd = app.add_subcommand(
      "token", "print a join token for a room and a name, signed with the server's secret");
  token_cmd->add_option("--secret-file", token_request.secret_file, "the server's secret file")
      ->required();
  token_cmd->add_option("--room", token_request.room, "the room it admits to")->required();
  token_cmd->add_option("--name", token_request.name, "the member name it admits")->required();
  token_cmd->add_option(
      "--ttl", token_request.ttl,
      "how long it is valid: seconds, or a number with s, m, h or d (default 1h)");
  app.set_version_flag("--version",
                       versionLine("vistel-server", kProtocolVersion, wire::kWireVersion));
  CLI11_PARSE(app, argc, argv);
  if (token_cmd->parsed()) {
    auto issued = auth::issueJoinToken(token_request, auth::unixNow());
    if (!issued) {
      std::fprintf(stderr, "vistel-server token: %s\n", issued.error().message.c_str());
      return 1;
    }
    if (!issued->warning.empty()) {
      std::fprintf(stderr, "vistel-server token: warning: %s\n", issued->warning.c_str());
    }
    std::printf("%s\n", issued->token.c_str());
    return 0;
  }

  spdlog::set_default_logger(spdlog::stderr_color_mt("vistel-server"));
  auto config = loadServerConfig(config_path);
  if (!config) {
    spdlog::error("{}", config.error().message);
    return 1;
  }
  // [web] is read by server/web from the same text (loadServerConfig skips it).
  auto config_text = readConfigText(config_path);
  Result<WebConfig> web_config = config_text ? parseWebConfig(*config_text, config_path)
                                             : Result<WebConfig>(config_text.error());
  if (!web_config) {
    spdlog::error("{}", web_config.error().message);
    return 1;
  }
  if (web_port >= 0) web_config->port = web_port;
  if (web_members) web_config->members = true;
  if (port >= 0) config->port = static_cast<std::uint16_t>(port);
  if (!bind.empty()) config->bind_address = bind;
  if (!log_level.empty()) {
    // spdlog reads an unknown name as "off": refuse it rather than go silent.
    if (log_level != "off" && spdlog::level::from_str(log_level) == spdlog::level::off) {
      spdlog::error("--log-level '{}': expected trace, debug, info, warn, error or off", log_level);
      return 2;
    }
    config->log_level = log_level;
  }
  spdlog::set_level(spdlog::level::from_str(config->log_level));
  if (!tls_cert.empty()) {
    config->tls_cert_file = tls_cert;
    config->tls_key_file = tls_key;
  }
  if (!secret_file.empty()) config->secret_file = secret_file;
  if (!config->secret_file.empty()) {
    auto secret = auth::readJoinSecret(config->secret_file);
    if (!secret) {
      spdlog::error("{}", secret.error().message);
      return 1;
    }
    if (!secret->warning.empty()) spdlog::warn("{}", secret->warning);
    config->join_secret = std::move(secret->bytes);
  }

  // Sockets, then the address line (tests and scripts parse it).
  asio::io_context io;
  ServerShell shell(io, *config);
  if (Status st = shell.start(); !st) {
    spdlog::error("{}", st.error().message);
    return 1;
  }
  std::printf("vistel-server listening on %s\n", shell.localAddress().c_str());
  std::fflush(stdout);
  spdlog::info("listening on {} (TCP control, UDP postures), {} Hz ticks, {} I/O threads",
               shell.localAddress(), config->tick_rate_hz, config->io_threads);
  if (!config->tls_cert_file.empty()) {
    spdlog::info("control channel over TLS (certificate {})", config->tls_cert_file);
  }
  if (config->join_secret.empty()) {
    spdlog::warn(
        "rooms are open: anyone who reaches {} can join any room (--secret-file requires join "
        "tokens)",
        shell.localAddress());
  } else {
    spdlog::info("join tokens required (secret from {})", config->secret_file);
  }

  // Health, readiness and metrics; the orchestrator's sidecar.
  std::atomic<bool> ready{false};
  std::unique_ptr<HttpEndpoint> http;
  std::unique_ptr<WebServer> web;  // started below; its figures join /metrics
  if (metrics_port >= 0) {
    HttpHandlers handlers;
    handlers.ready = [&ready] { return ready.load(); };
    handlers.metrics = [&shell, &ready, &web](MetricsReply reply) {
      shell.collectMetrics(
          [&web, reply = std::move(reply)](std::string text) {
            if (web) text += formatPrometheus(web->metricFamilies());
            reply(std::move(text));
          },
          ready.load());
    };
    auto started = HttpEndpoint::start(io, config->bind_address,
                                       static_cast<std::uint16_t>(metrics_port), handlers);
    if (!started) {
      spdlog::error("--metrics-port: {}", started.error().message);
      return 1;
    }
    http = std::move(*started);
    std::printf("vistel-server metrics on %s\n", http->localAddress().c_str());
    std::fflush(stdout);
  }
  // Spectators: the room list, pages and WebSockets (server/web).
  if (web_config->port >= 0) {
    WebServerOptions web_options;
    web_options.config = *web_config;
    web_options.bind_address = config->bind_address;
    web_options.seat_layout = config->seat_layout;
    web_options.tick_rate_hz = config->tick_rate_hz;
    web_options.join_secret = config->join_secret;
    web_options.session_port = shell.localPort();
    web_options.tls_cert_file = config->tls_cert_file;
    auto started = WebServer::start(io, shell, std::move(web_options));
    if (!started) {
      spdlog::error("--web-port: {}", started.error().message);
      return 1;
    }
    web = std::move(*started);
    std::printf("vistel-server web on http://%s/\n", web->localAddress().c_str());
    std::fflush(stdout);
  }
  // Recordings of the rooms (server/record).
  std::unique_ptr<ServerRecorder> recorder;
  if (!record_options.dir.empty()) {
    record_options.seat_layout = config->seat_layout;
    auto started = ServerRecorder::start(io, shell, record_options);
    if (!started) {
      spdlog::error("{}", started.error().message);
      return 1;
    }
    recorder = std::move(*started);
    spdlog::info("recording rooms into {} ({} samples/s, at most {} s per room)",
                 record_options.dir, record_options.rate_hz, record_options.max_duration_s);
  }
  std::unique_ptr<AgonesSdk> sdk;
  if (agones) {
    auto options = agonesOptionsFromEnvironment();
    if (!options) {
      spdlog::error("--agones: {}", options.error().message);
      return 1;
    }
    sdk = std::make_unique<AgonesSdk>(io, *options);
    // A closed room frees its slot in the GameServer's "rooms" list (the allocation added
    // it; deploy/README.md).
    shell.onRoomClosed([sdk = sdk.get()](const std::string& room) {
      sdk->removeListValue("rooms", room, [room](Status st) {
        if (!st)
          spdlog::warn("Agones: room '{}' not removed from the list: {}", room, st.error().message);
      });
    });
    sdk->ready([](Status st) {
      if (!st) spdlog::error("Agones: {}", st.error().message);
    });
    sdk->startHealth();
  }
  ready = true;

  // SIGINT/SIGTERM: graceful stop; io.run() returns when everything is closed.
  asio::signal_set signals(io, SIGINT, SIGTERM);
  signals.async_wait([&](const boost::system::error_code& ec, int signal) {
    if (ec) return;
    spdlog::info("signal {} received", signal);
    ready = false;
    if (http) http->stop();
    if (web) web->stop();
    if (recorder) recorder->stop();
    if (sdk) sdk->stop();
    shell.stop();
  });

  auto run = [&io] {
    while (true) {
      try {
        io.run();
        return;
      } catch (const std::exception& e) {
        spdlog::error("I/O thread: unexpected exception: {}", e.what());
      }
    }
  };
  std::vector<std::thread> threads;
  for (int i = 1; i < config->io_threads; ++i) threads.emplace_back(run);
  run();
  for (std::thread& t : threads) t.join();
  http.reset();
  web.reset();
  sdk.reset();
  if (recorder) {
    // The rooms still open when the server stopped.
    recorder->writeAll();
    const ServerRecorder::Stats rs = recorder->stats();
    spdlog::info("record: {} files written, {} failed", rs.files_written, rs.write_errors);
    recorder.reset();
  }
  if (!stats_json.empty()) {
    if (Status st = writeFileText(stats_json, shell.loadJson() + "\n"); !st) {
      spdlog::error("--stats-json: {}", st.error().message);
      return 1;
    }
  }
  spdlog::info("shut down cleanly");
  return 0;
}
