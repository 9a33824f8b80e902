// The server's join-token secret, read from a file (`--secret-file`, [auth] secret_file).
//
// The secret is the file's bytes with trailing whitespace (LF, CR, space, tab) removed, so
// `openssl rand -hex 32 > F` and an editor's final newline give the same secret to the
// server and to `vistel-server token`. Refused: a missing or unreadable file, a secret
// shorter than kMinSecretBytes (the message names the file and both sizes) or longer than
// 64 KiB. A file that its group or others may read is accepted with a warning (the
// caller logs it): anyone who reads it can mint tokens.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "common/base/result.hpp"

namespace vistel::auth {

struct JoinSecret {
  std::vector<std::uint8_t> bytes;  // >= kMinSecretBytes
  std::string warning;              // non-empty: say it (permissions too open)
};

Result<JoinSecret> readJoinSecret(const std::string& path);

}  // namespace vistel::auth
