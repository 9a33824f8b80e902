#include "common/auth/token_command.hpp"

#include <algorithm>
#include <chrono>

#include "common/auth/join_token.hpp"
#include "common/auth/member_name.hpp"
#include "common/auth/secret_file.hpp"

namespace vistel::auth {

Result<IssuedToken> issueJoinToken(const TokenRequest& request, std::int64_t now_unix) {
  // What the token grants: the lobby's rules for rooms and names.
  const bool room_ok = !request.room.empty() && request.room.size() <= 64 &&
                       std::all_of(request.room.begin(), request.room.end(), [](char c) {
                         return (c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') ||
                                (c >= '0' && c <= '9') || c == '_' || c == '.' || c == '-';
                       });
  if (!room_ok) return fail("--room '{}': 1-64 characters of A-Z a-z 0-9 _ . -", request.room);
  if (Status name = validateMemberName(request.name); !name) {
    return fail("--name: {}", name.error().message);
  }
  auto lifetime = parseLifetime(request.ttl);
  if (!lifetime) return fail("--ttl: {}", lifetime.error().message);
  // Sign with the secret.
  auto secret = readJoinSecret(request.secret_file);
  if (!secret) return secret.error();
  IssuedToken issued;
  issued.expires_at = now_unix + *lifetime;
  issued.warning = secret->warning;
  auto token = createJoinToken(secret->bytes, {request.room, request.name, issued.expires_at});
  if (!token) return token.error();
  issued.token = std::move(*token);
  return issued;
}

std::int64_t unixNow() {
  return std::chrono::duration_cast<std::chrono::seconds>(
             std::chrono::system_clock::now().time_since_epoch())
      .count();
}

}  // namespace vistel::auth
