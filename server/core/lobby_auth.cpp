// The lobby's join tokens (proto/SESSION.md §2.3): with a secret (ServerConfig
// join_secret), a Join must carry a token signed by it for the Join's room and name,
// valid at the lobby's unix clock. Refusals are UNAUTHORIZED, counted by reason
// ("token missing", "token malformed", "token bad signature", "token expired",
// "token wrong room", "token wrong name").
#include <fmt/format.h>

#include "common/auth/join_token.hpp"
#include "common/auth/token_command.hpp"
#include "server/core/lobby.hpp"

namespace vistel::server {

bool Lobby::admitToken(ConnId conn, const control::Join& join, double now, Effects& fx) {
  if (config_.join_secret.empty()) return true;
  // The check: missing, or what verification says.
  auth::TokenCheck check;
  if (join.token().empty()) {
    check.error = auth::TokenError::kMissing;
    check.message =
        "this server requires a join token for the room and name (ask its operator for one; "
        "clients and bots take --token)";
  } else {
    const std::int64_t unix_now = unix_clock_ ? unix_clock_() : auth::unixNow();
    check = auth::verifyJoinToken(config_.join_secret, join.token(), join.room(), join.name(),
                                  unix_now);
  }
  if (check.ok()) return true;
  // Refused: the reason names the kind of failure, the message says why.
  const std::string reason = fmt::format("token {}", auth::tokenErrorName(check.error));
  reject(conn, control::ErrorReply::UNAUTHORIZED, check.message, now, fx, reason);
  return false;
}

}  // namespace vistel::server
