// The posture delta codec: round trips against the encoder's own reconstruction, the stated
// precision, a lossy reordering channel, keyframe recovery, sequence wrap-around, forwarding,
// and hostile bytes (every prefix, appended bytes, random and mutated buffers).
#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <deque>
#include <map>
#include <random>
#include <string>
#include <vector>

#include <gtest/gtest.h>
#include <glm/gtc/quaternion.hpp>

#include "common/wire/posture_delta.hpp"

namespace vistel::wire {
namespace {

constexpr int kJoints = 52;
constexpr double kFrame = 1.0 / 60.0;

double angleRad(const glm::quat& a, const glm::quat& b) {
  const double d =
      std::fabs(double(a.w) * b.w + double(a.x) * b.x + double(a.y) * b.y + double(a.z) * b.z);
  return 2.0 * std::acos(std::min(1.0, d));
}

// A moving body: each joint turns at its own rate (some still, some fast), plus noise.
class Motion {
 public:
  explicit Motion(std::uint64_t seed) : rng_(seed) {
    posture_.rotations.assign(kJoints, glm::quat(1, 0, 0, 0));
    std::uniform_real_distribution<float> u(-1.0f, 1.0f);
    for (int j = 0; j < kJoints; ++j) {
      glm::vec3 axis(u(rng_), u(rng_), u(rng_));
      axis = glm::length(axis) > 1e-3f ? glm::normalize(axis) : glm::vec3(0, 1, 0);
      const float speed = j % 5 == 0 ? 0.0f : (j % 3 == 0 ? 3.0f : 0.4f);  // rad/s
      rates_.push_back(axis * speed);
      posture_.rotations[static_cast<std::size_t>(j)] =
          glm::angleAxis(u(rng_), glm::normalize(glm::vec3(u(rng_), 1.0f, u(rng_))));
    }
  }
  const Posture& next(double t) {
    std::normal_distribution<float> noise(0.0f, 0.002f);
    for (std::size_t j = 0; j < rates_.size(); ++j) {
      const glm::vec3 w =
          rates_[j] * float(kFrame) +
          (j % 7 == 1 ? glm::vec3(noise(rng_), noise(rng_), noise(rng_)) : glm::vec3(0.0f));
      const float a = glm::length(w);
      if (a > 0.0f) {
        posture_.rotations[j] = glm::normalize(glm::angleAxis(a, w / a) * posture_.rotations[j]);
      }
    }
    posture_.root_translation =
        glm::vec3(0.3f * std::sin(t), 0.9f + 0.02f * std::sin(5 * t), 0.5f * std::cos(0.7 * t));
    posture_.time = t;
    return posture_;
  }

