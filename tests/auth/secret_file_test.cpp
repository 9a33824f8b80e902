// The join-token secret file (common/auth/secret_file.hpp) and `vistel-server token`'s
// core (token_command.hpp).
#include <sys/stat.h>

#include <string>

#include <gtest/gtest.h>

#include "common/auth/join_token.hpp"
#include "common/auth/secret_file.hpp"
#include "common/auth/token_command.hpp"
#include "common/base/file.hpp"
#include "tests/support/test_support.hpp"

namespace vistel::auth {
namespace {

std::string writeSecret(const std::string& dir, const std::string& name, const std::string& text,
                        mode_t mode = 0600) {
  const std::string path = dir + "/" + name;
  EXPECT_TRUE(writeFileText(path, text).ok());
  ::chmod(path.c_str(), mode);
  return path;
}

const std::string kHex64 = "0123456789abcdef0123456789abcdef0123456789abcdef0123456789abcdef";

TEST(SecretFile, ReadsTheBytesWithoutTrailingWhitespace) {
  const std::string dir = test::scratchDir();
  const auto plain = readJoinSecret(writeSecret(dir, "plain", kHex64));
  const auto newline = readJoinSecret(writeSecret(dir, "newline", kHex64 + "\r\n \t\n"));
  ASSERT_TRUE(plain.ok()) << plain.error().message;
  ASSERT_TRUE(newline.ok()) << newline.error().message;
  EXPECT_EQ(plain->bytes.size(), 64u);
  EXPECT_EQ(plain->bytes, newline->bytes);
  EXPECT_TRUE(plain->warning.empty()) << plain->warning;
  // Exactly 32 bytes is enough.
  EXPECT_TRUE(readJoinSecret(writeSecret(dir, "exact", kHex64.substr(0, 32))).ok());
}

TEST(SecretFile, RefusesShortMissingAndEmptyNamingTheFile) {
  const std::string dir = test::scratchDir();
  const std::string short_path = writeSecret(dir, "short", kHex64.substr(0, 31) + "\n\n");
  const auto too_short = readJoinSecret(short_path);
  ASSERT_FALSE(too_short.ok());
  EXPECT_NE(too_short.error().message.find(short_path), std::string::npos)
      << too_short.error().message;
  EXPECT_NE(too_short.error().message.find("31 bytes"), std::string::npos)
      << too_short.error().message;
  EXPECT_NE(too_short.error().message.find("at least 32"), std::string::npos);
  const auto missing = readJoinSecret(dir + "/nope");
  ASSERT_FALSE(missing.ok());
  EXPECT_NE(missing.error().message.find(dir + "/nope"), std::string::npos)
      << missing.error().message;
  EXPECT_FALSE(readJoinSecret(writeSecret(dir, "empty", "")).ok());
  EXPECT_FALSE(readJoinSecret("").ok());
}

TEST(SecretFile, WarnsWhenOthersMayReadIt) {
  const std::string dir = test::scratchDir();
  const auto group = readJoinSecret(writeSecret(dir, "group", kHex64, 0640));
  ASSERT_TRUE(group.ok());
  EXPECT_NE(group->warning.find("its group"), std::string::npos) << group->warning;
  EXPECT_NE(group->warning.find("chmod 600"), std::string::npos) << group->warning;
  const auto world = readJoinSecret(writeSecret(dir, "world", kHex64, 0644));
  ASSERT_TRUE(world.ok());
  EXPECT_NE(world->warning.find("everyone"), std::string::npos) << world->warning;
  EXPECT_NE(world->warning.find(dir + "/world"), std::string::npos) << world->warning;
}

TEST(TokenCommand, IssuesATokenTheSecretVerifies) {
  const std::string dir = test::scratchDir();
  const std::string path = writeSecret(dir, "secret", kHex64 + "\n");
  const auto issued = issueJoinToken({path, "lab", "alice", "2h"}, 1000);
  ASSERT_TRUE(issued.ok()) << issued.error().message;
  EXPECT_EQ(issued->expires_at, 1000 + 7200);
  const auto secret = readJoinSecret(path);
  ASSERT_TRUE(secret.ok());
  EXPECT_TRUE(verifyJoinToken(secret->bytes, issued->token, "lab", "alice", 1000 + 7199).ok());
  EXPECT_FALSE(verifyJoinToken(secret->bytes, issued->token, "lab", "alice", 1000 + 7200).ok());
}

TEST(TokenCommand, RefusesWhatTheLobbyWouldRefuse) {
  const std::string dir = test::scratchDir();
  const std::string path = writeSecret(dir, "secret", kHex64);
  const auto room = issueJoinToken({path, "no room!", "alice", "1h"}, 0);
  ASSERT_FALSE(room.ok());
  EXPECT_NE(room.error().message.find("--room"), std::string::npos);
  const auto name = issueJoinToken({path, "lab", "al\xE2\x80\xAEice", "1h"}, 0);
  ASSERT_FALSE(name.ok());
  EXPECT_NE(name.error().message.find("character 3 (U+202E)"), std::string::npos)
      << name.error().message;
  const auto ttl = issueJoinToken({path, "lab", "alice", "soon"}, 0);
  ASSERT_FALSE(ttl.ok());
  EXPECT_NE(ttl.error().message.find("--ttl"), std::string::npos);
  EXPECT_FALSE(issueJoinToken({dir + "/absent", "lab", "alice", "1h"}, 0).ok());
}

}  // namespace
}  // namespace vistel::auth
