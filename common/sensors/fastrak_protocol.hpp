// The Polhemus FASTRAK-class record format and command set (facts from
// ../shared/data/devices/PROTOCOLS.md §1; all code here is vistel's own).
//
// A data record is a 3-byte header ('0', station '1'..'4', status ' ' or a letter) followed
// by the items of the station's output list, in order. Binary items are little-endian
// float32; ASCII items are fixed 7-character fields per number (position and Euler angles
// verified; quaternions and direction cosines assumed to use the same width, [unverified]
// in PROTOCOLS.md). Positions arrive in inches (default) or centimetres.
#pragma once

#include <cstdint>
#include <optional>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include <glm/glm.hpp>
#include <glm/gtc/quaternion.hpp>

#include "common/base/result.hpp"

namespace vistel {

// Output-list item codes (the `O` command).
enum class FastrakItem : std::uint8_t {
  kSpace = 0,
  kCrLf = 1,
  kPosition = 2,
  kRelativePosition = 3,
  kEuler = 4,             // azimuth, elevation, roll, degrees
  kDirectionCosines = 5,  // 3 x 3: the sensor's x, y, z axes in device axes [unverified order]
  kQuaternion = 11,       // w, x, y, z
  kStylus = 16,           // a space then '0' or '1'
  kPosition16 = 18,       // 16-bit binary forms (14 significant bits, [unverified] sign)
  kEuler16 = 19,
  kQuaternion16 = 20,
};

enum class FastrakEncoding : std::uint8_t { kAscii, kBinary };
enum class LengthUnit : std::uint8_t { kInches, kCentimetres };

inline constexpr int kFastrakMaxStations = 4;

struct FastrakFormat {
  FastrakEncoding encoding = FastrakEncoding::kBinary;
  LengthUnit units = LengthUnit::kInches;
  // The output list, the same for every station (VRPN's standard list by default).
  std::vector<FastrakItem> items = {FastrakItem::kPosition, FastrakItem::kQuaternion,
                                    FastrakItem::kSpace};
};

// The item for a numeric code, or nothing for codes vistel does not decode.
std::optional<FastrakItem> fastrakItemFromCode(int code);

// Checks that the list is non-empty, has a position or an orientation item, and that every
// item exists in the encoding (the 16-bit items are binary only). The message says which.
Status validateFastrakFormat(const FastrakFormat& format);

// Bytes one item / one whole record (header included) takes in this encoding.
std::size_t fastrakItemSize(FastrakItem item, FastrakEncoding encoding);
std::size_t fastrakRecordSize(const FastrakFormat& format);

// One decoded data record. Positions are converted to metres but stay in the device's axes.
struct FastrakRecord {
  int station = 0;    // 1..4
  char status = ' ';  // ' ' or a letter (a weak-signal or other warning)
  bool has_position = false;
  glm::vec3 position{0.0f};  // metres, device axes
  bool has_relative = false;
  glm::vec3 relative{0.0f};  // metres, device axes
  bool has_orientation = false;
  glm::quat orientation{1.0f, 0.0f, 0.0f, 0.0f};  // sensor -> device axes (from quaternion,
                                                  // Euler angles or direction cosines)
  bool has_euler = false;
  glm::vec3 euler_deg{0.0f};  // azimuth (about Z), elevation (Y), roll (X); R = Rz Ry Rx
  int stylus = -1;            // 0/1, or -1 when the list has no stylus item
};

// Decodes one complete record (exactly fastrakRecordSize bytes). Returns false when the
// bytes are not a plausible record: bad header, a terminator item that does not match,
// unparsable ASCII, a non-finite or out-of-range value, a quaternion far from unit length.
bool decodeFastrakRecord(std::span<const std::uint8_t> bytes, const FastrakFormat& format,
                         FastrakRecord& out);

// Encodes a record (the emulators' half; fields absent from the list are ignored). The
// orientation items are written from `orientation` (Euler angles from `euler_deg` when the
// record has them, else derived from the quaternion).
void encodeFastrakRecord(const FastrakRecord& record, const FastrakFormat& format,
                         std::string& out);

// Rotation of Polhemus Euler angles (degrees): Rz(azimuth) * Ry(elevation) * Rx(roll).
glm::quat fastrakEulerToQuat(const glm::vec3& euler_deg);
glm::vec3 fastrakQuatToEuler(const glm::quat& q);

// ---- Commands ---------------------------------------------------------------------------

inline constexpr std::string_view kFastrakPoll = "P";
inline constexpr std::string_view kFastrakContinuousOn = "C";
inline constexpr std::string_view kFastrakContinuousOff = "c";
inline constexpr std::string_view kFastrakStatusRequest = "S";

// "O<station>,<code>,<code>...\r".
std::string fastrakOutputListCommand(int station, std::span<const FastrakItem> items);
// "l<station>,1\r" / "l<station>,0\r".
std::string fastrakStationEnableCommand(int station, bool enable);

// The initialisation sequence (after VRPN's tested recipe): stop continuous output, enable
// the given stations (1..4) and disable the others, set every enabled station's output
// list, units, encoding, and finally start continuous output when asked. The status
// request that checks the unit answers is sent separately by the driver.
std::vector<std::string> fastrakInitCommands(const FastrakFormat& format,
                                             std::span<const int> stations, bool continuous);

}  // namespace vistel
