// The posture record of the UDP stream (proto/WIRE.md §3.3): one participant's posture
// in one frame, quantized to a stated bit budget.
//
// Budget per record: 104 bits of header (sequence 16, capture time 32, joint count 8,
// root position 3 x 16) + 32 bits per joint (smallest-three quaternion: 2-bit index of
// the dropped largest component + 3 x 10-bit components) = 13 + 4 n bytes for n joints
// (221 bytes for the 52-joint humanoid). Precision: root position 1 mm within +-32.767 m
// (clamped beyond); rotations within 0.25 degrees (kQuatAngleBoundRad); capture time
// 0.1 ms, modulo 2^32 ticks (4.97 days), resolved against a nearby reference time.
//
// Two layers: PostureRecord holds the quantized values and serializes exactly (bytes ->
// record -> bytes is the identity); encodePostureRecord / decodePostureRecord convert
// between it and a Posture (the lossy step).
#pragma once

#include <array>
#include <cstdint>

#include <glm/glm.hpp>
#include <glm/gtc/quaternion.hpp>

#include "common/anim/posture.hpp"
#include "common/wire/bit_stream.hpp"

namespace vistel::wire {

inline constexpr int kQuatComponentBits = 10;
inline constexpr int kQuatBits = 2 + 3 * kQuatComponentBits;  // 32 bits per joint
inline constexpr int kMaxWireJoints = 255;                    // joint count is a u8
inline constexpr double kWireTimeTick = 1e-4;                 // seconds per time unit
inline constexpr float kRootUnit = 0.001f;                    // metres per root unit
inline constexpr int kPostureHeaderBytes = 13;                // before the rotations
// Stated bound on the rotation error of one joint after a round trip: 0.25 degrees of
// rotation angle (0.125 degrees between the quaternions on the unit sphere). The largest
// error measured over 200000 random rotations is 0.227 degrees; the identity is exact.
inline constexpr float kQuatAngleBoundRad = 0.25f * 3.14159265f / 180.0f;

// Bytes of one serialized record with n joints.
constexpr int postureRecordBytes(int joint_count) {
  return kPostureHeaderBytes + joint_count * kQuatBits / 8;
}

struct PostureRecord {
  std::uint16_t sequence = 0;             // per sender, +1 per posture, wraps (see below)
  std::uint32_t time = 0;                 // capture time, server clock, kWireTimeTick
                                          // units modulo 2^32
  std::array<std::int16_t, 3> root_mm{};  // root translation, model space, millimetres
  std::uint8_t joint_count = 0;           // n
  std::array<std::uint32_t, kMaxWireJoints> rotations{};  // packed quaternion per joint
                                                          // (first n used)
};

template <typename Stream>
bool serialize(Stream& s, PostureRecord& r) {
  if (!serializeU16(s, r.sequence)) return false;
  if (!serializeU32(s, r.time)) return false;
  if (!serializeU8(s, r.joint_count)) return false;
  for (std::int16_t& c : r.root_mm) {
    if (!serializeI16(s, c)) return false;
  }
  for (int j = 0; j < r.joint_count; ++j) {
    if (!s.bits(r.rotations[static_cast<std::size_t>(j)], kQuatBits)) return false;
  }
  return true;
}

// Smallest-three quaternion in 32 bits. Bits 0-1: index (x=0, y=1, z=2, w=3) of the
// largest-magnitude component, made positive by negating the quaternion (q and -q are
// one rotation); bits 2-11, 12-21, 22-31: the other three components in x, y, z, w
// order, each mapped from [-1/sqrt2, 1/sqrt2] to 0..1022 (rounded, clamped; 0 is 511
// exactly, so rest rotations travel without error; 1023 is never written). A non-unit
// input is normalized; a zero or non-finite one is sent as the identity.
std::uint32_t packQuat(const glm::quat& q);
// Any 32-bit value decodes to a unit quaternion (the dropped component is
// sqrt(max(0, 1 - a^2 - b^2 - c^2)), then normalized): nothing to reject.
glm::quat unpackQuat(std::uint32_t packed);

// Wire time of a server-clock time in seconds (modulo 2^32 ticks).
std::uint32_t toWireTime(double seconds);
// The time in seconds, among those with this wire value, nearest to `reference` (the
// receiver's idea of "now" on the same clock; exact within +-2.48 days of it).
double fromWireTime(std::uint32_t ticks, double reference);

// True when sequence a is newer than b under wrap-around (serial number arithmetic:
// a is ahead of b by 1..32767).
inline bool sequenceNewer(std::uint16_t a, std::uint16_t b) {
  return a != b && static_cast<std::uint16_t>(a - b) < 0x8000u;
}

// Quantizes a posture into a record: rotations.size() <= kMaxWireJoints (false
// otherwise, record untouched); translations are not sent; non-finite root components
// become 0. capture_time is seconds on the server clock.
bool encodePostureRecord(const Posture& posture, std::uint16_t sequence, double capture_time,
                         PostureRecord& out);
// The posture of a record (out resized to joint_count; translations cleared);
// out.time = fromWireTime(record.time, reference_time).
void decodePostureRecord(const PostureRecord& record, double reference_time, Posture& out);

}  // namespace vistel::wire
