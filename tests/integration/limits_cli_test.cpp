// Limits at accept and the programs' blind spots (issue 20, findings 5 and 9), against real
// processes on loopback: connections past the limits are refused at accept with a reason
// counted in /metrics; dropped datagrams are counted by class; a bot or client the server
// refuses exits non-zero naming the refusal; every program prints --version and refuses
// an unknown --log-level with status 2.
#include <netinet/in.h>
#include <sys/socket.h>
#include <unistd.h>

#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "common/avatar/avatar_io.hpp"
#include "common/base/file.hpp"
#include "common/wire/datagram_crypto.hpp"
#include "common/wire/packets.hpp"
#include "tests/integration/http_get.hpp"
#include "tests/integration/program.hpp"
#include "tests/integration/raw_control.hpp"
#include "tests/integration/session_scratch.hpp"
#include "tests/net/synthetic_avatar.hpp"
#include "tests/support/test_support.hpp"
#include "vistel_version.hpp"

namespace vistel {
namespace {

using Child = test::Program;

using test::httpGet;
using test::portOf;

// One UDP datagram to 127.0.0.1:port.
void sendDatagram(std::uint16_t port, const std::vector<std::uint8_t>& bytes) {
  const int fd = ::socket(AF_INET, SOCK_DGRAM, 0);
  sockaddr_in a{};
  a.sin_family = AF_INET;
  a.sin_port = htons(port);
  a.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
  ::sendto(fd, bytes.data(), bytes.size(), 0, reinterpret_cast<const sockaddr*>(&a), sizeof a);
  ::close(fd);
}

// True once the socket reads end of stream (the server closed it) within timeout_s.
bool closedByPeer(int fd, int timeout_s) {
  timeval timeout{timeout_s, 0};
  ::setsockopt(fd, SOL_SOCKET, SO_RCVTIMEO, &timeout, sizeof timeout);
  char buffer[4096];
  while (true) {
    const ssize_t n = ::recv(fd, buffer, sizeof buffer, 0);
    if (n == 0) return true;
    if (n < 0) return false;
  }
}

TEST(LimitsCli, ConnectionsPastThePerAddressLimitAreRefusedAtAcceptAndCounted) {
  const std::string dir = test::scratchDir();
  const std::string config = dir + "/limits.toml";
  ASSERT_TRUE(writeFileText(config,
                            "[session]\njoin_timeout_s = 60.0\n"
                            "[limits]\nmax_connections_per_address = 2\nlimit_loopback = true\n"));
  Child server("vistel-server", {"--port", "0", "--config", config, "--metrics-port", "0"},
               dir + "/server.log", true);
  const std::string address = test::serverAddress(server);
  ASSERT_FALSE(address.empty()) << server.log();
  const auto metrics_line = server.readLine(20.0);
  ASSERT_TRUE(metrics_line.has_value()) << server.log();
  const std::uint16_t port = portOf(address);
  const std::uint16_t metrics_port = portOf(*metrics_line);

  // Two connections are held (no Join yet); the third is refused before any handshake.
  const int first = test::connectLoopback(port);
  const int second = test::connectLoopback(port);
  ASSERT_GE(first, 0);
  ASSERT_GE(second, 0);
  // The accepts happen in order on the server: wait until both are in before the third.
  for (int i = 0; i < 100 && httpGet(metrics_port, "/metrics").find("vistel_connections 2\n") ==
                                 std::string::npos;
       ++i) {
    ::usleep(50000);
  }
  const int third = test::connectLoopback(port);
  ASSERT_GE(third, 0);
  const auto reply = test::receiveControl(third, 10);
  ASSERT_TRUE(reply.has_value()) << server.log();
  ASSERT_TRUE(reply->has_error());
  EXPECT_EQ(reply->error().code(), control::ErrorReply::SERVER_FULL);
  EXPECT_NE(reply->error().message().find("connections per address"), std::string::npos)
      << reply->error().message();
  EXPECT_TRUE(closedByPeer(third, 10));
  ::close(third);

  // Datagrams the server cannot route are counted by class, not only logged.
  sendDatagram(port, {0x01, 0x02, 0x03});
  sendDatagram(port, {0xff, 0xff, 0xff, 0xff, 0xff, 0xff, 0xff, 0xff, 0xff, 0xff, 0xff, 0xff});
  // A ping (routed by member id) and a hello (the lobby's) for a member that does not exist
  // (sealed, with some key: proto/WIRE.md §3.9).
  const wire::AeadKey guessed{};
  std::vector<std::uint8_t> ping;
  wire::PingPacket ping_packet;
  ping_packet.header.member_id = 0x00070007;
  wire::write(ping_packet, ping);
  wire::sealDatagram(guessed, 1, wire::kClientHeaderBytes, ping);
  sendDatagram(port, ping);
  // ... and a hello for a real member not sealed with its key (the lobby drops it).
  ASSERT_TRUE(
      test::sendControl(first, test::joinRequest("lab", "raw", std::string(64, 'a'), 5000)));
  const auto welcome = test::receiveControl(first, 10);
  ASSERT_TRUE(welcome.has_value() && welcome->has_welcome()) << server.log();
  std::vector<std::uint8_t> forged;
  wire::HelloPacket forged_packet;
  forged_packet.header.member_id = welcome->welcome().member_id();
  wire::write(forged_packet, forged);
  wire::sealDatagram(guessed, 1, wire::kClientHeaderBytes, forged);
  sendDatagram(port, forged);
  std::vector<std::uint8_t> hello;
  wire::HelloPacket hello_packet;
  hello_packet.header.member_id = 0x00070007;
  wire::write(hello_packet, hello);
  wire::sealDatagram(guessed, 2, wire::kClientHeaderBytes, hello);
  sendDatagram(port, hello);
  std::string text;
  for (int i = 0; i < 100; ++i) {
    text = httpGet(metrics_port, "/metrics");
    if (text.find("vistel_datagrams_dropped_total{reason=\"unknown key\"} 3\n") !=
        std::string::npos) {
      break;
    }
    ::usleep(50000);
  }
  EXPECT_NE(text.find("vistel_connections_dropped_total{reason=\"connections per address\"} 1\n"),
            std::string::npos)
      << text;
  EXPECT_NE(text.find("vistel_datagrams_dropped_total{reason=\"bad header\"} 2\n"),
            std::string::npos)
      << text;
  EXPECT_NE(text.find("vistel_datagrams_dropped_total{reason=\"unknown key\"} 3\n"),
            std::string::npos)
      << text;
  // The lobby's hello drop is a datagram, not a dropped connection.
  EXPECT_EQ(text.find("vistel_connections_dropped_total{reason=\"hello"), std::string::npos)
      << text;
  ::close(first);
  ::close(second);
}

class RefusedPrograms : public test::SessionScratch {};

TEST_F(RefusedPrograms, ABotAndAClientRefusedUntilTheEndExitNonZeroSayingWhy) {
  // A server that takes one connection, held by a raw peer that never joins.
  const std::string config = dir_ + "/one.toml";
  ASSERT_TRUE(writeFileText(config,
                            "[session]\njoin_timeout_s = 60.0\n"
                            "[limits]\nmax_connections = 1\n"));
  Child server("vistel-server", {"--port", "0", "--config", config}, dir_ + "/server.log", true);
  const std::string address = test::serverAddress(server);
  ASSERT_FALSE(address.empty()) << server.log();
  const int holder = test::connectLoopback(portOf(address));
  ASSERT_GE(holder, 0);

  Child bot("vistel-bot",
            {"--server", address, "--room", "it", "--name", "late", "--bvh", bvh_path_, "--avatar",
             avatar_path_, "--duration", "1.5"},
            dir_ + "/bot.log");
  EXPECT_EQ(bot.wait(60.0), 1) << bot.log();
  EXPECT_NE(bot.log().find("never joined room 'it': server: SERVER_FULL"), std::string::npos)
      << bot.log();
  EXPECT_NE(bot.log().find("connection limit"), std::string::npos) << bot.log();

  Child client("vistel-client",
               {"--server", address, "--room", "it", "--name", "viewer", "--headless", "--avatar",
                avatar_path_, "--duration", "1.5"},
               dir_ + "/client.log");
  EXPECT_EQ(client.wait(60.0), 1) << client.log();
  EXPECT_NE(client.log().find("never joined room 'it': server: SERVER_FULL"), std::string::npos)
      << client.log();
  ::close(holder);
}

TEST(ProgramsCli, EveryProgramPrintsItsVersion) {
  const std::string dir = test::scratchDir();
  for (const char* program : {"vistel-server", "vistel-client", "vistel-bot", "vistel-avatar"}) {
    Child p(program, {"--version"}, dir + "/" + program + ".log");
    EXPECT_EQ(p.wait(20.0), 0) << program << ": " << p.log();
    EXPECT_NE(p.log().find(std::string(program) + " " + VISTEL_VERSION), std::string::npos)
        << p.log();
    EXPECT_NE(p.log().find("datagram wire " + std::to_string(wire::kWireVersion)),
              std::string::npos)
        << p.log();
  }
}

TEST(ProgramsCli, AnUnknownLogLevelIsRefusedByTheClientAndTheBot) {
  const std::string dir = test::scratchDir();
  for (const std::string program : {"vistel-client", "vistel-bot"}) {
    std::vector<std::string> args = {"--server", "127.0.0.1:9", "--room",      "r",
                                     "--name",   "n",           "--log-level", "loud"};
    if (program == "vistel-bot") args.insert(args.end(), {"--bvh", "x.bvh"});
    Child p(program, args, dir + "/" + program + ".log");
    EXPECT_EQ(p.wait(20.0), 2) << program << ": " << p.log();
    EXPECT_NE(p.log().find("--log-level 'loud'"), std::string::npos) << p.log();
  }
}

}  // namespace
}  // namespace vistel
