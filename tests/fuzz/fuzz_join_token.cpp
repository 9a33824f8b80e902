// libFuzzer target: join tokens and member names (common/auth) on arbitrary bytes, as a
// hostile client puts them in Join.token and Join.name. Properties: nothing crashes or
// reads out of bounds; a token verifies only with the claims it was checked against; a
// token that parses re-encodes to one that verifies; a name that validates is valid UTF-8
// of 1..64 characters with none of the forbidden ones at its ends.
//
// Seeds: tokens made with the test secret (plain, Unicode name, empty claims, expired),
// one made with another secret, and names.
#include <cstdint>
#include <string>
#include <string_view>
#include <vector>

#include "common/auth/join_token.hpp"
#include "common/auth/member_name.hpp"
#include "tests/fuzz/fuzz_support.hpp"

namespace {

using namespace vistel;
using fuzz::check;

const std::vector<std::uint8_t> kSecret(32, 0x42);
constexpr std::int64_t kNow = 1'700'000'000;

std::vector<fuzz::Seed> makeSeeds() {
  std::vector<fuzz::Seed> seeds;
  auto add = [&](const char* name, const std::vector<std::uint8_t>& secret,
                 const auth::JoinClaims& claims) {
    auto token = auth::createJoinToken(secret, claims);
    check(token.ok(), "a seed token is made");
    seeds.push_back(fuzz::textSeed(name, *token));
  };
  add("gen_plain.txt", kSecret, {"lab", "alice", kNow + 3600});
  add("gen_unicode.txt", kSecret, {"r-1.x_y", "Zo\xC3\xAB \xE6\x9D\x8E", kNow + 60});
  add("gen_empty_claims.txt", kSecret, {"", "", kNow + 1});
  add("gen_expired.txt", kSecret, {"lab", "bob", kNow - 1});
  add("gen_other_secret.txt", std::vector<std::uint8_t>(40, 0x07), {"lab", "alice", kNow + 60});
  seeds.push_back(fuzz::textSeed("gen_name_bidi.txt", "evil\xE2\x80\xAEtxt"));
  seeds.push_back(fuzz::textSeed("gen_name_ascii.txt", "Dr. Who (guest)"));
  return seeds;
}

}  // namespace

extern "C" int LLVMFuzzerInitialize(int* argc, char*** argv) {
  fuzz::writeSeedsIfAsked(*argc, *argv, makeSeeds);
  return 0;
}

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string_view text(reinterpret_cast<const char*>(data), size);
  // As a token: verification against a room and name from the token itself, and others.
  const auto parsed = auth::parseJoinToken(text);
  const auth::TokenCheck plain = auth::verifyJoinToken(kSecret, text, "lab", "alice", kNow);
  check(plain.ok() == plain.message.empty(), "a refusal says why, a success says nothing");
  if (plain.ok()) {
    check(plain.claims.room == "lab" && plain.claims.name == "alice" &&
              plain.claims.expires_at > kNow,
          "an accepted token grants what was asked");
  }
  if (plain.error != auth::TokenError::kMalformed)
    check(parsed.ok(), "verifiable implies parsable");
  if (parsed.ok()) {
    const auto again = auth::verifyJoinToken(kSecret, text, parsed->room, parsed->name, kNow);
    check(
        again.error != auth::TokenError::kWrongRoom && again.error != auth::TokenError::kWrongName,
        "a token is for its own claims");
    auto remade = auth::createJoinToken(kSecret, *parsed);
    check(remade.ok(), "parsed claims can be signed");
    if (parsed->expires_at != INT64_MIN) {
      const auto remade_check = auth::verifyJoinToken(kSecret, *remade, parsed->room, parsed->name,
                                                      parsed->expires_at - 1);
      check(remade_check.ok(), "a re-signed token verifies before its expiry");
    }
  }
  // As a name.
  if (auth::validateMemberName(text).ok()) {
    check(!text.empty() && text.size() <= 4 * auth::kMaxNameChars, "a valid name is 1..256 bytes");
    check(text.front() != ' ' && text.back() != ' ', "no spaces at the ends");
    for (char c : text) {
      const auto u = static_cast<unsigned char>(c);
      check(u >= 0x20 && u != 0x7F, "no C0 controls or DEL");
    }
  }
  return 0;
}
