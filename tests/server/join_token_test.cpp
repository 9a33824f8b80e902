// Join tokens and member names in the lobby (issue 20, finding 4): a server with a secret
// refuses a Join without a token, with a malformed, badly signed, expired or other room's
// or name's token (UNAUTHORIZED, the reason said and counted), and admits one with a good
// token; names with bidirectional controls and the like are refused naming the character;
// every refused join is counted by reason apart from other dropped connections.
#include <string>
#include <vector>

#include <gtest/gtest.h>
#include <spdlog/spdlog.h>

#include "common/auth/join_token.hpp"
#include "server/core/lobby.hpp"
#include "tests/net/sim_network.hpp"
#include "tests/net/synthetic_avatar.hpp"
#include "tests/server/control_frames.hpp"

namespace vistel::server {
namespace {

const std::vector<std::uint8_t> kSecret(48, 0xA7);
const std::vector<std::uint8_t> kOtherSecret(48, 0x11);
constexpr std::int64_t kUnixNow = 1'900'000'000;
const std::string kHash(64, 'c');

std::string tokenFor(const std::string& room, const std::string& name, std::int64_t expires_at,
                     const std::vector<std::uint8_t>& secret = kSecret) {
  auto token = auth::createJoinToken(secret, {room, name, expires_at});
  EXPECT_TRUE(token.ok());
  return token.ok() ? *token : std::string();
}

// A lobby with a secret and a fixed unix clock, fed raw Joins.
class LobbyTokens : public ::testing::Test {
 protected:
  LobbyTokens() : lobby_(configWithSecret(), 5) {
    spdlog::set_level(spdlog::level::off);
    lobby_.setUnixClock([this] { return unix_now_; });
  }
  static ServerConfig configWithSecret() {
    ServerConfig c;
    c.join_secret = kSecret;
    return c;
  }

  // Sends a Join on a new connection; the first ServerMessage back.
  control::ServerMessage join(const std::string& room, const std::string& name,
                              const std::string& token) {
    const ConnId conn = next_conn_++;
    Effects fx;
    lobby_.onConnect(conn, 0.0, fx);
    control::ClientMessage msg = test::joinMessage(room, name, kHash, 4000, kProtocolVersion);
    if (!token.empty()) msg.mutable_join()->set_token(token);
    lobby_.onStreamBytes(conn, test::frameOf(msg), 0.0, fx);
    std::vector<std::uint8_t> bytes;
    for (const OutFrame& f : fx.frames) {
      if (f.conn == conn) bytes.insert(bytes.end(), f.bytes.begin(), f.bytes.end());
    }
    const auto messages = test::messagesOf(bytes);
    EXPECT_FALSE(messages.empty());
    return messages.empty() ? control::ServerMessage{} : messages.front();
  }

  // Expects an UNAUTHORIZED refusal whose message holds `says`.
  void expectRefused(const control::ServerMessage& reply, const std::string& says) {
    ASSERT_TRUE(reply.has_error()) << reply.DebugString();
    EXPECT_EQ(reply.error().code(), control::ErrorReply::UNAUTHORIZED);
    EXPECT_NE(reply.error().message().find(says), std::string::npos) << reply.error().message();
  }

  std::uint64_t refused(const std::string& reason) const {
    auto it = lobby_.joinsRefused().find(reason);
    return it == lobby_.joinsRefused().end() ? 0 : it->second;
  }

