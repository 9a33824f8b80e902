// Join tokens: HMAC-SHA256 (RFC 2104 over FIPS 180-4 SHA-256, through OpenSSL) over a
// small little-endian body, written in base64url (RFC 4648 §5) without padding.
#include "common/auth/join_token.hpp"

#include <array>
#include <charconv>
#include <limits>

#include <openssl/crypto.h>
#include <openssl/evp.h>
#include <openssl/hmac.h>

namespace vistel::auth {
namespace {

constexpr std::string_view kMacDomain{"vistel join token\0", 18};
constexpr char kAlphabet[] = "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789-_";

// The value of a base64url character, or -1.
int sextet(char c) {
  if (c >= 'A' && c <= 'Z') return c - 'A';
  if (c >= 'a' && c <= 'z') return c - 'a' + 26;
  if (c >= '0' && c <= '9') return c - '0' + 52;
  if (c == '-') return 62;
  if (c == '_') return 63;
  return -1;
}

void putU16(std::vector<std::uint8_t>& out, std::uint16_t v) {
  out.push_back(static_cast<std::uint8_t>(v & 0xFF));
  out.push_back(static_cast<std::uint8_t>(v >> 8));
}

void putI64(std::vector<std::uint8_t>& out, std::int64_t value) {
  const auto v = static_cast<std::uint64_t>(value);
  for (int i = 0; i < 8; ++i) out.push_back(static_cast<std::uint8_t>(v >> (8 * i)));
}

// The body's bytes for these claims (lengths already checked).
std::vector<std::uint8_t> bodyOf(const JoinClaims& claims) {
  std::vector<std::uint8_t> body;
  body.reserve(1 + 8 + 4 + claims.room.size() + claims.name.size() + kMacBytes);
  body.push_back(kTokenVersion);
  putI64(body, claims.expires_at);
  putU16(body, static_cast<std::uint16_t>(claims.room.size()));
  body.insert(body.end(), claims.room.begin(), claims.room.end());
  putU16(body, static_cast<std::uint16_t>(claims.name.size()));
  body.insert(body.end(), claims.name.begin(), claims.name.end());
  return body;
}

// HMAC-SHA256(secret, domain + body).
std::array<std::uint8_t, kMacBytes> macOf(std::span<const std::uint8_t> secret,
                                          std::span<const std::uint8_t> body) {
  std::vector<std::uint8_t> input(kMacDomain.begin(), kMacDomain.end());
  input.insert(input.end(), body.begin(), body.end());
  std::array<std::uint8_t, kMacBytes> mac{};
  unsigned int length = 0;
  HMAC(EVP_sha256(), secret.data(), static_cast<int>(secret.size()), input.data(), input.size(),
       mac.data(), &length);
  return mac;
}

// Reads the body of decoded token bytes (everything but the trailing MAC).
Result<JoinClaims> readBody(std::span<const std::uint8_t> body) {
  std::size_t at = 0;
  auto need = [&](std::size_t n) { return body.size() - at >= n; };
  if (!need(1)) return fail("join token: empty");
  if (body[0] != kTokenVersion) {
    return fail("join token: version {} (this server reads version {})", body[0], kTokenVersion);
  }
  at = 1;
  if (!need(8)) return fail("join token: truncated at the expiry");
  std::uint64_t expiry = 0;
  for (int i = 0; i < 8; ++i) expiry |= std::uint64_t{body[at + i]} << (8 * i);
  at += 8;
  JoinClaims claims;
  claims.expires_at = static_cast<std::int64_t>(expiry);
  for (std::string* field : {&claims.room, &claims.name}) {
    const char* what = field == &claims.room ? "room" : "name";
    if (!need(2)) return fail("join token: truncated at the {} length", what);
    const std::size_t length = body[at] | (std::size_t{body[at + 1]} << 8);
    at += 2;
    if (length > kMaxClaimBytes) return fail("join token: {} of {} bytes", what, length);
    if (!need(length)) return fail("join token: truncated in the {}", what);
    field->assign(reinterpret_cast<const char*>(body.data() + at), length);
    at += length;
  }
  if (at != body.size()) return fail("join token: {} bytes after the name", body.size() - at);
  return claims;
}

// The decoded bytes of a token's text (body then MAC), or why it is not a token.
Result<std::vector<std::uint8_t>> decodeToken(std::string_view token) {
  if (token.empty()) return fail("join token: empty");
  if (token.size() > kMaxTokenChars) {
    return fail("join token: {} characters (at most {})", token.size(), kMaxTokenChars);
  }
  if (!token.starts_with(kTokenPrefix)) {
    return fail("join token: does not start with '{}'", kTokenPrefix);
  }
  auto bytes = base64UrlDecode(token.substr(kTokenPrefix.size()));
  if (!bytes) return fail("join token: {}", bytes.error().message);
  if (bytes->size() < 1 + 8 + 2 + 2 + kMacBytes) {
    return fail("join token: {} bytes, too short", bytes->size());
  }
  return bytes;
}

}  // namespace

std::string_view tokenErrorName(TokenError error) {
  switch (error) {
    case TokenError::kNone:
      return "none";
    case TokenError::kMissing:
      return "missing";
    case TokenError::kMalformed:
      return "malformed";
    case TokenError::kBadSignature:
      return "bad signature";
    case TokenError::kExpired:
      return "expired";
    case TokenError::kWrongRoom:
      return "wrong room";
    case TokenError::kWrongName:
      return "wrong name";
  }
  return "unknown";
}

std::string base64UrlEncode(std::span<const std::uint8_t> bytes) {
  std::string out;
  out.reserve((bytes.size() * 4 + 2) / 3);
  std::size_t i = 0;
  // Whole groups of three bytes, then the one or two left (no padding).
  for (; i + 3 <= bytes.size(); i += 3) {
    const std::uint32_t v =
        (std::uint32_t{bytes[i]} << 16) | (std::uint32_t{bytes[i + 1]} << 8) | bytes[i + 2];
    for (int k = 3; k >= 0; --k) out.push_back(kAlphabet[(v >> (6 * k)) & 63]);
  }
  const std::size_t left = bytes.size() - i;
  if (left == 1) {
    const std::uint32_t v = std::uint32_t{bytes[i]} << 16;
    out.push_back(kAlphabet[(v >> 18) & 63]);
    out.push_back(kAlphabet[(v >> 12) & 63]);
  } else if (left == 2) {
    const std::uint32_t v = (std::uint32_t{bytes[i]} << 16) | (std::uint32_t{bytes[i + 1]} << 8);
    out.push_back(kAlphabet[(v >> 18) & 63]);
    out.push_back(kAlphabet[(v >> 12) & 63]);
    out.push_back(kAlphabet[(v >> 6) & 63]);
  }
  return out;
}

Result<std::vector<std::uint8_t>> base64UrlDecode(std::string_view text) {
  if (text.size() % 4 == 1) return fail("base64url text of impossible length {}", text.size());
  std::vector<std::uint8_t> out;
  out.reserve(text.size() * 3 / 4);
  std::uint32_t acc = 0;
  int bits = 0;
  for (std::size_t i = 0; i < text.size(); ++i) {
    const int v = sextet(text[i]);
    if (v < 0) return fail("character {} is not base64url", i + 1);
    acc = (acc << 6) | static_cast<std::uint32_t>(v);
    bits += 6;
    if (bits >= 8) {
      bits -= 8;
      out.push_back(static_cast<std::uint8_t>(acc >> bits));
      acc &= (1u << bits) - 1;
    }
  }
  // The bits left over must be zero (one spelling per byte string).
  if (acc != 0) return fail("base64url text with stray trailing bits");
  return out;
}

Result<std::string> createJoinToken(std::span<const std::uint8_t> secret,
                                    const JoinClaims& claims) {
  if (secret.size() < kMinSecretBytes) {
    return fail("join token secret of {} bytes (at least {})", secret.size(), kMinSecretBytes);
  }
  if (claims.room.size() > kMaxClaimBytes || claims.name.size() > kMaxClaimBytes) {
    return fail("join token: room or name longer than {} bytes", kMaxClaimBytes);
  }
  std::vector<std::uint8_t> bytes = bodyOf(claims);
  const auto mac = macOf(secret, bytes);
  bytes.insert(bytes.end(), mac.begin(), mac.end());
  return std::string(kTokenPrefix) + base64UrlEncode(bytes);
}

Result<JoinClaims> parseJoinToken(std::string_view token) {
  auto bytes = decodeToken(token);
  if (!bytes) return bytes.error();
  return readBody(std::span(*bytes).first(bytes->size() - kMacBytes));
}

TokenCheck verifyJoinToken(std::span<const std::uint8_t> secret, std::string_view token,
                           std::string_view room, std::string_view name, std::int64_t now_unix) {
  TokenCheck check;
  auto refuse = [&](TokenError error, std::string message) {
    check.error = error;
    check.message = std::move(message);
    return check;
  };
  // Structure.
  auto bytes = decodeToken(token);
  if (!bytes) return refuse(TokenError::kMalformed, bytes.error().message);
  const std::span<const std::uint8_t> all(*bytes);
  const auto body = all.first(all.size() - kMacBytes);
  auto claims = readBody(body);
  if (!claims) return refuse(TokenError::kMalformed, claims.error().message);
  // Signature, in constant time; nothing of the claims is trusted before it matches.
  const auto mac = macOf(secret, body);
  if (secret.size() < kMinSecretBytes ||
      CRYPTO_memcmp(mac.data(), all.last(kMacBytes).data(), kMacBytes) != 0) {
    return refuse(TokenError::kBadSignature,
                  "join token: bad signature (made with another secret, or altered)");
  }
  check.claims = std::move(*claims);
  // Expiry, then what it grants.
  if (now_unix >= check.claims.expires_at) {
    return refuse(TokenError::kExpired,
                  fmt::format("join token: expired {} s ago", now_unix - check.claims.expires_at));
  }
  if (check.claims.room != room) {
    return refuse(TokenError::kWrongRoom,
                  fmt::format("join token: for room '{}', not '{}'", check.claims.room, room));
  }
  if (check.claims.name != name) {
    return refuse(TokenError::kWrongName,
                  fmt::format("join token: for name '{}', not '{}'", check.claims.name, name));
  }
  return check;
}

Result<std::int64_t> parseLifetime(std::string_view text) {
  constexpr std::int64_t kMax = 10ll * 366 * 86400;
  auto bad = [&] {
    return fail(
        "lifetime '{}': expected a whole number with an optional unit s, m, h or d (1 s to 10 "
        "years), e.g. 90s, 15m, 1h, 7d",
        text);
  };
  // The unit, if the text ends in one.
  std::int64_t unit = 1;
  std::string_view digits = text;
  if (!text.empty() && (text.back() < '0' || text.back() > '9')) {
    switch (text.back()) {
      case 's':
        unit = 1;
        break;
      case 'm':
        unit = 60;
        break;
      case 'h':
        unit = 3600;
        break;
      case 'd':
        unit = 86400;
        break;
      default:
        return bad();
    }
    digits.remove_suffix(1);
  }
  std::int64_t count = 0;
  const auto [end, ec] = std::from_chars(digits.data(), digits.data() + digits.size(), count);
  if (digits.empty() || ec != std::errc() || end != digits.data() + digits.size() || count < 1 ||
      count > kMax / unit) {
    return bad();
  }
  return count * unit;
}

}  // namespace vistel::auth
