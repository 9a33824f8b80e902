// Join tokens: what a server with a secret asks of every Join (proto/SESSION.md §2.3).
//
// A token says "whoever holds this may join room R as name N until time E", signed by the
// server's secret with HMAC-SHA256. Its text form (what `vistel-server token` prints and
// `--token` takes) is
//   "vt1." + base64url-without-padding(body + mac)
// where body is, little-endian:
//   u8 version (1) | i64 expires_at (unix seconds) | u16 room bytes | room (UTF-8)
//   | u16 name bytes | name (UTF-8)
// and mac = HMAC-SHA256(secret, "vistel join token\0" + body), 32 bytes. Everything a
// token grants is signed; nothing else travels in it. Text only of [A-Za-z0-9_.-], so it
// passes a shell and a URL unquoted.
//
// Verification order: structure (kMalformed), signature (kBadSignature, compared in
// constant time), expiry (kExpired: the token is good while now < expires_at), then room
// and name (kWrongRoom, kWrongName: compared byte for byte with the Join's). The claims of
// a token whose signature does not match are never looked at. Cost: one HMAC over < 600
// bytes; no allocation beyond the decoded bytes.
#pragma once

#include <cstdint>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "common/base/result.hpp"

namespace vistel::auth {

inline constexpr std::uint8_t kTokenVersion = 1;
inline constexpr std::string_view kTokenPrefix = "vt1.";
inline constexpr std::size_t kMacBytes = 32;
inline constexpr std::size_t kMinSecretBytes = 32;
inline constexpr std::size_t kMaxClaimBytes = 1024;  // room or name, in bytes (the lobby
                                                     // limits them further)
inline constexpr std::size_t kMaxTokenChars = 4096;  // above any token of legal claims

// What a token grants.
struct JoinClaims {
  std::string room;
  std::string name;
  std::int64_t expires_at = 0;  // unix seconds; the token is refused from this second on
};

enum class TokenError {
  kNone,
  kMissing,       // no token where one is required (the lobby's case; never from verify)
  kMalformed,     // not a token: prefix, base64url, version, lengths
  kBadSignature,  // made with another secret, or altered
  kExpired,
  kWrongRoom,
  kWrongName,
};

// A short fixed phrase per error ("malformed", "bad signature", ...): metric labels.
std::string_view tokenErrorName(TokenError error);

struct TokenCheck {
  TokenError error = TokenError::kNone;
  std::string message;  // why, for the ErrorReply and the log; empty when kNone
  JoinClaims claims;    // filled once the signature matched
  bool ok() const { return error == TokenError::kNone; }
};

// A token for these claims. Errors: a secret shorter than kMinSecretBytes, a room or name
// longer than kMaxClaimBytes.
Result<std::string> createJoinToken(std::span<const std::uint8_t> secret, const JoinClaims& claims);

// Checks a token against the Join it came with at unix time now_unix (see the order
// above). Any bytes are safe: a token longer than kMaxTokenChars is kMalformed unread.
TokenCheck verifyJoinToken(std::span<const std::uint8_t> secret, std::string_view token,
                           std::string_view room, std::string_view name, std::int64_t now_unix);

// The claims of a well-formed token without checking its signature (for tools and the
// fuzzer; never to admit anyone). Errors say what is malformed.
Result<JoinClaims> parseJoinToken(std::string_view token);

// base64url without padding (RFC 4648 §5), as the tokens use it. decode refuses other
// characters, padding and impossible lengths.
std::string base64UrlEncode(std::span<const std::uint8_t> bytes);
Result<std::vector<std::uint8_t>> base64UrlDecode(std::string_view text);

// A token lifetime: a whole number with an optional unit s, m, h or d ("90", "15m", "1h",
// "7d"); 1 second to 10 years. Errors name the text.
Result<std::int64_t> parseLifetime(std::string_view text);

}  // namespace vistel::auth