  Lobby lobby_;
  std::int64_t unix_now_ = kUnixNow;
  ConnId next_conn_ = 1;
};

TEST_F(LobbyTokens, AGoodTokenIsAdmitted) {
  const auto reply = join("lab", "alice", tokenFor("lab", "alice", kUnixNow + 3600));
  ASSERT_TRUE(reply.has_welcome()) << reply.DebugString();
  EXPECT_EQ(lobby_.memberCount(), 1);
  EXPECT_TRUE(lobby_.joinsRefused().empty());
}

TEST_F(LobbyTokens, EveryBadTokenIsRefusedWithItsReason) {
  expectRefused(join("lab", "alice", ""), "requires a join token");
  expectRefused(join("lab", "alice", "vt1.garbage!"), "join token");
  expectRefused(join("lab", "alice", tokenFor("lab", "alice", kUnixNow + 60, kOtherSecret)),
                "bad signature");
  expectRefused(join("lab", "alice", tokenFor("lab", "alice", kUnixNow - 5)), "expired 5 s ago");
  expectRefused(join("lab", "alice", tokenFor("kitchen", "alice", kUnixNow + 60)),
                "for room 'kitchen'");
  expectRefused(join("lab", "alice", tokenFor("lab", "bob", kUnixNow + 60)), "for name 'bob'");
  EXPECT_EQ(lobby_.memberCount(), 0);
  EXPECT_EQ(lobby_.roomCount(), 0);
  // Each counted under its reason, as a refused join and as a drop.
  for (const char* reason : {"token missing", "token malformed", "token bad signature",
                             "token expired", "token wrong room", "token wrong name"}) {
    EXPECT_EQ(refused(reason), 1u) << reason;
    EXPECT_EQ(lobby_.drops().count(reason), 1u) << reason;
  }
}

TEST_F(LobbyTokens, ATokenExpiresAtItsSecond) {
  const std::string token = tokenFor("lab", "alice", kUnixNow + 10);
  unix_now_ = kUnixNow + 10;
  expectRefused(join("lab", "alice", token), "expired 0 s ago");
  unix_now_ = kUnixNow + 9;
  EXPECT_TRUE(join("lab", "alice", token).has_welcome());
}

TEST_F(LobbyTokens, ATokenForOneNameDoesNotAdmitTwoMembers) {
  const std::string token = tokenFor("lab", "alice", kUnixNow + 60);
  EXPECT_TRUE(join("lab", "alice", token).has_welcome());
  // The same token again: the name is taken (a token is not a second identity).
  const auto again = join("lab", "alice", token);
  ASSERT_TRUE(again.has_error());
  EXPECT_EQ(again.error().code(), control::ErrorReply::NAME_TAKEN);
  EXPECT_EQ(refused("NAME_TAKEN"), 1u);
}

TEST(LobbyOpen, WithoutASecretTokensAreIgnored) {
  spdlog::set_level(spdlog::level::off);
  Lobby lobby(ServerConfig{}, 5);
  Effects fx;
  lobby.onConnect(1, 0.0, fx);
  control::ClientMessage msg = test::joinMessage("lab", "alice", kHash, 4000, kProtocolVersion);
  msg.mutable_join()->set_token("not even a token");
  lobby.onStreamBytes(1, test::frameOf(msg), 0.0, fx);
  EXPECT_EQ(lobby.memberCount(), 1);
}

TEST(LobbyNames, NamesAreRefusedNamingTheCharacterAndCounted) {
  spdlog::set_level(spdlog::level::off);
  Lobby lobby(ServerConfig{}, 5);
  struct Case {
    std::string name;
    std::string says;
  };
  const std::vector<Case> cases = {
      {"\xE2\x80\xAE\xE2\x80\xAE\xE2\x80\xAE", "character 1 (U+202E) is a bidirectional control"},
      {"ali\xE2\x80\x8B"
       "ce",
       "character 4 (U+200B) is an invisible format character"},
      {"bob\x7F", "character 4 (U+007F) is a control character"},
      {" carol", "whitespace at the start"},
      {std::string(65, 'd'), "longer than 64 characters"},
  };
  ConnId conn = 1;
  for (const Case& c : cases) {
    Effects fx;
    lobby.onConnect(conn, 0.0, fx);
    lobby.onStreamBytes(
        conn, test::frameOf(test::joinMessage("lab", c.name, kHash, 4000, kProtocolVersion)), 0.0,
        fx);
    ASSERT_EQ(fx.frames.size(), 1u);
    const auto messages = test::messagesOf(fx.frames[0].bytes);
    ASSERT_EQ(messages.size(), 1u);
    ASSERT_TRUE(messages[0].has_error());
    EXPECT_EQ(messages[0].error().code(), control::ErrorReply::BAD_JOIN);
    EXPECT_NE(messages[0].error().message().find(c.says), std::string::npos)
        << messages[0].error().message();
    ++conn;
  }
  EXPECT_EQ(lobby.memberCount(), 0);
  EXPECT_EQ(lobby.joinsRefused().at("bad name"), cases.size());
  // A Unicode name is fine.
  Effects fx;
  lobby.onConnect(conn, 0.0, fx);
  lobby.onStreamBytes(
      conn, test::frameOf(test::joinMessage("lab", "Zoë 李", kHash, 4000, kProtocolVersion)), 0.0,
      fx);
  EXPECT_EQ(lobby.memberCount(), 1);
}

TEST(LobbyRefusals, OnlyRefusedJoinsCountAsRefusedJoins) {
  spdlog::set_level(spdlog::level::off);
  Lobby lobby(ServerConfig{}, 5);
  Effects fx;
  // A refused join (version), a bad first message (not a join), and a joined member that
  // later sends a second Join: only the first is a refused join.
  lobby.onConnect(1, 0.0, fx);
  lobby.onStreamBytes(1, test::frameOf(test::joinMessage("lab", "a", kHash, 4000, 99)), 0.0, fx);
  lobby.onConnect(2, 0.0, fx);
  control::ClientMessage leave;
  leave.mutable_leave()->set_reason("bye");
  lobby.onStreamBytes(2, test::frameOf(leave), 0.0, fx);
  lobby.onConnect(3, 0.0, fx);
  const auto join = test::frameOf(test::joinMessage("lab", "b", kHash, 4000, kProtocolVersion));
  lobby.onStreamBytes(3, join, 0.0, fx);
  lobby.onStreamBytes(3, join, 0.0, fx);
  EXPECT_EQ(lobby.joinsRefused().size(), 1u);
  EXPECT_EQ(lobby.joinsRefused().at("VERSION_MISMATCH"), 1u);
  EXPECT_EQ(lobby.drops().count("BAD_MESSAGE"), 2u);
}

TEST(AuthConfig, SecretFileAndTlsFilesAreReadFromTheirSections) {
  auto c = parseServerConfig("[auth]\nsecret_file = \"/etc/vistel/secret\"\n", "t.toml");
  ASSERT_TRUE(c.ok()) << c.error().message;
  EXPECT_EQ(c->secret_file, "/etc/vistel/secret");
  EXPECT_TRUE(c->join_secret.empty());  // the program reads the file
  auto unknown = parseServerConfig("[auth]\nsecret = \"inline\"\n", "t.toml");
  ASSERT_FALSE(unknown.ok());
  EXPECT_NE(unknown.error().message.find("secret"), std::string::npos) << unknown.error().message;
  // [tls]: both files or neither.
  auto tls = parseServerConfig("[tls]\ncert_file = \"c.pem\"\nkey_file = \"k.pem\"\n", "t.toml");
  ASSERT_TRUE(tls.ok()) << tls.error().message;
  EXPECT_EQ(tls->tls_cert_file, "c.pem");
  EXPECT_EQ(tls->tls_key_file, "k.pem");
  auto half = parseServerConfig("[tls]\ncert_file = \"c.pem\"\n", "t.toml");
  ASSERT_FALSE(half.ok());
  EXPECT_NE(half.error().message.find("both cert_file and key_file"), std::string::npos);
  // The built-in config leaves rooms open.
  auto builtin = loadServerConfig("config/server.toml");
  ASSERT_TRUE(builtin.ok()) << builtin.error().message;
  EXPECT_TRUE(builtin->secret_file.empty());
  EXPECT_TRUE(builtin->tls_cert_file.empty());
}

// The client side: a session with a token in its settings is admitted; one without is
// closed as refused for good, saying why.
TEST(SessionTokens, AClientSessionSendsItsTokenAndHearsTheRefusal) {
  spdlog::set_level(spdlog::level::off);
  ServerConfig config;
  config.join_secret = kSecret;
  test::SimNetwork net(config, 9);
  const auto avatar = test::encodeSynthetic(test::makeSyntheticAvatar("a", 0.1f));
  const std::int64_t now = std::chrono::duration_cast<std::chrono::seconds>(
                               std::chrono::system_clock::now().time_since_epoch())
                               .count();
  net::SessionSettings good = test::sessionFor("lab", "alice", avatar, 5);
  good.token = tokenFor("lab", "alice", now + 3600);
  net::SessionSettings none = test::sessionFor("lab", "bob", avatar, 5);
  const auto a = net.addClient(good, {}, {}, 0.0, std::make_shared<net::AvatarCache>());
  const auto b = net.addClient(none, {}, {}, 0.0, std::make_shared<net::AvatarCache>());
  net.connect(a);
  net.connect(b);
  net.advance(0.5);
  EXPECT_EQ(net.session(a).state(), net::SessionState::kLive) << net.session(a).error();
  ASSERT_EQ(net.session(b).state(), net::SessionState::kClosed);
  EXPECT_EQ(net.session(b).closeCause(), net::CloseCause::kRefused);
  EXPECT_NE(net.session(b).error().find("UNAUTHORIZED"), std::string::npos)
      << net.session(b).error();
  EXPECT_NE(net.session(b).error().find("requires a join token"), std::string::npos)
      << net.session(b).error();
}

}  // namespace
}  // namespace vistel::server
