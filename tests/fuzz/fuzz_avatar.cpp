// libFuzzer target: decodeAvatar (common/avatar/avatar_io.hpp) on arbitrary bytes, as a
// .vavatar file. Properties: nothing crashes, leaks or reads out of bounds; a rejected file
// gets a message naming the source; an accepted one is a valid avatar, and encoding it
// and decoding again gives the same model (compared through its encoding).
//
// Every chunk carries a CRC-32, so the custom mutator repairs the checksums of most
// mutants (fuzz_support.hpp). Seeds: small avatars encoded by encodeAvatar.
#include <cstdint>
#include <span>
#include <vector>

#include "common/avatar/avatar_io.hpp"
#include "common/base/bytes.hpp"
#include "tests/fuzz/fuzz_support.hpp"
#include "tests/fuzz/tiny_avatar.hpp"

namespace {

using namespace vistel;

constexpr std::size_t kFileHeader = 16;  // magic, version, chunk count
constexpr std::size_t kChunkHeader = 8;  // tag, payload size

// Recomputes the CRC-32 of every chunk whose payload and checksum lie within the input.
void repairChunks(std::uint8_t* data, std::size_t size) {
  std::size_t at = kFileHeader;
  while (at + kChunkHeader <= size) {
    const std::uint32_t payload = fuzz::loadU32(data + at + 4);
    const std::size_t body = at + kChunkHeader;
    if (payload > size - body || size - body - payload < 4) return;
    fuzz::storeU32(data + body + payload, crc32({data + body, payload}));
    at = body + payload + 4;
  }
}

std::vector<fuzz::Seed> makeSeeds() {
  std::vector<fuzz::Seed> seeds;
  for (int joints = 1; joints <= 3; ++joints) {
    for (int influences : {1, 2, 4}) {
      const AvatarModel avatar = fuzz::tinyAvatar(joints, influences);
      std::vector<std::uint8_t> bytes = encodeAvatar(avatar);
      fuzz::check(decodeAvatar(bytes, "seed").ok(), "a seed avatar decodes");
      seeds.push_back(
          {"tiny_j" + std::to_string(joints) + "_k" + std::to_string(influences) + ".vavatar",
           std::move(bytes)});
    }
  }
  return seeds;
}

}  // namespace

extern "C" int LLVMFuzzerInitialize(int* argc, char*** argv) {
  fuzz::writeSeedsIfAsked(*argc, *argv, makeSeeds);
  return 0;
}

extern "C" std::size_t LLVMFuzzerCustomMutator(std::uint8_t* data, std::size_t size,
                                               std::size_t max_size, unsigned seed) {
  return fuzz::mutateThenRepair(data, size, max_size, seed, repairChunks);
}

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::span<const std::uint8_t> bytes(data, size);
  Result<AvatarModel> avatar = decodeAvatar(bytes, "fuzz.vavatar");
  if (!avatar.ok()) {
    fuzz::check(avatar.error().message.starts_with("fuzz.vavatar"), "a rejection names the source");
    return 0;
  }
  fuzz::check(validateAvatar(*avatar).ok(), "an accepted avatar validates");

  // Round trip: the decoded model re-encodes to bytes that decode to the same model.
  const std::vector<std::uint8_t> encoded = encodeAvatar(*avatar);
  Result<AvatarModel> again = decodeAvatar(encoded, "again");
  fuzz::check(again.ok(), "the re-encoded avatar decodes");
  fuzz::check(encodeAvatar(*again) == encoded, "decode(encode(avatar)) is the same avatar");
  return 0;
}
