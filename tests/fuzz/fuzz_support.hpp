// Shared pieces of the libFuzzer targets in tests/fuzz (header only: each target is one
// translation unit compiled with -fsanitize=fuzzer).
//
// - check(): a property of the decoder's contract that failed. It prints what and aborts,
//   which libFuzzer reports as a crash and saves the input.
// - Seeds: every target generates its own seed inputs with the project's encoders, so no
//   data files are copied into the repository. `fuzz_X --write-seeds=DIR` writes them into
//   DIR and exits (libFuzzer ignores arguments that start with "--"); scripts/fuzz does
//   this before each run. The same call registers the generator for the replay driver
//   (replay_main.cpp), which runs the seeds and mutants of them as an ordinary test.
// - Chunks: stream decoders are fed the input in pieces whose sizes come from a small
//   deterministic sequence, so split records and resynchronisation are exercised without
//   spending input bytes on the split.
// - Checksums: formats that carry a CRC-32 per chunk or record install a custom mutator
//   that repairs most mutants' checksums, so mutations reach the decoders behind them.
#pragma once

#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <functional>
#include <span>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include "common/base/bytes.hpp"

// libFuzzer's own mutator, callable from a custom mutator.
extern "C" std::size_t LLVMFuzzerMutate(std::uint8_t* data, std::size_t size, std::size_t max_size);

namespace vistel::fuzz {

// Aborts (a libFuzzer crash) when a property of the contract does not hold.
inline void check(bool condition, const char* what) {
  if (condition) return;
  std::fprintf(stderr, "fuzz property violated: %s\n", what);
  std::abort();
}

// A parser's rejection of the input: its message must name the source ("fuzz.toml"); with
// VISTEL_FUZZ_TRACE set it is printed (to check a corpus file or follow a finding).
inline void checkRejection(const std::string& message) {
  if (std::getenv("VISTEL_FUZZ_TRACE") != nullptr)
    std::fprintf(stderr, "rejected: %s\n", message.c_str());
  check(message.starts_with("fuzz.toml"), "a rejection names the source");
}

// A finite value within [lo, hi].
inline bool within(double v, double lo, double hi) {
  return std::isfinite(v) && v >= lo && v <= hi;
}

// ---- seeds -----------------------------------------------------------------------------

struct Seed {
  std::string name;                 // file name inside the corpus folder
  std::vector<std::uint8_t> bytes;  // the input
};

inline Seed textSeed(std::string name, std::string_view text) {
  return {std::move(name), std::vector<std::uint8_t>(text.begin(), text.end())};
}

inline std::string_view textOf(const Seed& seed) {
  return {reinterpret_cast<const char*>(seed.bytes.data()), seed.bytes.size()};
}

// The target's seed generator, once LLVMFuzzerInitialize has run (empty before).
inline std::function<std::vector<Seed>()>& registeredSeeds() {
  static std::function<std::vector<Seed>()> make_seeds;
  return make_seeds;
}

// Call from LLVMFuzzerInitialize: with --write-seeds=DIR among the arguments, writes
// make_seeds() into DIR (which must exist) and exits; otherwise registers make_seeds (for
// the replay driver) and returns.
template <typename MakeSeeds>
void writeSeedsIfAsked(int argc, char** argv, MakeSeeds make_seeds) {
  registeredSeeds() = make_seeds;
  constexpr std::string_view kFlag = "--write-seeds=";
  for (int i = 1; i < argc; ++i) {
    const std::string_view arg(argv[i]);
    if (!arg.starts_with(kFlag)) continue;
    const std::string dir(arg.substr(kFlag.size()));
    int written = 0;
    for (const Seed& seed : make_seeds()) {
      std::ofstream out(dir + "/" + seed.name, std::ios::binary | std::ios::trunc);
      out.write(reinterpret_cast<const char*>(seed.bytes.data()),
                static_cast<std::streamsize>(seed.bytes.size()));
      if (!out) {
        std::fprintf(stderr, "cannot write seed %s/%s\n", dir.c_str(), seed.name.c_str());
        std::exit(1);
      }
      ++written;
    }
    std::printf("%d seeds written to %s\n", written, dir.c_str());
    std::exit(0);
  }
}

// ---- chunked feeding -------------------------------------------------------------------

// Calls feed(piece) for consecutive pieces of `bytes`, 1..17 bytes each, in a pattern
// that depends on `salt` (so different inputs split differently).
template <typename Feed>
void feedInChunks(std::span<const std::uint8_t> bytes, unsigned salt, Feed feed) {
  std::size_t at = 0;
  unsigned state = salt * 2654435761u + 1u;
  while (at < bytes.size()) {
    state = state * 1103515245u + 12345u;
    const std::size_t want = 1 + (state >> 16) % 17;
    const std::size_t n = want < bytes.size() - at ? want : bytes.size() - at;
    feed(bytes.subspan(at, n));
    at += n;
  }
}

// ---- checksum repair -------------------------------------------------------------------

inline std::uint32_t loadU32(const std::uint8_t* p) {
  std::uint32_t v = 0;
  std::memcpy(&v, p, 4);
  return v;
}

inline void storeU32(std::uint8_t* p, std::uint32_t v) { std::memcpy(p, &v, 4); }

// Mutates with libFuzzer's mutator, then, for three mutants in four, lets repair(data,
// size) recompute the checksums (the fourth keeps exercising the checksum checks).
template <typename Repair>
std::size_t mutateThenRepair(std::uint8_t* data, std::size_t size, std::size_t max_size,
                             unsigned seed, Repair repair) {
  const std::size_t n = LLVMFuzzerMutate(data, size, max_size);
  if (seed % 4 != 0) repair(data, n);
  return n;
}

}  // namespace vistel::fuzz
