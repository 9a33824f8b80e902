// Seal + open of the datagrams a session sends (proto/WIRE.md §3.9): per-datagram time of
// ChaCha20-Poly1305 over a 52-joint keyframe posture (236 plain bytes), a typical delta
// posture (70), a full snapshot (1184, the largest that fits 1200 sealed), and the
// handshake (X25519 key pair, agreement, HKDF) both sides do once per join.
#include <cstdint>
#include <vector>

#include <benchmark/benchmark.h>

#include "common/wire/datagram_crypto.hpp"
#include "common/wire/packets.hpp"

namespace vistel {
namespace {

wire::AeadKey benchKey() {
  wire::AeadKey k{};
  for (std::size_t i = 0; i < k.size(); ++i) k[i] = static_cast<std::uint8_t>(i * 3 + 1);
  return k;
}

// A plain datagram of `size` bytes with a valid-looking clear header.
std::vector<std::uint8_t> plainOf(std::size_t size, wire::PacketType type) {
  std::vector<std::uint8_t> d(size, 0x5A);
  d[0] = wire::kWireVersion;
  d[1] = static_cast<std::uint8_t>(type);
  return d;
}

// Seal then open (in place), as sender and receiver do for every datagram.
void sealOpen(benchmark::State& state, std::size_t size, wire::PacketType type) {
  const wire::AeadKey key = benchKey();
  const std::size_t clear = wire::clearHeaderBytes(type);
  const std::vector<std::uint8_t> plain = plainOf(size, type);
  std::vector<std::uint8_t> d;
  d.reserve(wire::kMaxDatagramBytes);
  wire::DatagramSealer sealer{key};
  wire::DatagramOpener opener{key, {}};
  std::size_t plain_size = 0;
  std::string_view reason;
  for (auto _ : state) {
    d.assign(plain.begin(), plain.end());
    sealer.seal(clear, d);
    const bool ok = opener.open(clear, d, plain_size, reason);
    benchmark::DoNotOptimize(ok);
  }
  state.SetBytesProcessed(static_cast<std::int64_t>(state.iterations() * size));
  state.counters["sealed_bytes"] = static_cast<double>(size + wire::kSealOverheadBytes);
}

void sealOnly(benchmark::State& state, std::size_t size, wire::PacketType type) {
  const wire::AeadKey key = benchKey();
  const std::size_t clear = wire::clearHeaderBytes(type);
  const std::vector<std::uint8_t> plain = plainOf(size, type);
  std::vector<std::uint8_t> d;
  d.reserve(wire::kMaxDatagramBytes);
  wire::DatagramSealer sealer{key};
  for (auto _ : state) {
    d.assign(plain.begin(), plain.end());
    sealer.seal(clear, d);
    benchmark::DoNotOptimize(d.data());
  }
  state.SetBytesProcessed(static_cast<std::int64_t>(state.iterations() * size));
}

void BM_SealOpenPostureKeyframe(benchmark::State& state) {
  sealOpen(state, 236, wire::PacketType::kPosture);
}
void BM_SealOpenPostureDelta(benchmark::State& state) {
  sealOpen(state, 70, wire::PacketType::kPosture);
}
void BM_SealOpenFullSnapshot(benchmark::State& state) {
  sealOpen(state, wire::kMaxPlainDatagramBytes, wire::PacketType::kSnapshot);
}
void BM_SealFullSnapshot(benchmark::State& state) {
  sealOnly(state, wire::kMaxPlainDatagramBytes, wire::PacketType::kSnapshot);
}

void BM_Handshake(benchmark::State& state) {
  for (auto _ : state) {
    auto client = wire::KeyExchange::generate();
    auto server = wire::serverHandshake(client->publicKey(), 0x00010002u, "lab");
    auto shared = client->sharedSecret(server->server_public);
    auto keys = wire::deriveSessionKeys(*shared, client->publicKey(), server->server_public,
                                        0x00010002u, "lab");
    benchmark::DoNotOptimize(keys.ok());
  }
}

BENCHMARK(BM_SealOpenPostureKeyframe);
BENCHMARK(BM_SealOpenPostureDelta);
BENCHMARK(BM_SealOpenFullSnapshot);
BENCHMARK(BM_SealFullSnapshot);
BENCHMARK(BM_Handshake);

}  // namespace
}  // namespace vistel

BENCHMARK_MAIN();
