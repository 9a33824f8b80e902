#include "common/wire/posture_codec.hpp"

#include <algorithm>
#include <cmath>

namespace vistel::wire {
namespace {

constexpr float kHalfRange = 0.70710678118f;  // 1/sqrt(2): bound of the three smallest
constexpr std::uint32_t kComponentMask = (1u << kQuatComponentBits) - 1u;
// Codes 0..1022 span [-1/sqrt2, 1/sqrt2], so that 0 is code 511 exactly (rest rotations
// travel without error); code 1023 is never written and decodes just past the range.
constexpr float kComponentSteps = static_cast<float>(kComponentMask - 1u);

std::uint32_t quantizeComponent(float c) {
  const float t = (c + kHalfRange) / (2.0f * kHalfRange) * kComponentSteps;
  return static_cast<std::uint32_t>(std::round(std::clamp(t, 0.0f, kComponentSteps)));
}

float dequantizeComponent(std::uint32_t v) {
  return static_cast<float>(v) / kComponentSteps * (2.0f * kHalfRange) - kHalfRange;
}

std::int16_t quantizeRoot(float metres) {
  if (!std::isfinite(metres)) return 0;
  const float units = std::round(metres / kRootUnit);
  return static_cast<std::int16_t>(std::clamp(units, -32767.0f, 32767.0f));
}

}  // namespace

std::uint32_t packQuat(const glm::quat& q_in) {
  // Normalize (or fall back to the identity), in x, y, z, w order.
  float c[4] = {q_in.x, q_in.y, q_in.z, q_in.w};
  const float norm = std::sqrt(c[0] * c[0] + c[1] * c[1] + c[2] * c[2] + c[3] * c[3]);
  if (!std::isfinite(norm) || norm < 1e-12f) {
    c[0] = c[1] = c[2] = 0.0f;
    c[3] = 1.0f;
  } else {
    for (float& v : c) v /= norm;
  }

  // Drop the largest-magnitude component, made positive.
  int largest = 0;
  for (int i = 1; i < 4; ++i) {
    if (std::fabs(c[i]) > std::fabs(c[largest])) largest = i;
  }
  const float sign = c[largest] < 0.0f ? -1.0f : 1.0f;

  // Index in bits 0-1, the other three in order above it.
  std::uint32_t packed = static_cast<std::uint32_t>(largest);
  int shift = 2;
  for (int i = 0; i < 4; ++i) {
    if (i == largest) continue;
    packed |= quantizeComponent(sign * c[i]) << shift;
    shift += kQuatComponentBits;
  }
  return packed;
}

glm::quat unpackQuat(std::uint32_t packed) {
  // The three sent components, then the dropped one from the unit norm.
  const int largest = static_cast<int>(packed & 3u);
  float c[4] = {0.0f, 0.0f, 0.0f, 0.0f};
  int shift = 2;
  float sum = 0.0f;
  for (int i = 0; i < 4; ++i) {
    if (i == largest) continue;
    c[i] = dequantizeComponent((packed >> shift) & kComponentMask);
    sum += c[i] * c[i];
    shift += kQuatComponentBits;
  }
  c[largest] = std::sqrt(std::max(0.0f, 1.0f - sum));

  // Renormalize (an adversarial value may have a^2 + b^2 + c^2 > 1).
  const float norm = std::sqrt(c[0] * c[0] + c[1] * c[1] + c[2] * c[2] + c[3] * c[3]);
  return glm::quat(c[3] / norm, c[0] / norm, c[1] / norm, c[2] / norm);
}

// Tick counts this far from zero (thousands of years of 0.1 ms ticks) are not times a session
// can hold; they come only from corrupt or hostile input.
constexpr double kMaxTickMagnitude = 4503599627370496.0;  // 2^52

std::uint32_t toWireTime(double seconds) {
  const double ticks = std::round(seconds / kWireTimeTick);
  if (!(std::abs(ticks) <= kMaxTickMagnitude)) return 0;  // also NaN and infinities
  // Reduce modulo 2^32 in double (exact for any tick count below 2^53).
  const double wrapped = ticks - std::floor(ticks / 4294967296.0) * 4294967296.0;
  return static_cast<std::uint32_t>(static_cast<std::uint64_t>(wrapped) & 0xFFFFFFFFull);
}

double fromWireTime(std::uint32_t ticks, double reference) {
  if (!(std::abs(std::round(reference / kWireTimeTick)) <= kMaxTickMagnitude)) reference = 0.0;
  const double ref_ticks = std::round(reference / kWireTimeTick);
  const auto delta = static_cast<std::int32_t>(toWireTime(reference) - ticks);
  return (ref_ticks - static_cast<double>(delta)) * kWireTimeTick;
}

bool encodePostureRecord(const Posture& posture, std::uint16_t sequence, double capture_time,
                         PostureRecord& out) {
  if (posture.rotations.size() > static_cast<std::size_t>(kMaxWireJoints)) return false;
  out.sequence = sequence;
  out.time = toWireTime(capture_time);
  for (int k = 0; k < 3; ++k) out.root_mm[k] = quantizeRoot(posture.root_translation[k]);
  out.joint_count = static_cast<std::uint8_t>(posture.rotations.size());
  for (std::size_t j = 0; j < posture.rotations.size(); ++j) {
    out.rotations[j] = packQuat(posture.rotations[j]);
  }
  return true;
}

void decodePostureRecord(const PostureRecord& record, double reference_time, Posture& out) {
  out.time = fromWireTime(record.time, reference_time);
  for (int k = 0; k < 3; ++k) {
    out.root_translation[k] = static_cast<float>(record.root_mm[k]) * kRootUnit;
  }
  out.rotations.resize(record.joint_count);
  for (std::size_t j = 0; j < out.rotations.size(); ++j) {
    out.rotations[j] = unpackQuat(record.rotations[j]);
  }
  out.translations.clear();
}

}  // namespace vistel::wire
