// Authenticated rooms with the real programs (issue 20, finding 4): `vistel-server token`
// prints a token from the secret file; a server started with --secret-file admits a bot
// holding a token for its room and name, refuses a bot without one and a client whose token
// is for another room (both exit 1 saying UNAUTHORIZED and why), and counts the refusals
// by reason in /metrics. A server without a secret says at start that rooms are open; a
// short secret file stops the server naming the file.
#include <sys/socket.h>
#include <sys/stat.h>
#include <unistd.h>

#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "common/base/file.hpp"
#include "tests/integration/http_get.hpp"
#include "tests/integration/program.hpp"
#include "tests/integration/raw_control.hpp"
#include "tests/integration/session_scratch.hpp"

namespace vistel {
namespace {

using Child = test::Program;

using test::httpGet;
using test::portOf;

class JoinTokensCli : public test::SessionScratch {
 protected:
  // A secret file (mode 600) in the scratch folder.
  std::string makeSecret() {
    const std::string path = dir_ + "/secret";
    EXPECT_TRUE(writeFileText(path, std::string(64, 'k') + "\n").ok());
    ::chmod(path.c_str(), 0600);
    return path;
  }

  // `vistel-server token ...`'s one line of stdout.
  std::string token(const std::string& secret, const std::string& room, const std::string& name) {
    Child cmd("vistel-server",
              {"token", "--secret-file", secret, "--room", room, "--name", name, "--ttl", "10m"},
              dir_ + "/token-" + name + ".log", true);
    const auto line = cmd.readLine(20.0);
    EXPECT_EQ(cmd.wait(20.0), 0) << cmd.log();
    EXPECT_TRUE(line.has_value() && line->starts_with("vt1.")) << line.value_or("(nothing)");
    return line.value_or("");
  }
};

TEST_F(JoinTokensCli, ATokenAdmitsItsHolderAndRefusalsAreSaidAndCounted) {
  const std::string secret = makeSecret();
  Child server("vistel-server", {"--port", "0", "--secret-file", secret, "--metrics-port", "0"},
               dir_ + "/server.log", true);
  const std::string address = test::serverAddress(server);
  ASSERT_FALSE(address.empty()) << server.log();
  const auto metrics_line = server.readLine(20.0);
  ASSERT_TRUE(metrics_line.has_value()) << server.log();
  EXPECT_TRUE(server.waitForLog("join tokens required", 10.0)) << server.log();
  EXPECT_EQ(server.log().find("rooms are open"), std::string::npos) << server.log();

  // A bot with its token joins and leaves cleanly.
  Child good(
      "vistel-bot",
      {"--server", address, "--room", "lab", "--name", "alice", "--bvh", bvh_path_, "--avatar",
       avatar_path_, "--duration", "1.0", "--token", token(secret, "lab", "alice")},
      dir_ + "/good.log");
  EXPECT_EQ(good.wait(60.0), 0) << good.log();

  // A bot without a token, and a client with another room's: refused, exit 1, saying why.
  Child none("vistel-bot",
             {"--server", address, "--room", "lab", "--name", "bob", "--bvh", bvh_path_, "--avatar",
              avatar_path_, "--duration", "1.0"},
             dir_ + "/none.log");
  EXPECT_EQ(none.wait(60.0), 1) << none.log();
  EXPECT_NE(none.log().find("UNAUTHORIZED"), std::string::npos) << none.log();
  EXPECT_NE(none.log().find("requires a join token"), std::string::npos) << none.log();
  Child other("vistel-client",
              {"--server", address, "--room", "lab", "--name", "carol", "--headless", "--avatar",
               avatar_path_, "--duration", "1.0", "--token", token(secret, "kitchen", "carol")},
              dir_ + "/other.log");
  EXPECT_EQ(other.wait(60.0), 1) << other.log();
  EXPECT_NE(other.log().find("UNAUTHORIZED"), std::string::npos) << other.log();
  EXPECT_NE(other.log().find("for room 'kitchen'"), std::string::npos) << other.log();

  // The refusals by reason, apart from dropped connections.
  const std::string text = httpGet(portOf(*metrics_line), "/metrics");
  EXPECT_NE(text.find("vistel_joins_refused_total{reason=\"token missing\"} 1\n"),
            std::string::npos)
      << text;
  EXPECT_NE(text.find("vistel_joins_refused_total{reason=\"token wrong room\"} 1\n"),
            std::string::npos)
      << text;
  EXPECT_EQ(text.find("vistel_connections_dropped_total{reason=\"token"), std::string::npos)
      << text;
  EXPECT_NE(text.find("vistel_joins_total 1\n"), std::string::npos) << text;
}

TEST_F(JoinTokensCli, ABotWithOneTokenPerParticipantJoinsThemAll) {
  const std::string secret = makeSecret();
  Child server("vistel-server", {"--port", "0", "--secret-file", secret}, dir_ + "/server.log",
               true);
  const std::string address = test::serverAddress(server);
  ASSERT_FALSE(address.empty()) << server.log();
  Child bots("vistel-bot",
             {"--server", address, "--room", "lab", "--name", "b", "--count", "2", "--bvh",
              bvh_path_, "--avatar", avatar_path_, "--duration", "1.0", "--token",
              token(secret, "lab", "b-1"), "--token", token(secret, "lab", "b-2")},
             dir_ + "/bots.log");
  EXPECT_EQ(bots.wait(60.0), 0) << bots.log();
  // One token for two participants is bad usage.
  Child wrong("vistel-bot",
              {"--server", address, "--room", "lab", "--name", "b", "--count", "2", "--bvh",
               bvh_path_, "--token", "vt1.x"},
              dir_ + "/wrong.log");
  EXPECT_EQ(wrong.wait(20.0), 2) << wrong.log();
}

TEST_F(JoinTokensCli, WithoutASecretTheServerSaysRoomsAreOpenAndAShortSecretStopsIt) {
  Child open("vistel-server", {"--port", "0"}, dir_ + "/open.log", true);
  ASSERT_FALSE(test::serverAddress(open).empty()) << open.log();
  EXPECT_TRUE(open.waitForLog("rooms are open", 10.0)) << open.log();

  const std::string short_secret = dir_ + "/short";
  ASSERT_TRUE(writeFileText(short_secret, "too short\n").ok());
  Child refused("vistel-server", {"--port", "0", "--secret-file", short_secret},
                dir_ + "/short.log");
  EXPECT_EQ(refused.wait(20.0), 1) << refused.log();
  EXPECT_NE(refused.log().find(short_secret + ": 9 bytes"), std::string::npos) << refused.log();

  Child bad_ttl(
      "vistel-server",
      {"token", "--secret-file", makeSecret(), "--room", "lab", "--name", "a", "--ttl", "1 week"},
      dir_ + "/ttl.log");
  EXPECT_EQ(bad_ttl.wait(20.0), 1) << bad_ttl.log();
  EXPECT_NE(bad_ttl.log().find("--ttl"), std::string::npos) << bad_ttl.log();
}

}  // namespace
}  // namespace vistel
