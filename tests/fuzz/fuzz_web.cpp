// libFuzzer target: the spectator web server's parsing (server/web) on arbitrary bytes:
// request heads with the server's parser settings (web_beast.hpp), what a head gets
// (judgeRequest), request targets and query parameters, and WebSocket frames from a
// browser read by a server-side Beast stream with the server's message limit.
//
// Properties: nothing crashes or reads out of bounds; a rejected head names 400 or 431;
// a judged request gets 0 (served) or one of 400, 403, 404, 405, 413, 414, 426, and a served
// one has a known route with a valid room name, a 64-hex hash or an asset name; decoded
// text holds no control characters; no WebSocket message read is longer than the limit;
// Host headers (hostAllowed, parseAllowedHosts) and a visible spectator's messages
// (parseSpectatorMessage: a pose within its documented ranges, a sanitised member name
// that the lobby's name rule accepts) never crash either.
#include <cstdint>
#include <string>
#include <string_view>
#include <vector>

#include <cmath>

#include "common/auth/member_name.hpp"
#include "server/web/web_beast.hpp"
#include "server/web/web_member.hpp"
#include "server/web/web_request.hpp"
#include "tests/fuzz/fuzz_support.hpp"

#include <boost/beast/_experimental/test/stream.hpp>

namespace {

using namespace vistel;
using namespace vistel::server;
using fuzz::check;

constexpr std::size_t kHeaderLimit = 1024;
constexpr std::size_t kMessageLimit = 1024;
const std::string kUpgrade =
    "GET /ws/room/lab HTTP/1.1\r\nHost: h\r\nConnection: Upgrade\r\nUpgrade: websocket\r\n"
    "Sec-WebSocket-Version: 13\r\nSec-WebSocket-Key: dGhlIHNhbXBsZSBub25jZQ==\r\n\r\n";

std::vector<fuzz::Seed> makeSeeds() {
  // A masked client text frame "hi" and a masked close.
  const std::string text_frame = std::string("\x81\x82\x01\x02\x03\x04", 6) + "\x69\x6b";
  const std::string close_frame = std::string("\x88\x82\x00\x00\x00\x00\x03\xe8", 8);
  return {
      fuzz::textSeed("get_room", "GET /room/lab?token=vt1.x HTTP/1.1\r\nHost: 127.0.0.1\r\n\r\n"),
      fuzz::textSeed("get_avatar", "GET /avatar/" + std::string(64, 'a') + ".glb HTTP/1.1\r\n\r\n"),
      fuzz::textSeed("upgrade", kUpgrade),
      fuzz::textSeed("upgrade_origin",
                     "GET /ws/room/lab HTTP/1.1\r\nHost: a:1\r\nOrigin: http://b:1\r\n"
                     "Connection: Upgrade\r\nUpgrade: websocket\r\n\r\n"),
      fuzz::textSeed("post_body", "POST / HTTP/1.1\r\nContent-Length: 2\r\n\r\n{}"),
      fuzz::textSeed("chunked", "GET / HTTP/1.1\r\nTransfer-Encoding: chunked\r\n\r\n0\r\n\r\n"),
      fuzz::textSeed("escapes", "GET /room/l%61b/%2e%2e?token=%41+%zz&a HTTP/1.0\r\n\r\n"),
      fuzz::textSeed("ws_frames", text_frame + close_frame),
      fuzz::textSeed("pose", R"({"type":"pose","x":1,"y":1.6,"z":-2,"yaw":0.5,"pitch":0.1})"),
      fuzz::textSeed("join", R"({"type":"join","name":"Ann <b>"})"),
      fuzz::textSeed("host", "[::1]:8080"),
  };
}

bool noControl(std::string_view s) {
  for (char c : s) {
    const auto u = static_cast<unsigned char>(c);
    if (u < 0x20 || u == 0x7f) return false;
  }
  return true;
}

void checkTarget(const WebTarget& t) {
  check(noControl(t.token), "a decoded token holds no control characters");
  switch (t.route) {
    case WebRoute::kRoomPage:
    case WebRoute::kRoomSocket:
      check(webRoomName(t.room), "a routed room name is valid");
      break;
    case WebRoute::kAvatar:
      check(t.hash.size() == 64, "an avatar hash has 64 characters");
      break;
    case WebRoute::kAsset:
      check(!t.asset.empty() && t.asset.size() <= 64 && t.asset.front() != '.' &&
                t.asset.find('/') == std::string::npos,
            "an asset name is a plain file name");
      break;
    default:
      break;
  }
}

// The bytes as WebSocket frames from a browser, after an accepted upgrade.
void readFrames(std::string_view bytes) {
  boost::asio::io_context io;
  beast::test::stream local(io);
  beast::test::stream remote(io);
  local.connect(remote);
  local.append(kUpgrade);  // what the browser sent: the upgrade, then the bytes as frames
  local.append(beast::string_view(bytes.data(), bytes.size()));
  local.close_remote();  // then end of stream
  websocket::stream<beast::test::stream&> ws(local);
  ws.read_message_max(kMessageLimit);
  beast::error_code ec;
  ws.accept(ec);
  check(!ec, "the upgrade is accepted");
  for (int i = 0; i < 64 && !ec; ++i) {
    beast::flat_buffer buffer;
    const std::size_t n = ws.read(buffer, ec);
    if (!ec)
      check(n <= kMessageLimit && buffer.size() <= kMessageLimit, "messages within the limit");
  }
}

}  // namespace

