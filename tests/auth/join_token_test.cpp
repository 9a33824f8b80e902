// Join tokens (common/auth/join_token.hpp): round trip, every refusal, a changed byte
// anywhere, the expiry boundary, base64url and lifetimes.
#include <cstdint>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "common/auth/join_token.hpp"

namespace vistel::auth {
namespace {

const std::vector<std::uint8_t> kSecret(32, 0x5A);
const std::vector<std::uint8_t> kOtherSecret(40, 0x33);
constexpr std::int64_t kNow = 1'800'000'000;

std::string tokenFor(const std::string& room, const std::string& name, std::int64_t expires_at,
                     const std::vector<std::uint8_t>& secret = kSecret) {
  auto token = createJoinToken(secret, {room, name, expires_at});
  EXPECT_TRUE(token.ok()) << (token.ok() ? "" : token.error().message);
  return token.ok() ? *token : std::string();
}

TEST(JoinToken, RoundTripGrantsTheRoomAndNameUntilExpiry) {
  const std::string token = tokenFor("lab", "alice", kNow + 3600);
  EXPECT_TRUE(token.starts_with("vt1."));
  for (char c : token) {
    EXPECT_TRUE(std::isalnum(static_cast<unsigned char>(c)) || c == '-' || c == '_' || c == '.')
        << token;
  }
  const TokenCheck check = verifyJoinToken(kSecret, token, "lab", "alice", kNow);
  ASSERT_TRUE(check.ok()) << check.message;
  EXPECT_EQ(check.claims.room, "lab");
  EXPECT_EQ(check.claims.name, "alice");
  EXPECT_EQ(check.claims.expires_at, kNow + 3600);
  auto parsed = parseJoinToken(token);
  ASSERT_TRUE(parsed.ok());
  EXPECT_EQ(parsed->name, "alice");
}

TEST(JoinToken, UnicodeNamesAndEmptyClaimsRoundTrip) {
  const std::string name = "Zoë \xE6\x9D\x8E";
  const std::string token = tokenFor("r", name, kNow + 1);
  EXPECT_TRUE(verifyJoinToken(kSecret, token, "r", name, kNow).ok());
  const std::string empty = tokenFor("", "", kNow + 1);
  EXPECT_TRUE(verifyJoinToken(kSecret, empty, "", "", kNow).ok());
}

TEST(JoinToken, EachRefusalHasItsOwnError) {
  const std::string token = tokenFor("lab", "alice", kNow + 60);
  EXPECT_EQ(verifyJoinToken(kOtherSecret, token, "lab", "alice", kNow).error,
            TokenError::kBadSignature);
  EXPECT_EQ(verifyJoinToken(kSecret, token, "lab", "alice", kNow + 60).error, TokenError::kExpired);
  const TokenCheck room = verifyJoinToken(kSecret, token, "kitchen", "alice", kNow);
  EXPECT_EQ(room.error, TokenError::kWrongRoom);
  EXPECT_NE(room.message.find("for room 'lab'"), std::string::npos) << room.message;
  const TokenCheck name = verifyJoinToken(kSecret, token, "lab", "bob", kNow);
  EXPECT_EQ(name.error, TokenError::kWrongName);
  EXPECT_NE(name.message.find("for name 'alice'"), std::string::npos) << name.message;
  for (const std::string bad :
       {"", "vt1.", "vt2.AAAA", "hello", "vt1.!!!!", "vt1.AAAAA",
        "vt1.AAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAA"}) {
    const TokenCheck check = verifyJoinToken(kSecret, bad, "lab", "alice", kNow);
    EXPECT_EQ(check.error, TokenError::kMalformed) << bad;
    EXPECT_FALSE(check.message.empty());
  }
  EXPECT_EQ(
      verifyJoinToken(kSecret, std::string(kMaxTokenChars + 1, 'A'), "lab", "alice", kNow).error,
      TokenError::kMalformed);
  EXPECT_EQ(tokenErrorName(TokenError::kExpired), "expired");
  EXPECT_EQ(tokenErrorName(TokenError::kBadSignature), "bad signature");
}

TEST(JoinToken, ASignatureMismatchComesBeforeExpiryRoomAndName) {
  // A token from another secret that is also expired and for another room: the signature
  // is what is refused (its claims are never trusted).
  const std::string token = tokenFor("other", "mallory", kNow - 10, kOtherSecret);
  const TokenCheck check = verifyJoinToken(kSecret, token, "lab", "alice", kNow);
  EXPECT_EQ(check.error, TokenError::kBadSignature);
  EXPECT_TRUE(check.claims.room.empty());
}

TEST(JoinToken, ChangingAnyByteOrCharacterIsRefused) {
  const std::string token = tokenFor("lab", "alice", kNow + 60);
  auto bytes = base64UrlDecode(std::string_view(token).substr(4));
  ASSERT_TRUE(bytes.ok());
  // Every bit of every decoded byte: the body (claims) and the MAC itself.
  for (std::size_t i = 0; i < bytes->size(); ++i) {
    for (int bit = 0; bit < 8; ++bit) {
      std::vector<std::uint8_t> changed = *bytes;
      changed[i] ^= static_cast<std::uint8_t>(1u << bit);
      const std::string forged = "vt1." + base64UrlEncode(changed);
      const TokenCheck check = verifyJoinToken(kSecret, forged, "lab", "alice", kNow);
      EXPECT_FALSE(check.ok()) << "byte " << i << " bit " << bit;
      EXPECT_TRUE(check.error == TokenError::kBadSignature || check.error == TokenError::kMalformed)
          << "byte " << i << " bit " << bit << ": " << check.message;
    }
  }
  // A longer expiry, re-encoded without the secret, is a bad signature.
  std::vector<std::uint8_t> later = *bytes;
  later[8] ^= 0x40;  // the expiry's high byte
  EXPECT_EQ(verifyJoinToken(kSecret, "vt1." + base64UrlEncode(later), "lab", "alice", kNow).error,
            TokenError::kBadSignature);
  // Truncated or extended text.
  EXPECT_FALSE(
      verifyJoinToken(kSecret, token.substr(0, token.size() - 1), "lab", "alice", kNow).ok());
  EXPECT_FALSE(verifyJoinToken(kSecret, token + "A", "lab", "alice", kNow).ok());
  EXPECT_FALSE(verifyJoinToken(kSecret, token + "AA", "lab", "alice", kNow).ok());
}

TEST(JoinToken, ExpiresAtItsSecond) {
  const std::string token = tokenFor("lab", "alice", kNow);
  EXPECT_TRUE(verifyJoinToken(kSecret, token, "lab", "alice", kNow - 1).ok());
  const TokenCheck at = verifyJoinToken(kSecret, token, "lab", "alice", kNow);
  EXPECT_EQ(at.error, TokenError::kExpired);
  EXPECT_NE(at.message.find("expired 0 s ago"), std::string::npos) << at.message;
  EXPECT_EQ(verifyJoinToken(kSecret, token, "lab", "alice", kNow + 7200).error,
            TokenError::kExpired);
}

TEST(JoinToken, CreateRefusesAShortSecretAndHugeClaims) {
  EXPECT_FALSE(createJoinToken(std::vector<std::uint8_t>(31, 1), {"lab", "alice", kNow}).ok());
  EXPECT_FALSE(createJoinToken(kSecret, {"lab", std::string(kMaxClaimBytes + 1, 'a'), kNow}).ok());
  // Verification with a short secret never succeeds.
  const std::vector<std::uint8_t> short_secret(8, 1);
  const std::string token = tokenFor("lab", "alice", kNow + 60);
  EXPECT_EQ(verifyJoinToken(short_secret, token, "lab", "alice", kNow).error,
            TokenError::kBadSignature);
}

TEST(Base64Url, EncodesAndDecodesEveryLengthAndRefusesBadText) {
  std::vector<std::uint8_t> bytes;
  for (int n = 0; n < 40; ++n) {
    const std::string text = base64UrlEncode(bytes);
    EXPECT_EQ(text.find('='), std::string::npos);
    auto back = base64UrlDecode(text);
    ASSERT_TRUE(back.ok()) << text;
    EXPECT_EQ(*back, bytes);
    bytes.push_back(static_cast<std::uint8_t>(n * 37 + 250));
  }
  EXPECT_EQ(base64UrlEncode(std::vector<std::uint8_t>{0xfb, 0xff}), "-_8");
  EXPECT_FALSE(base64UrlDecode("A").ok());     // impossible length
  EXPECT_FALSE(base64UrlDecode("AB==").ok());  // padding
  EXPECT_FALSE(base64UrlDecode("A+B/").ok());  // the other alphabet
  EXPECT_FALSE(base64UrlDecode("AB").ok());    // stray bits: "AA" is the only spelling of 0
  EXPECT_TRUE(base64UrlDecode("AA").ok());
}

TEST(Lifetime, AcceptsUnitsAndRefusesTheRest) {
  EXPECT_EQ(*parseLifetime("90"), 90);
  EXPECT_EQ(*parseLifetime("90s"), 90);
  EXPECT_EQ(*parseLifetime("15m"), 900);
  EXPECT_EQ(*parseLifetime("1h"), 3600);
  EXPECT_EQ(*parseLifetime("7d"), 7 * 86400);
  for (const char* bad : {"", "h", "0", "0s", "-5m", "1.5h", "1x", "1 h", "+3", "99999d", "1hh"}) {
    const auto parsed = parseLifetime(bad);
    EXPECT_FALSE(parsed.ok()) << bad;
    if (!parsed.ok()) {
      EXPECT_NE(parsed.error().message.find("lifetime"), std::string::npos);
    }
  }
}

}  // namespace
}  // namespace vistel::auth
