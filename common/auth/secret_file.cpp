#include "common/auth/secret_file.hpp"

#include <sys/stat.h>

#include "common/auth/join_token.hpp"
#include "common/base/file.hpp"

namespace vistel::auth {

Result<JoinSecret> readJoinSecret(const std::string& path) {
  constexpr std::size_t kMaxSecretBytes = 64u << 10;
  if (path.empty()) return fail("secret file: no path given");
  // The bytes, less trailing whitespace.
  auto bytes = readFileBytes(path, kMaxSecretBytes);
  if (!bytes) return fail("secret file: {}", bytes.error().message);
  JoinSecret secret;
  secret.bytes = std::move(*bytes);
  while (!secret.bytes.empty() && (secret.bytes.back() == '\n' || secret.bytes.back() == '\r' ||
                                   secret.bytes.back() == ' ' || secret.bytes.back() == '\t')) {
    secret.bytes.pop_back();
  }
  if (secret.bytes.size() < kMinSecretBytes) {
    return fail(
        "secret file {}: {} bytes, but a join-token secret needs at least {} (make one with "
        "`openssl rand -hex 32 > {}`)",
        path, secret.bytes.size(), kMinSecretBytes, path);
  }
  // Who else may read it.
  struct stat info {};
  if (::stat(path.c_str(), &info) == 0 && (info.st_mode & (S_IRGRP | S_IROTH)) != 0) {
    secret.warning = fmt::format(
        "secret file {} is readable by {} (mode {:o}): anyone who reads it can mint join "
        "tokens; chmod 600 it",
        path, (info.st_mode & S_IROTH) != 0 ? "everyone" : "its group", info.st_mode & 0777);
  }
  return secret;
}

}  // namespace vistel::auth