extern "C" int LLVMFuzzerInitialize(int* argc, char*** argv) {
  fuzz::writeSeedsIfAsked(*argc, *argv, makeSeeds);
  return 0;
}

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string_view bytes(reinterpret_cast<const char*>(data), size);

  // Request heads, as the server reads them.
  HeadError error;
  if (auto parsed = parseRequestHead(bytes, kHeaderLimit, &error)) {
    check(!parsed->head.method.empty(), "a method");
    check(parsed->version == 10 || parsed->version == 11, "HTTP/1.0 or 1.1");
    const RequestVerdict v = judgeRequest(parsed->head);
    check(v.status == 0 || v.status == 400 || v.status == 403 || v.status == 404 ||
              v.status == 405 || v.status == 413 || v.status == 414 || v.status == 426,
          "a verdict is served or one of the documented statuses");
    if (v.status == 0) {
      check(v.target.route != WebRoute::kNotFound, "a served request has a route");
      check(parsed->head.method == "GET", "only GET is served");
      check(!parsed->head.has_body, "no body is served");
      checkTarget(v.target);
    }
  } else {
    check(error.status == 400 || error.status == 431, "a rejected head names 400 or 431");
  }

  // The bytes as a target, a query and an escaped text.
  if (auto target = parseTarget(bytes)) checkTarget(*target);
  if (auto value = queryParam(bytes, "token")) check(noControl(*value), "a decoded parameter");
  if (auto text = percentDecode(bytes, true)) {
    check(noControl(*text), "decoded text holds no control characters");
    check(text->size() <= bytes.size(), "decoding never grows the text");
  }

  // Host headers and the allow-list's text.
  if (hostAllowed(bytes, {})) {
    check(bytes.empty() || bytes.find('/') == std::string_view::npos, "an allowed Host");
  }
  if (auto hosts = parseAllowedHosts(bytes)) {
    for (const std::string& h : *hosts) check(hostAllowed(h, *hosts), "a listed name passes");
  }

  // A visible spectator's message.
  if (auto msg = parseSpectatorMessage(bytes)) {
    if (msg->kind == SpectatorMessage::Kind::kPose) {
      const SpectatorPose& p = msg->pose;
      check(std::isfinite(p.x) && std::abs(p.x) <= kMaxPoseDistanceM && std::isfinite(p.y) &&
                std::abs(p.y) <= kMaxPoseDistanceM && std::isfinite(p.z) &&
                std::abs(p.z) <= kMaxPoseDistanceM,
            "a pose within range");
      check(std::abs(p.yaw) <= 3.1416 && std::abs(p.pitch) <= 1.5708, "angles within range");
    }
  }
  check(auth::validateMemberName(spectatorMemberName(bytes, 7)).ok(),
        "a spectator's member name is one the lobby takes");

  readFrames(bytes);
  return 0;
}
