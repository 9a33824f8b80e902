// The datagram seal (WIRE.md §3.9): key exchange, AEAD round trips and tampering, the
// replay window's edges.
#include "common/wire/datagram_crypto.hpp"

#include <gtest/gtest.h>

#include <limits>

#include "common/wire/packets.hpp"

namespace vistel::wire {
namespace {

SessionKeys handshake(std::uint32_t member = 0x00010002, std::string_view room = "lab") {
  auto client = KeyExchange::generate();
  EXPECT_TRUE(client.ok());
  auto server = serverHandshake(client->publicKey(), member, room);
  EXPECT_TRUE(server.ok());
  auto shared = client->sharedSecret(server->server_public);
  EXPECT_TRUE(shared.ok());
  auto keys = deriveSessionKeys(*shared, client->publicKey(), server->server_public, member, room);
  EXPECT_TRUE(keys.ok());
  EXPECT_EQ(keys->client_to_server, server->keys.client_to_server);
  EXPECT_EQ(keys->server_to_client, server->keys.server_to_client);
  EXPECT_EQ(keys->server_hello, server->keys.server_hello);
  EXPECT_EQ(keys->resume, server->keys.resume);
  return *keys;
}

std::vector<std::uint8_t> pingDatagram() {
  PingPacket ping;
  ping.header.member_id = 0x00010002;
  ping.ping_id = 7;
  ping.client_time = 1.5;
  std::vector<std::uint8_t> bytes;
  write(ping, bytes);
  return bytes;
}

TEST(DatagramCrypto, BothSidesDeriveTheSameDistinctKeys) {
  const SessionKeys k = handshake();
  EXPECT_NE(k.client_to_server, k.server_to_client);
  EXPECT_NE(k.server_to_client, k.server_hello);
  EXPECT_NE(k.client_to_server, k.server_hello);
  // Another handshake (fresh ephemeral keys) gives other keys.
  const SessionKeys other = handshake();
  EXPECT_NE(k.client_to_server, other.client_to_server);
}

TEST(DatagramCrypto, KeysAreBoundToMemberAndRoom) {
  auto client = KeyExchange::generate();
  ASSERT_TRUE(client.ok());
  auto server = serverHandshake(client->publicKey(), 5, "lab");
  ASSERT_TRUE(server.ok());
  auto shared = client->sharedSecret(server->server_public);
  ASSERT_TRUE(shared.ok());
  auto other_member =
      deriveSessionKeys(*shared, client->publicKey(), server->server_public, 6, "lab");
  auto other_room =
      deriveSessionKeys(*shared, client->publicKey(), server->server_public, 5, "lab2");
  ASSERT_TRUE(other_member.ok() && other_room.ok());
  EXPECT_NE(other_member->client_to_server, server->keys.client_to_server);
  EXPECT_NE(other_room->client_to_server, server->keys.client_to_server);
}

TEST(DatagramCrypto, BadPublicKeysAreRefused) {
  auto pair = KeyExchange::generate();
  ASSERT_TRUE(pair.ok());
  std::vector<std::uint8_t> short_key(31, 9);
  EXPECT_FALSE(pair->sharedSecret(short_key).ok());
  EXPECT_FALSE(serverHandshake(short_key, 1, "lab").ok());
  // The identity (all zero) is a low-order point: no secret from it.
  std::array<std::uint8_t, 32> zero{};
  EXPECT_FALSE(pair->sharedSecret(zero).ok());
  EXPECT_FALSE(serverHandshake(zero, 1, "lab").ok());
}

TEST(DatagramCrypto, SealOpenRoundTripKeepsHeaderClearAndBodySecret) {
  const SessionKeys k = handshake();
  const std::vector<std::uint8_t> plain = pingDatagram();
  std::vector<std::uint8_t> sealed = plain;
  ASSERT_TRUE(sealDatagram(k.client_to_server, 42, kClientHeaderBytes, sealed));
  ASSERT_EQ(sealed.size(), plain.size() + kAeadTagBytes);
  // Version, type and member id unchanged; the counter in its slot; the body encrypted.
  EXPECT_TRUE(std::equal(plain.begin(), plain.begin() + 6, sealed.begin()));
  EXPECT_EQ(peekCounter(sealed, kClientHeaderBytes), 42u);
  EXPECT_FALSE(std::equal(plain.begin() + kClientHeaderBytes, plain.end(),
                          sealed.begin() + kClientHeaderBytes));
  EXPECT_EQ(peekPacketType(sealed), PacketType::kPing);
  EXPECT_EQ(peekMemberId(sealed), 0x00010002u);

  std::uint64_t counter = 0;
  std::size_t plain_size = 0;
  std::vector<std::uint8_t> buffer = sealed;
  ASSERT_TRUE(openDatagram(k.client_to_server, kClientHeaderBytes, buffer, counter, plain_size));
  EXPECT_EQ(counter, 42u);
  ASSERT_EQ(plain_size, plain.size());
  PingPacket back;
  ASSERT_TRUE(read(std::span(buffer).first(plain_size), back));
  EXPECT_EQ(back.ping_id, 7u);
  EXPECT_EQ(back.client_time, 1.5);
  EXPECT_EQ(back.header.counter, 42u);
}

TEST(DatagramCrypto, AnyChangedByteIsRejected) {
  const SessionKeys k = handshake();
  std::vector<std::uint8_t> sealed = pingDatagram();
  ASSERT_TRUE(sealDatagram(k.client_to_server, 3, kClientHeaderBytes, sealed));
  for (std::size_t i = 0; i < sealed.size(); ++i) {
    for (std::uint8_t flip : {std::uint8_t{0x01}, std::uint8_t{0x80}}) {
      std::vector<std::uint8_t> bad = sealed;
      bad[i] ^= flip;
      std::uint64_t counter = 0;
      std::size_t plain_size = 0;
      EXPECT_FALSE(openDatagram(k.client_to_server, kClientHeaderBytes, bad, counter, plain_size))
          << "byte " << i << " flipped by " << int(flip);
    }
  }
  // Truncated (tag cut) and extended datagrams are rejected too.
  for (std::size_t cut = 1; cut <= kAeadTagBytes + 2; ++cut) {
    std::vector<std::uint8_t> bad(sealed.begin(), sealed.end() - static_cast<long>(cut));
    std::uint64_t counter = 0;
    std::size_t plain_size = 0;
    EXPECT_FALSE(openDatagram(k.client_to_server, kClientHeaderBytes, bad, counter, plain_size));
  }
  std::vector<std::uint8_t> longer = sealed;
  longer.push_back(0);
  std::uint64_t counter = 0;
  std::size_t plain_size = 0;
  EXPECT_FALSE(openDatagram(k.client_to_server, kClientHeaderBytes, longer, counter, plain_size));
}

TEST(DatagramCrypto, WrongKeyOrDirectionIsRejected) {
  const SessionKeys k = handshake();
  const SessionKeys other = handshake();
  std::vector<std::uint8_t> sealed = pingDatagram();
  ASSERT_TRUE(sealDatagram(k.client_to_server, 1, kClientHeaderBytes, sealed));
  for (const AeadKey* key : {&other.client_to_server, &k.server_to_client, &k.server_hello}) {
    std::vector<std::uint8_t> buffer = sealed;
    std::uint64_t counter = 0;
    std::size_t plain_size = 0;
    EXPECT_FALSE(openDatagram(*key, kClientHeaderBytes, buffer, counter, plain_size));
  }
  // The clear header's extent is part of what is authenticated.
  std::vector<std::uint8_t> buffer = sealed;
  std::uint64_t counter = 0;
  std::size_t plain_size = 0;
  EXPECT_FALSE(openDatagram(k.client_to_server, kServerHeaderBytes, buffer, counter, plain_size));
}

TEST(DatagramCrypto, SealRefusesCounterZeroAndShortDatagrams) {
  const SessionKeys k = handshake();
  std::vector<std::uint8_t> d = pingDatagram();
  const auto before = d;
  EXPECT_FALSE(sealDatagram(k.client_to_server, 0, kClientHeaderBytes, d));
  EXPECT_EQ(d, before);
  std::vector<std::uint8_t> tiny(5, 0);
  EXPECT_FALSE(sealDatagram(k.client_to_server, 1, kClientHeaderBytes, tiny));
  // A datagram that is only a header still seals (an empty body, a tag).
  std::vector<std::uint8_t> header_only(kServerHeaderBytes, 0);
  ASSERT_TRUE(sealDatagram(k.server_to_client, std::numeric_limits<std::uint64_t>::max(),
                           kServerHeaderBytes, header_only));
  std::uint64_t counter = 0;
  std::size_t plain_size = 0;
  ASSERT_TRUE(
      openDatagram(k.server_to_client, kServerHeaderBytes, header_only, counter, plain_size));
  EXPECT_EQ(counter, std::numeric_limits<std::uint64_t>::max());
  EXPECT_EQ(plain_size, kServerHeaderBytes);
}

TEST(DatagramCrypto, SealerCountsAndOpenerDropsReplays) {
  const SessionKeys k = handshake();
  DatagramSealer sealer{k.client_to_server};
  DatagramOpener opener{k.client_to_server, {}};
  std::vector<std::vector<std::uint8_t>> sent;
  for (int i = 0; i < 3; ++i) {
    sent.push_back(pingDatagram());
    ASSERT_TRUE(sealer.seal(kClientHeaderBytes, sent.back()));
    EXPECT_EQ(peekCounter(sent.back(), kClientHeaderBytes), static_cast<std::uint64_t>(i + 1));
  }
  // Reordered within the window: accepted once each; a copy of any: dropped.
  for (int i : {2, 0, 1}) {
    std::vector<std::uint8_t> buffer = sent[static_cast<std::size_t>(i)];
    std::size_t plain_size = 0;
    std::string_view reason;
    EXPECT_TRUE(opener.open(kClientHeaderBytes, buffer, plain_size, reason)) << i;
  }
  for (const auto& d : sent) {
    std::vector<std::uint8_t> buffer = d;
    std::size_t plain_size = 0;
    std::string_view reason;
    EXPECT_FALSE(opener.open(kClientHeaderBytes, buffer, plain_size, reason));
    EXPECT_EQ(reason, "replayed datagram");
  }
  // A forged datagram with a fresh counter does not move the window.
  std::vector<std::uint8_t> forged = pingDatagram();
  ASSERT_TRUE(sealDatagram(handshake().client_to_server, 1000, kClientHeaderBytes, forged));
  std::size_t plain_size = 0;
  std::string_view reason;
  EXPECT_FALSE(opener.open(kClientHeaderBytes, forged, plain_size, reason));
  EXPECT_EQ(reason, "bad datagram tag");
  EXPECT_EQ(opener.window.newest(), 3u);
}

TEST(ReplayWindow, EdgesOfTheWindow) {
  ReplayWindow w;
  using V = ReplayWindow::Verdict;
  EXPECT_EQ(w.check(0), V::kInvalid);
  EXPECT_EQ(w.check(1), V::kFresh);
  w.accept(100);
  EXPECT_EQ(w.check(100), V::kDuplicate);
  EXPECT_EQ(w.check(101), V::kFresh);
  EXPECT_EQ(w.check(37), V::kFresh);   // 63 behind: the oldest slot of the window
  EXPECT_EQ(w.check(36), V::kTooOld);  // 64 behind: outside
  w.accept(37);
  EXPECT_EQ(w.check(37), V::kDuplicate);
  // Moving ahead by less than the window keeps what was seen.
  w.accept(110);
  EXPECT_EQ(w.check(100), V::kDuplicate);
  EXPECT_EQ(w.check(37), V::kTooOld);
  EXPECT_EQ(w.check(105), V::kFresh);
  // Moving ahead by 63 keeps the old newest as the window's oldest slot; by 64, not.
  w.accept(173);
  EXPECT_EQ(w.check(110), V::kDuplicate);
  w.accept(174);
  EXPECT_EQ(w.check(110), V::kTooOld);
  EXPECT_EQ(w.check(173), V::kDuplicate);
}

TEST(ReplayWindow, ExactWindowShiftAndLargeJumps) {
  ReplayWindow w;
  using V = ReplayWindow::Verdict;
  w.accept(10);
  w.accept(74);  // 64 ahead: the bitmap is cleared
  EXPECT_EQ(w.check(10), V::kTooOld);
  EXPECT_EQ(w.check(11), V::kFresh);
  EXPECT_EQ(w.check(74), V::kDuplicate);
  w.accept(73);
  EXPECT_EQ(w.check(73), V::kDuplicate);
  // A huge jump, up to the last counter: no overflow, the window follows.
  const std::uint64_t top = std::numeric_limits<std::uint64_t>::max();
  w.accept(top);
  EXPECT_EQ(w.check(top), V::kDuplicate);
  EXPECT_EQ(w.check(top - 1), V::kFresh);
  EXPECT_EQ(w.check(top - 63), V::kFresh);
  EXPECT_EQ(w.check(top - 64), V::kTooOld);
  EXPECT_EQ(w.check(74), V::kTooOld);
  w.accept(top - 63);
  EXPECT_EQ(w.check(top - 63), V::kDuplicate);
  EXPECT_EQ(replayReason(V::kDuplicate), "replayed datagram");
  EXPECT_EQ(replayReason(V::kTooOld), "datagram too old");
  EXPECT_EQ(replayReason(V::kFresh), "");
}

TEST(ReplayWindow, EveryCounterOnceUnderReordering) {
  // 1..500 delivered in blocks of 8 reversed, each twice: each accepted exactly once.
  ReplayWindow w;
  int accepted = 0;
  for (std::uint64_t block = 0; block < 500 / 8 + 1; ++block) {
    for (int copy = 0; copy < 2; ++copy) {
      for (std::uint64_t i = 8; i >= 1; --i) {
        const std::uint64_t c = block * 8 + i;
        if (c > 500) continue;
        if (w.check(c) == ReplayWindow::Verdict::kFresh) {
          w.accept(c);
          ++accepted;
        }
      }
    }
  }
  EXPECT_EQ(accepted, 500);
}

TEST(DatagramCrypto, ResumeProofIsBoundToTheNewKey) {
  const SessionKeys k = handshake();
  auto a = KeyExchange::generate();
  auto b = KeyExchange::generate();
  ASSERT_TRUE(a.ok() && b.ok());
  const ResumeProof proof = resumeProof(k.resume, a->publicKey());
  EXPECT_TRUE(resumeProofMatches(k.resume, a->publicKey(), proof));
  EXPECT_FALSE(resumeProofMatches(k.resume, b->publicKey(), proof));  // replayed with another key
  EXPECT_FALSE(resumeProofMatches(handshake().resume, a->publicKey(), proof));
  EXPECT_FALSE(resumeProofMatches(k.resume, a->publicKey(), std::span(proof).first(31)));
  ResumeProof bad = proof;
  bad[5] ^= 1;
  EXPECT_FALSE(resumeProofMatches(k.resume, a->publicKey(), bad));
}

}  // namespace
}  // namespace vistel::wire
