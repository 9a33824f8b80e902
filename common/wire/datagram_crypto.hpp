// Authenticated, encrypted UDP datagrams (proto/WIRE.md §3.9): the key exchange of the
// handshake, the AEAD that seals every datagram, and the replay window that drops a
// datagram seen before.
//
// Keys. The client sends an ephemeral X25519 public key in its Join; the server answers
// with its own in the Welcome. Both compute the X25519 shared secret and expand it with
// HKDF-SHA256 (salt "vistel udp v4", info: a label, both public keys, the member id, the
// room name) into four 256-bit secrets: the client -> server datagram key, the server ->
// client key for the room's datagrams (snapshots, pongs), the server -> client key for the
// lobby's datagrams (hello acks; a separate key so that lobby and room never share a
// nonce), and the resume secret (a later Join proves it holds it: resumeProof). No secret
// travels; a passive observer of the whole session learns none of them.
//
// Sealing. A datagram is written in its plain layout (packets.hpp): a clear header that
// ends with a u64 counter slot, then the body. sealDatagram stores the counter in the slot,
// encrypts the body in place with ChaCha20-Poly1305 (RFC 8439; nonce = 4 zero bytes, then
// the counter, little-endian; associated data = the clear header) and appends the 16-byte
// tag. openDatagram checks the tag and decrypts in place. Each key is used by exactly one
// sender with a strictly increasing counter from 1, so a nonce never repeats under a key.
//
// Replay. A receiver keeps a ReplayWindow per key: it accepts a counter once, newer than
// everything seen or within the 64 before the newest; check before opening (cheap), and
// mark only after the tag verified (a forged datagram cannot move the window).
//
// Cost: one ChaCha20-Poly1305 pass over the body (a few hundred ns to ~1 µs for 1200
// bytes); no heap allocation per datagram beyond growing the output vector by 16 bytes.
// Key generation and derivation allocate (OpenSSL objects), once per join.
#pragma once

#include <array>
#include <cstdint>
#include <span>
#include <string_view>
#include <vector>

#include "common/base/result.hpp"

namespace vistel::wire {

inline constexpr std::size_t kAeadKeyBytes = 32;
inline constexpr std::size_t kAeadTagBytes = 16;
inline constexpr std::size_t kCounterBytes = 8;
inline constexpr std::size_t kX25519KeyBytes = 32;
inline constexpr std::size_t kResumeSecretBytes = 32;
inline constexpr std::size_t kResumeProofBytes = 32;

using AeadKey = std::array<std::uint8_t, kAeadKeyBytes>;
using PublicKey = std::array<std::uint8_t, kX25519KeyBytes>;
using ResumeSecret = std::array<std::uint8_t, kResumeSecretBytes>;
using ResumeProof = std::array<std::uint8_t, kResumeProofBytes>;

// An ephemeral X25519 key pair (the private half stays inside; move-only).
class KeyExchange {
 public:
  // A fresh key pair from the system's random source.
  static Result<KeyExchange> generate();
  // The key pair of a given 32-byte X25519 private key (reproducible sessions: tests and
  // fuzzing replay a capture with the key it used; never for real sessions).
  static Result<KeyExchange> fromPrivateKey(std::span<const std::uint8_t> private_key);
  KeyExchange(KeyExchange&& other) noexcept;
  KeyExchange& operator=(KeyExchange&& other) noexcept;
  KeyExchange(const KeyExchange&) = delete;
  KeyExchange& operator=(const KeyExchange&) = delete;
  ~KeyExchange();

  const PublicKey& publicKey() const { return public_; }
  // The 32-byte shared secret with a peer's public key. Fails on a public key of another
  // size or one giving an all-zero secret (a low-order point).
  Result<std::array<std::uint8_t, 32>> sharedSecret(std::span<const std::uint8_t> peer) const;

