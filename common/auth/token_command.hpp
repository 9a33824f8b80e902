// `vistel-server token`: a join token from the server's secret file, for a room, a name
// and a lifetime (join_token.hpp, secret_file.hpp).
#pragma once

#include <cstdint>
#include <string>

#include "common/base/result.hpp"

namespace vistel::auth {

struct TokenRequest {
  std::string secret_file;
  std::string room;        // 1..64 of [A-Za-z0-9_.-] (what the lobby accepts)
  std::string name;        // a valid member name (member_name.hpp)
  std::string ttl = "1h";  // parseLifetime
};

struct IssuedToken {
  std::string token;
  std::int64_t expires_at = 0;  // unix seconds
  std::string warning;          // the secret file's (permissions), or empty
};

// Reads the secret, checks room, name and lifetime (a token the lobby would refuse for
// them is not made), and signs. now_unix: the current unix time in seconds.
Result<IssuedToken> issueJoinToken(const TokenRequest& request, std::int64_t now_unix);

// The system clock in unix seconds.
std::int64_t unixNow();

}  // namespace vistel::auth
