// SensorFrame: one timestamped snapshot of a participant's sensors (DESIGN.md §5): four
// 6-DOF tracker stations (head, chest, both wrists), optionally two more on the feet (six
// sensors; a station nobody wears simply never becomes valid), and two data gloves.
//
// Space: tracker space, metres, right-handed, +Y up (a device's own axes are mapped into it
// by the driver's transmitter transform). A station's orientation takes vectors from the
// sensor's frame into tracker space. Glove angles are radians in the CyberGlove 22-sensor
// order (GloveSensor); 18-sensor gloves fill the four distal slots from the PIJ readings.
// Fixed size: copying a frame allocates nothing.
#pragma once

#include <array>
#include <cstdint>
#include <optional>
#include <string_view>

#include <glm/glm.hpp>
#include <glm/gtc/quaternion.hpp>

namespace vistel {

// Where a tracker station is worn. The first four are always worn; the feet (on the instep,
// anchored at the ankle joint) are optional.
enum class BodySite : std::uint8_t {
  kHead = 0,
  kChest = 1,
  kLeftWrist = 2,
  kRightWrist = 3,
  kLeftFoot = 4,
  kRightFoot = 5,
};
inline constexpr int kBodySiteCount = 6;
inline constexpr int kUpperBodySiteCount = 4;  // head, chest, wrists: the sites always worn
inline constexpr bool isFootSite(BodySite site) {
  return site == BodySite::kLeftFoot || site == BodySite::kRightFoot;
}
inline constexpr BodySite footSite(int side) {  // 0 left, 1 right
  return side == 0 ? BodySite::kLeftFoot : BodySite::kRightFoot;
}

// "head", "chest", "left_wrist", "right_wrist", "left_foot", "right_foot".
std::string_view bodySiteName(BodySite site);
std::optional<BodySite> parseBodySite(std::string_view name);

enum class Hand : std::uint8_t { kLeft = 0, kRight = 1 };
inline constexpr int kHandCount = 2;
std::string_view handName(Hand hand);  // "left", "right"
std::optional<Hand> parseHand(std::string_view name);

// Glove sensors, in the CyberGlove 22-sensor record order (PROTOCOLS.md §3).
enum GloveSensor : int {
  kThumbRotation = 0,
  kThumbMpj = 1,
  kThumbIj = 2,
  kThumbAbduction = 3,
  kIndexMpj = 4,
  kIndexPij = 5,
  kIndexDij = 6,
  kMiddleMpj = 7,
  kMiddlePij = 8,
  kMiddleDij = 9,
  kMiddleIndexAbduction = 10,
  kRingMpj = 11,
  kRingPij = 12,
  kRingDij = 13,
  kRingMiddleAbduction = 14,
  kPinkyMpj = 15,
  kPinkyPij = 16,
  kPinkyDij = 17,
  kPinkyRingAbduction = 18,
  kPalmArch = 19,
  kWristPitch = 20,
  kWristYaw = 21,
};
inline constexpr int kGloveSensorCount = 22;

struct StationReading {
  glm::vec3 position{0.0f};                       // tracker space, metres
  glm::quat orientation{1.0f, 0.0f, 0.0f, 0.0f};  // sensor frame -> tracker space, unit
  double time = 0.0;   // when the device measured it, seconds on the source's clock
  bool valid = false;  // false: no reading yet, or the station dropped out
  char status = ' ';   // the device's status character (' ' = OK, a letter = warning)
};

struct GloveReading {
  std::array<float, kGloveSensorCount> angles{};  // radians, GloveSensor order
  double time = 0.0;                              // seconds on the source's clock
  bool valid = false;
};

struct SensorFrame {
  double time = 0.0;           // when the newest reading in the frame arrived, seconds
  std::uint64_t sequence = 0;  // increments with every frame a source delivers
  std::array<StationReading, kBodySiteCount> stations{};  // indexed by BodySite
  std::array<GloveReading, kHandCount> gloves{};          // indexed by Hand

  StationReading& station(BodySite site) { return stations[static_cast<int>(site)]; }
  const StationReading& station(BodySite site) const { return stations[static_cast<int>(site)]; }
  GloveReading& glove(Hand hand) { return gloves[static_cast<int>(hand)]; }
  const GloveReading& glove(Hand hand) const { return gloves[static_cast<int>(hand)]; }
};

}  // namespace vistel