 private:
  KeyExchange() = default;
  // Takes ownership of `key` (an EVP_PKEY*) and reads its public key.
  static Result<KeyExchange> adopt(void* key);
  void* key_ = nullptr;  // EVP_PKEY*
  PublicKey public_{};
};

// What both ends derive from one handshake.
struct SessionKeys {
  AeadKey client_to_server{};  // Hello, Posture, Ping
  AeadKey server_to_client{};  // Snapshot, Pong (the room)
  AeadKey server_hello{};      // HelloAck (the lobby)
  ResumeSecret resume{};       // proves, in a later Join, that this session was ours
};

// HKDF-SHA256 of the shared secret, bound to both public keys, the member id and the
// room name (WIRE.md §3.9). Fails only if OpenSSL does.
Result<SessionKeys> deriveSessionKeys(std::span<const std::uint8_t> shared_secret,
                                      const PublicKey& client_public,
                                      const PublicKey& server_public, std::uint32_t member_id,
                                      std::string_view room);

// Client and server in one call: a client key pair's public key and the server's
// answer (tests, benchmarks and the server's side of a Join).
struct Handshake {
  PublicKey server_public{};
  SessionKeys keys;
};
Result<Handshake> serverHandshake(std::span<const std::uint8_t> client_public,
                                  std::uint32_t member_id, std::string_view room);

// HMAC-SHA256(resume secret, "vistel resume" || the new Join's public key): a resume
// proof that is useless with any other key exchange (so seeing it in a Join gives nothing).
ResumeProof resumeProof(const ResumeSecret& secret, std::span<const std::uint8_t> new_public);
// Constant-time comparison of a received proof (any size) with the expected one.
bool resumeProofMatches(const ResumeSecret& secret, std::span<const std::uint8_t> new_public,
                        std::span<const std::uint8_t> proof);

// Seals a datagram in place: `datagram` holds the plain layout, whose first
// `clear_bytes` bytes are the clear header ending with the 8-byte counter slot. Writes
// the counter there, encrypts the rest, appends the tag. counter must be >= 1. False
// (datagram unchanged) when it is shorter than the header or counter is 0.
bool sealDatagram(const AeadKey& key, std::uint64_t counter, std::size_t clear_bytes,
                  std::vector<std::uint8_t>& datagram);
// Opens a sealed datagram in place: on success `datagram` (the caller's buffer) holds the
// plain layout in its first datagram.size() - 16 bytes, `plain_size` says how many, and
// `counter` is the header's. False when shorter than header + tag, or the tag does not
// verify (wrong key, any byte changed); the buffer's contents are then unspecified.
bool openDatagram(const AeadKey& key, std::size_t clear_bytes, std::span<std::uint8_t> datagram,
                  std::uint64_t& counter, std::size_t& plain_size);
// The counter in a sealed datagram's clear header (0 when too short): to check the replay
// window before opening.
std::uint64_t peekCounter(std::span<const std::uint8_t> datagram, std::size_t clear_bytes);

// A receiver's record of the counters it accepted: the newest, and which of the 64 below
// it. Counter 0 is never valid.
class ReplayWindow {
 public:
  static constexpr std::uint64_t kSize = 64;
  enum class Verdict { kFresh, kDuplicate, kTooOld, kInvalid };
  // Whether `counter` could be accepted (does not change the window).
  Verdict check(std::uint64_t counter) const;
  // Records an accepted counter (call after the datagram authenticated; check() first).
  void accept(std::uint64_t counter);
  std::uint64_t newest() const { return newest_; }

 private:
  std::uint64_t newest_ = 0;  // 0: nothing yet
  std::uint64_t seen_ = 0;    // bit i: counter newest_ - i accepted
};

// The reason a replay verdict is counted under ("replayed datagram", "datagram too old",
// "invalid counter"); empty for kFresh.
std::string_view replayReason(ReplayWindow::Verdict verdict);

// One direction's sender state: its key and the next counter.
struct DatagramSealer {
  AeadKey key{};
  std::uint64_t next_counter = 1;
  // Seals `datagram` with the next counter (WIRE.md §3.9). False only for a too-short
  // datagram.
  bool seal(std::size_t clear_bytes, std::vector<std::uint8_t>& datagram) {
    if (!sealDatagram(key, next_counter, clear_bytes, datagram)) return false;
    ++next_counter;
    return true;
  }
};

// One direction's receiver state: its key and replay window.
struct DatagramOpener {
  AeadKey key{};
  ReplayWindow window;
  // Opens `datagram` in place when its counter is fresh and its tag verifies; then marks
  // the counter. On failure `reason` names why ("replayed datagram", "datagram too old",
  // "invalid counter", "bad datagram tag").
  bool open(std::size_t clear_bytes, std::span<std::uint8_t> datagram, std::size_t& plain_size,
            std::string_view& reason);
};

}  // namespace vistel::wire