 private:
  std::mt19937_64 rng_;
  std::vector<glm::vec3> rates_;
  Posture posture_;
};

void expectWithinBound(const PostureRecord& got, const Posture& sent) {
  ASSERT_EQ(got.joint_count, sent.rotations.size());
  for (std::size_t j = 0; j < sent.rotations.size(); ++j) {
    EXPECT_LE(angleRad(unpackQuat(got.rotations[j]), sent.rotations[j]), kQuatAngleBoundRad)
        << "joint " << j;
  }
  for (int k = 0; k < 3; ++k) {
    EXPECT_LE(
        std::fabs(got.root_mm[static_cast<std::size_t>(k)] * kRootUnit - sent.root_translation[k]),
        kRootUnit + 1e-6f);
  }
}

bool sameRecord(const PostureRecord& a, const PostureRecord& b) {
  if (a.sequence != b.sequence || a.time != b.time || a.root_mm != b.root_mm ||
      a.joint_count != b.joint_count) {
    return false;
  }
  return std::equal(a.rotations.begin(), a.rotations.begin() + a.joint_count, b.rotations.begin());
}

TEST(PostureDelta, RoundTripMatchesEncoderAndStaysWithinBound) {
  for (DeltaReference ref :
       {DeltaReference::kAcked, DeltaReference::kKeyframe, DeltaReference::kPrevious}) {
    PostureDeltaOptions options;
    options.reference = ref;
    PostureDeltaEncoder enc(options);
    PostureDeltaDecoder dec(kJoints);
    Motion motion(3);
    std::vector<std::uint8_t> bytes;
    PostureRecord got;
    int keys = 0;
    std::size_t total = 0;
    for (int i = 0; i < 600; ++i) {
      const double t = 10.0 + i * kFrame;
      const Posture& p = motion.next(t);
      bytes.clear();
      DeltaFrameInfo info;
      ASSERT_TRUE(enc.encode(p, static_cast<std::uint16_t>(i), t, false, bytes, &info));
      EXPECT_EQ(info.bytes, static_cast<int>(bytes.size()));
      total += bytes.size();
      keys += info.keyframe ? 1 : 0;
      const DeltaDecodeResult r = dec.decode(bytes, got);
      ASSERT_TRUE(r.ok()) << r.reason << " at frame " << i;
      EXPECT_EQ(r.keyframe, info.keyframe);
      ASSERT_TRUE(sameRecord(got, enc.lastReconstructed())) << "frame " << i;
      expectWithinBound(got, p);
      EXPECT_NEAR(fromWireTime(got.time, t), t, 1e-4);
      enc.acknowledge(r.sequence);
    }
    // Keyframes every 0.5 s of capture time: 600 frames at 60 Hz -> 20.
    EXPECT_GE(keys, 19);
    EXPECT_LE(keys, 21);
    std::printf("[ measure  ] reference %d: %.1f record bytes per frame (keyframe %d)\n",
                static_cast<int>(ref), double(total) / 600.0, deltaKeyframeBytes(kJoints));
    EXPECT_LT(total / 600, static_cast<std::size_t>(deltaKeyframeBytes(kJoints)));
  }
}

TEST(PostureDelta, ExactWithoutToleranceAndForwardingIsBitExact) {
  PostureDeltaOptions options;
  options.joint_tolerance_rad = 0.0f;
  options.root_tolerance_m = 0.0f;
  PostureDeltaEncoder enc(options);
  PostureDeltaDecoder dec(kJoints);
  PostureDeltaEncoder forward_enc;  // the server's, per receiver
  PostureDeltaDecoder forward_dec(kJoints);
  Motion motion(5);
  std::vector<std::uint8_t> bytes, forwarded;
  PostureRecord got, got2, exact;
  for (int i = 0; i < 300; ++i) {
    const double t = i * kFrame;
    const Posture& p = motion.next(t);
    bytes.clear();
    ASSERT_TRUE(enc.encode(p, static_cast<std::uint16_t>(i + 100), t, false, bytes));
    ASSERT_TRUE(dec.decode(bytes, got).ok());
    // Without tolerance the frame is today's quantized record exactly.
    ASSERT_TRUE(encodePostureRecord(p, static_cast<std::uint16_t>(i + 100), t, exact));
    ASSERT_TRUE(sameRecord(got, exact)) << "frame " << i;
    enc.acknowledge(got.sequence);
    // Forwarded as a record: decoded the same by the next receiver.
    forwarded.clear();
    ASSERT_TRUE(forward_enc.encode(got, false, forwarded));
    ASSERT_TRUE(forward_dec.decode(forwarded, got2).ok());
    ASSERT_TRUE(sameRecord(got, got2)) << "frame " << i;
    if (i % 3 == 0) forward_enc.acknowledge(got2.sequence);
  }
}

// The byte example of .team/wire-posture-delta.md: a one-joint keyframe (the §3.3 example
// behind a flags byte) and a delta one frame later.
TEST(PostureDelta, ByteExample) {
  PostureDeltaOptions options;
  options.joint_count = 1;
  PostureDeltaEncoder enc(options);
  PostureRecord r;
  r.sequence = 0x0102;
  r.time = toWireTime(1.0);
  r.joint_count = 1;
  r.root_mm = {1, -1, 1000};
  r.rotations[0] = packQuat(glm::quat(1, 0, 0, 0));
  std::vector<std::uint8_t> key, delta;
  ASSERT_TRUE(enc.encode(r, false, key));
  r.sequence = 0x0103;
  r.time = toWireTime(1.0 + 1.0 / 60.0);
  r.root_mm = {2, -1, 1000};
  r.rotations[0] += 5u << 2;  // first component code 511 -> 516
  ASSERT_TRUE(enc.encode(r, false, delta));
  const auto hex = [](const std::vector<std::uint8_t>& b) {
    std::string s;
    char buf[4];
    for (std::uint8_t x : b) {
      std::snprintf(buf, sizeof buf, "%02X ", x);
      s += buf;
    }
    return s;
  };
  std::printf("[ example  ] keyframe %s\n[ example  ] delta    %s\n", hex(key).c_str(),
              hex(delta).c_str());
  EXPECT_EQ(hex(key), "01 02 01 10 27 00 00 01 01 00 FF FF E8 03 FF F7 DF 7F ");
  EXPECT_EQ(hex(delta), "02 03 01 E8 34 01 AA 00 00 ");
  PostureDeltaDecoder dec(1);
  PostureRecord got;
  ASSERT_TRUE(dec.decode(key, got).ok());
  ASSERT_TRUE(dec.decode(delta, got).ok());
  EXPECT_TRUE(sameRecord(got, r));
}

// A forwarder with one history per sender (its uplink decoder) and, per recipient, only a
// DeltaForwardState; recipients lose 10% and acknowledge what they decode.
TEST(PostureDelta, ForwardingFromOneSharedHistory) {
  PostureDeltaEncoder sender;
  PostureDeltaDecoder uplink(kJoints);
  struct Recipient {
    PostureDeltaDecoder dec{kJoints};
    DeltaForwardState state;
    int decoded = 0, keyframes = 0;
    std::size_t bytes = 0;
  };
  std::array<Recipient, 2> recipients;
  std::mt19937_64 rng(5);
  Motion motion(9);
  std::vector<std::uint8_t> bytes, down;
  PostureRecord got, scratch, received;
  for (int i = 0; i < 400; ++i) {
    bytes.clear();
    ASSERT_TRUE(sender.encode(motion.next(i * kFrame), static_cast<std::uint16_t>(i), i * kFrame,
                              false, bytes));
    ASSERT_TRUE(uplink.decode(bytes, got).ok());
    sender.acknowledge(got.sequence);
    if (i % 2 == 1) continue;  // forwarded at half the sender's rate
    for (Recipient& r : recipients) {
      down.clear();
      const std::size_t n = appendForwardedPosture(uplink, got, {}, r.state, scratch, down);
      ASSERT_EQ(n, down.size());
      r.bytes += n;
      r.keyframes += down[0] & 1;
      if (std::uniform_int_distribution<int>(0, 9)(rng) == 0) continue;  // lost
      const DeltaDecodeResult res = r.dec.decode(down, received);
      if (!res.ok()) {
        // Only a delta against a lost first keyframe, before any acknowledgement.
        EXPECT_EQ(res.status, DeltaStatus::kMissingReference);
        EXPECT_FALSE(r.state.have_ack);
        continue;
      }
      ASSERT_TRUE(sameRecord(received, got));
      ++r.decoded;
      r.state.acknowledge(res.sequence);
    }
  }
  for (const Recipient& r : recipients) {
    std::printf(
        "[ measure  ] forwarded 200 frames, 10%% lost: %d decoded, %d keyframes, %.1f B "
        "per record\n",
        r.decoded, r.keyframes, static_cast<double>(r.bytes) / 200.0);
    EXPECT_GT(r.decoded, 160);
    EXPECT_LE(r.keyframes, 20);  // the first, one per 0.5 s (6.7 s of frames), a few retries
    EXPECT_LT(r.bytes / 200, 150u);
  }
}

// A channel that loses, delays and reorders datagrams (both directions).
struct Channel {
  struct Item {
    int due;
    std::vector<std::uint8_t> bytes;
  };
  std::mt19937_64 rng;
  double loss;
  int max_delay;
  std::vector<Item> in_flight;
  int lost = 0;
  void send(int now, const std::vector<std::uint8_t>& b) {
    if (std::uniform_real_distribution<double>(0, 1)(rng) < loss) {
      ++lost;
      return;
    }
    in_flight.push_back({now + std::uniform_int_distribution<int>(0, max_delay)(rng), b});
  }
  // Delivers what is due, in random order.
  std::vector<std::vector<std::uint8_t>> receive(int now) {
    std::shuffle(in_flight.begin(), in_flight.end(), rng);
    std::vector<std::vector<std::uint8_t>> out;
    for (auto it = in_flight.begin(); it != in_flight.end();) {
      if (it->due <= now) {
        out.push_back(std::move(it->bytes));
        it = in_flight.erase(it);
      } else {
        ++it;
      }
    }
    return out;
  }
};

struct LossRun {
  int sent = 0, lost = 0, decoded = 0, refused = 0, malformed = 0, stale = 0;
};

LossRun runLossy(DeltaReference ref, std::uint64_t seed, std::uint16_t first_seq) {
  PostureDeltaOptions options;
  options.reference = ref;
  PostureDeltaEncoder enc(options);
  PostureDeltaDecoder dec(kJoints);
  Motion motion(seed);
  Channel up{std::mt19937_64(seed), 0.10, 3, {}};
  Channel acks{std::mt19937_64(seed + 1), 0.10, 3, {}};
  std::map<std::uint16_t, Posture> sent;
  std::map<std::uint16_t, PostureRecord> reconstructed;
  LossRun run;
  PostureRecord got;
  std::vector<std::uint8_t> bytes;
  for (int i = 0; i < 1200; ++i) {
    const double t = 100.0 + i * kFrame;
    const auto seq = static_cast<std::uint16_t>(first_seq + i);
    const Posture& p = motion.next(t);
    bytes.clear();
    if (!enc.encode(p, seq, t, false, bytes)) ADD_FAILURE() << "encode failed";
    sent[seq] = p;
    reconstructed[seq] = enc.lastReconstructed();
    up.send(i, bytes);
    ++run.sent;
    // The receiver decodes what arrives and acknowledges what it decoded.
    for (const auto& d : up.receive(i)) {
      const DeltaDecodeResult r = dec.decode(d, got);
      if (r.status == DeltaStatus::kMalformed) ++run.malformed;
      if (r.status == DeltaStatus::kMissingReference) ++run.refused;
      if (!r.ok()) continue;
      ++run.decoded;
      EXPECT_TRUE(sameRecord(got, reconstructed.at(r.sequence))) << "sequence " << r.sequence;
      expectWithinBound(got, sent.at(r.sequence));
      const std::vector<std::uint8_t> ack = {static_cast<std::uint8_t>(r.sequence & 0xFF),
                                             static_cast<std::uint8_t>(r.sequence >> 8)};
      acks.send(i, ack);
    }
    for (const auto& a : acks.receive(i)) {
      enc.acknowledge(static_cast<std::uint16_t>(a[0] | (a[1] << 8)));
    }
  }
  run.lost = up.lost;
  run.stale = static_cast<int>(up.in_flight.size());
  return run;
}

TEST(PostureDelta, LossyReorderingChannelDecodesWithinBoundOrRefuses) {
  for (DeltaReference ref : {DeltaReference::kAcked, DeltaReference::kKeyframe}) {
    const LossRun run = runLossy(ref, 11, 0);
    std::printf(
        "[ measure  ] reference %d, 10%% loss, reordering: %d sent, %d lost, %d decoded, %d "
        "refused (missing reference)\n",
        static_cast<int>(ref), run.sent, run.lost, run.decoded, run.refused);
    EXPECT_EQ(run.malformed, 0);
    EXPECT_EQ(run.decoded + run.refused + run.lost + run.stale, run.sent);
    EXPECT_GT(run.lost, 60);
    if (ref == DeltaReference::kAcked) {
      // Acknowledged references: a lost datagram costs only itself (refusals only before the
      // first acknowledgement arrives, when a delta names the first keyframe).
      EXPECT_LE(run.refused, 8);
    }
  }
}

TEST(PostureDelta, SequenceWrapAround) {
  const LossRun run = runLossy(DeltaReference::kAcked, 12, 65000);  // wraps after 536 frames
  EXPECT_EQ(run.malformed, 0);
  EXPECT_LE(run.refused, 8);
  EXPECT_GT(run.decoded, 1000);

  PostureDeltaEncoder enc;
  PostureDeltaDecoder dec(kJoints);
  Motion motion(4);
  std::vector<std::uint8_t> bytes;
  PostureRecord got;
  for (int i = 0; i < 200; ++i) {
    const auto seq = static_cast<std::uint16_t>(65436 + i);
    bytes.clear();
    DeltaFrameInfo info;
    ASSERT_TRUE(enc.encode(motion.next(i * kFrame), seq, i * kFrame, false, bytes, &info));
    const DeltaDecodeResult r = dec.decode(bytes, got);
    ASSERT_TRUE(r.ok()) << r.reason;
    EXPECT_EQ(r.sequence, seq);
    if (!info.keyframe) {
      EXPECT_EQ(r.reference, info.reference);
    }
    enc.acknowledge(seq);
  }
}

TEST(PostureDelta, LostKeyframeIsRefusedThenRecovered) {
  PostureDeltaOptions options;
  options.reference = DeltaReference::kKeyframe;
  PostureDeltaEncoder enc(options);
  PostureDeltaDecoder dec(kJoints);
  Motion motion(8);
  std::vector<std::uint8_t> bytes;
  PostureRecord got;
  DeltaFrameInfo info;
  // The first keyframe is lost: the deltas against it are refused, never decoded.
  ASSERT_TRUE(enc.encode(motion.next(0), 1, 0.0, false, bytes, &info));
  ASSERT_TRUE(info.keyframe);
  for (int i = 2; i < 6; ++i) {
    bytes.clear();
    ASSERT_TRUE(enc.encode(motion.next(i * kFrame), static_cast<std::uint16_t>(i), i * kFrame,
                           false, bytes, &info));
    ASSERT_FALSE(info.keyframe);
    const DeltaDecodeResult r = dec.decode(bytes, got);
    EXPECT_EQ(r.status, DeltaStatus::kMissingReference);
    EXPECT_EQ(r.reference, 1);
    EXPECT_STREQ(r.reason, "delta reference not held");
  }
  // The receiver asks for a keyframe: it and the deltas after it decode.
  enc.requestKeyframe();
  for (int i = 6; i < 12; ++i) {
    bytes.clear();
    ASSERT_TRUE(enc.encode(motion.next(i * kFrame), static_cast<std::uint16_t>(i), i * kFrame,
                           false, bytes, &info));
    EXPECT_EQ(info.keyframe, i == 6);
    ASSERT_TRUE(dec.decode(bytes, got).ok());
    ASSERT_TRUE(sameRecord(got, enc.lastReconstructed()));
  }
  // Forced keyframes on demand.
  bytes.clear();
  ASSERT_TRUE(enc.encode(motion.next(1.0), 12, 1.0, true, bytes, &info));
  EXPECT_TRUE(info.keyframe);
  EXPECT_EQ(bytes.size(), static_cast<std::size_t>(deltaKeyframeBytes(kJoints)));
}

// A sender that starts over (a new encoder, sequences from 0) is followed from its first
// keyframe, even though the decoder has seen much newer sequences.
TEST(PostureDelta, RestartedSenderIsFollowed) {
  PostureDeltaDecoder dec(kJoints);
  Motion motion(2);
  std::vector<std::uint8_t> bytes;
  PostureRecord got;
  for (int pass = 0; pass < 3; ++pass) {
    PostureDeltaEncoder enc;
    const int first = pass == 0 ? 5000 : pass == 1 ? 0 : 30;  // 30: only 70 behind the newest
    for (int i = first; i < first + 100; ++i) {
      bytes.clear();
      ASSERT_TRUE(enc.encode(motion.next(i * kFrame), static_cast<std::uint16_t>(i), i * kFrame,
                             false, bytes));
      const DeltaDecodeResult r = dec.decode(bytes, got);
      ASSERT_TRUE(r.ok()) << r.reason << " pass " << pass << " frame " << i;
      ASSERT_TRUE(sameRecord(got, enc.lastReconstructed()));
      enc.acknowledge(r.sequence);
    }
  }
}

// Acknowledged references: an unacknowledged keyframe is sent again after key_retry_s, so a
// lost first keyframe costs 0.2 s, not a whole key interval.
TEST(PostureDelta, UnacknowledgedKeyframeIsRetried) {
  PostureDeltaEncoder enc;  // kAcked, key_retry_s 0.2, key_interval_s 0.5
  Motion motion(6);
  std::vector<std::uint8_t> bytes;
  std::vector<int> keys;
  for (int i = 0; i < 30; ++i) {
    bytes.clear();
    DeltaFrameInfo info;
    ASSERT_TRUE(enc.encode(motion.next(i * kFrame), static_cast<std::uint16_t>(i), i * kFrame,
                           false, bytes, &info));
    if (info.keyframe) keys.push_back(i);
  }
  // No acknowledgement ever: a keyframe at 0, then one each 0.2 s (12 frames).
  EXPECT_EQ(keys, (std::vector<int>{0, 12, 24}));
}

TEST(PostureDelta, WrongJointCountIsRefused) {
  PostureDeltaEncoder enc;
  Posture p;
  p.rotations.assign(51, glm::quat(1, 0, 0, 0));
  std::vector<std::uint8_t> bytes;
  EXPECT_FALSE(enc.encode(p, 1, 0.0, false, bytes));
  EXPECT_TRUE(bytes.empty());
  // A keyframe of another avatar.
  PostureDeltaOptions o;
  o.joint_count = 25;
  PostureDeltaEncoder enc25(o);
  p.rotations.assign(25, glm::quat(1, 0, 0, 0));
  ASSERT_TRUE(enc25.encode(p, 1, 0.0, false, bytes));
  PostureDeltaDecoder dec(kJoints);
  PostureRecord got;
  const DeltaDecodeResult r = dec.decode(bytes, got);
  EXPECT_EQ(r.status, DeltaStatus::kMalformed);
  EXPECT_STREQ(r.reason, "keyframe joint count is not the avatar's");
}

// A short stream of valid records (keyframe first), each decodable after the ones before it.
std::vector<std::vector<std::uint8_t>> validStream(int frames) {
  PostureDeltaEncoder enc;
  Motion motion(21);
  std::vector<std::vector<std::uint8_t>> out;
  for (int i = 0; i < frames; ++i) {
    std::vector<std::uint8_t> b;
    EXPECT_TRUE(
        enc.encode(motion.next(i * kFrame), static_cast<std::uint16_t>(i), i * kFrame, false, b));
    enc.acknowledge(static_cast<std::uint16_t>(i));
    out.push_back(std::move(b));
  }
  return out;
}

TEST(PostureDelta, EveryPrefixAndAppendedByteIsRejected) {
  const auto stream = validStream(12);
  PostureRecord got;
  for (std::size_t f = 0; f < stream.size(); ++f) {
    // A decoder holding the frames before f.
    PostureDeltaDecoder dec(kJoints);
    for (std::size_t g = 0; g < f; ++g) ASSERT_TRUE(dec.decode(stream[g], got).ok());
    const auto& b = stream[f];
    for (std::size_t len = 0; len < b.size(); ++len) {
      const DeltaDecodeResult r = dec.decode(std::span(b.data(), len), got);
      EXPECT_EQ(r.status, DeltaStatus::kMalformed) << "frame " << f << " prefix " << len;
      EXPECT_STRNE(r.reason, "");
    }
    std::vector<std::uint8_t> longer = b;
    longer.push_back(0);
    EXPECT_EQ(dec.decode(longer, got).status, DeltaStatus::kMalformed);
    ASSERT_TRUE(dec.decode(b, got).ok());
  }
}

TEST(PostureDelta, BadHeadsAreRejectedWithReasons) {
  const auto stream = validStream(3);
  PostureDeltaDecoder dec(kJoints);
  PostureRecord got;
  ASSERT_TRUE(dec.decode(stream[0], got).ok());
  std::vector<std::uint8_t> b = stream[0];
  b[0] = 0x03;  // keyframe with a reserved bit
  EXPECT_STREQ(dec.decode(b, got).reason, "keyframe flags: reserved bits 1-7 set");
  b = stream[1];
  b[0] = 0x00;  // distance 0
  EXPECT_STREQ(dec.decode(b, got).reason, "delta distance outside 1..63");
  b[0] = 64 << 1;
  EXPECT_STREQ(dec.decode(b, got).reason, "delta distance outside 1..63");
  std::vector<std::uint8_t> huge(2000, 0);
  EXPECT_STREQ(dec.decode(huge, got).reason, "record longer than a datagram allows");
}

// Fuzz-style: random buffers, random heads on valid bodies, bit flips and truncations of valid
// records, against a decoder holding references. No crash, no UB (run under ASan/UBSan); any
// accepted frame has the avatar's joint count and its root within range.
TEST(PostureDelta, HostileBytesNeverCrash) {
  const auto stream = validStream(40);
  // Fixed inputs by default; with --gtest_shuffle, seeded from gtest's random seed, so that a
  // longer run is --gtest_filter=*HostileBytes* --gtest_repeat=N --gtest_shuffle (a failure
  // names its seed; rerun with --gtest_random_seed=SEED).
  const std::uint64_t seed =
      GTEST_FLAG_GET(shuffle) ? ::testing::UnitTest::GetInstance()->random_seed() : 0;
  std::mt19937_64 rng(99 + seed);
  PostureRecord got;
  PostureDeltaDecoder dec(kJoints);
  for (const auto& b : stream) ASSERT_TRUE(dec.decode(b, got).ok());
  std::uniform_int_distribution<int> byte(0, 255);
  int accepted = 0, refused = 0, malformed = 0;
  const auto check = [&](std::span<const std::uint8_t> bytes) {
    const DeltaDecodeResult r = dec.decode(bytes, got);
    if (r.ok()) {
      ++accepted;
      EXPECT_EQ(got.joint_count, kJoints);
      for (std::int16_t c : got.root_mm) EXPECT_GE(c, -32767);
    } else if (r.status == DeltaStatus::kMissingReference) {
      ++refused;
    } else {
      ++malformed;
      EXPECT_STRNE(r.reason, "");
    }
  };
  std::vector<std::uint8_t> buf;
  for (int i = 0; i < 20000; ++i) {
    if (i % 64 == 0) {  // fresh references now and then (accepted garbage moves the window)
      dec.reset();
      for (const auto& b : stream) ASSERT_TRUE(dec.decode(b, got).ok());
    }
    const int kind = i % 4;
    if (kind == 0) {  // random bytes, random length
      buf.resize(static_cast<std::size_t>(std::uniform_int_distribution<int>(0, 300)(rng)));
      for (auto& x : buf) x = static_cast<std::uint8_t>(byte(rng));
    } else {  // a valid record, mutated
      buf = stream[static_cast<std::size_t>(i) % stream.size()];
      if (kind == 1) {
        const int flips = std::uniform_int_distribution<int>(1, 8)(rng);
        for (int k = 0; k < flips; ++k) {
          const std::size_t bit =
              std::uniform_int_distribution<std::size_t>(0, buf.size() * 8 - 1)(rng);
          buf[bit / 8] ^= static_cast<std::uint8_t>(1u << (bit % 8));
        }
      } else if (kind == 2) {
        buf.resize(std::uniform_int_distribution<std::size_t>(0, buf.size())(rng));
      } else {
        buf[0] = static_cast<std::uint8_t>(byte(rng));  // another distance or flags
        if (buf.size() > 3) buf[3] = static_cast<std::uint8_t>(byte(rng));
      }
    }
    check(buf);
  }
  std::printf("[ measure  ] hostile (seed %llu): %d accepted, %d refused, %d malformed of 20000\n",
              static_cast<unsigned long long>(seed), accepted, refused, malformed);
  EXPECT_GT(malformed, 10000);
}

}  // namespace
}  // namespace vistel::wire
