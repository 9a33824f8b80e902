// Sensor configuration files (config/sensors/*.toml): which devices a site uses and how —
// a FASTRAK-class tracker (serial or USB) or a HID tracker, CyberGlove-class gloves, where
// each sensor is worn, how the solver and calibration behave. Parsed once at start-up;
// errors name the file, the key and the reason. Glove files referenced by a setup are read
// through readConfigText (disk first, then the embedded copy).
#pragma once

#include <array>
#include <cstdint>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include <glm/glm.hpp>
#include <glm/gtc/quaternion.hpp>

#include "common/base/result.hpp"
#include "common/sensors/calibration.hpp"
#include "common/sensors/cyberglove_protocol.hpp"
#include "common/sensors/fastrak_protocol.hpp"
#include "common/sensors/posture_solver.hpp"
#include "common/sensors/rig_simulator.hpp"
#include "common/sensors/sensor_frame.hpp"
#include "common/sensors/sensor_mount.hpp"

namespace vistel {

// Where the device's axes sit in tracker space (+Y up, metres): p = rotation * p_device +
// position.
struct TransmitterPlacement {
  glm::quat rotation{1.0f, 0.0f, 0.0f, 0.0f};
  glm::vec3 position{0.0f};
};

struct UsbConfig {
  std::uint16_t vendor_id = 0;
  std::uint16_t product_id = 0;
  int interface_number = 0;
  std::uint8_t endpoint_out = 0x02;
  std::uint8_t endpoint_in = 0x82;
};

enum class TrackerTransport : std::uint8_t { kSerial, kUsb };

struct StationMapping {
  int station = 1;  // device station number, 1..4
  BodySite site = BodySite::kHead;
};

struct TrackerConfig {
  TrackerTransport transport = TrackerTransport::kSerial;
  std::string port = "/dev/ttyUSB0";
  int baud = 115200;
  UsbConfig usb;
  FastrakFormat format;
  bool continuous = true;  // else polled with 'P'
  std::vector<StationMapping> stations;
  TransmitterPlacement transmitter;
  double reply_timeout_s = 1.0;
  bool check_status = true;  // send 'S' at start-up and expect a status record
};

struct GloveDeviceConfig {
  Hand hand = Hand::kRight;
  std::string port = "/dev/ttyUSB1";
  int baud = 115200;
  GloveFormat format;
  bool stream = true;  // else polled with 'G'
  GloveCalibration calibration;
  double reply_timeout_s = 1.0;
};

// A HID device's input report, decoded by layout. Numbers are little-endian.
enum class HidValueType : std::uint8_t { kF32, kI16, kU8 };
struct HidStationLayout {
  BodySite site = BodySite::kHead;
  int position_offset = 0;  // byte offset of x, y, z in the report (report id included)
  HidValueType position_type = HidValueType::kF32;
  float position_scale = 1.0f;  // metres per unit
  int orientation_offset = 12;  // w, x, y, z
  HidValueType orientation_type = HidValueType::kF32;
  float orientation_scale = 1.0f;
  int valid_offset = -1;  // byte that is non-zero when the station is tracked (-1: always)
};
struct HidGloveLayout {
  Hand hand = Hand::kRight;
  int offset = 0;  // first raw sensor byte
  int sensor_count = 22;
  GloveCalibration calibration;
};
struct HidConfig {
  std::uint16_t vendor_id = 0;
  std::uint16_t product_id = 0;
  std::string serial;  // empty: the first matching device
  int report_id = -1;  // expected first byte, -1 when the device uses no report ids
  int report_size = 64;
  std::vector<HidStationLayout> stations;
  std::vector<HidGloveLayout> gloves;
  TransmitterPlacement transmitter;
};

// A force-feedback device (the [force_feedback] section): the own avatar's contact force per
// body part, sent as HID output reports (common/sensors/io/force_feedback.hpp). A report is
// report_size bytes as hid_write takes it: byte 0 is the report id (0 for a device that
// uses no report ids), the channels' values follow at their offsets, little-endian, every
// other byte 0.
enum class ForceComponent : std::uint8_t { kX, kY, kZ, kMagnitude };
struct ForceFeedbackChannel {
  std::string part;  // the avatar's primitive ("l_hand"); names the avatar lacks are warned
                     // about at start and send 0
  int offset = 1;    // byte offset in the report, >= 1 (byte 0 is the report id)
  HidValueType type = HidValueType::kU8;
  float scale = 1.0f;  // newtons per count (> 0): count = round(value / scale), clamped to
                       // the type's range (u8: 0..255, i16: -32768..32767); f32: newtons / scale
  ForceComponent component = ForceComponent::kMagnitude;  // a model-space axis (the avatar's
                                                          // +X left, +Y up, +Z forward) or |F|
};
struct ForceFeedbackConfig {
  bool enabled = false;  // the section is present
  std::uint16_t vendor_id = 0;
  std::uint16_t product_id = 0;
  std::string serial;         // empty: the first matching device
  int report_id = 0;          // byte 0 of every report (0..255)
  int report_size = 64;       // bytes, report id included (2..4096)
  double max_rate_hz = 60.0;  // reports per second at most (the client also caps it at its
                              // frame rate)
  std::vector<ForceFeedbackChannel> channels;  // non-overlapping, inside the report
};

enum class TrackerKind : std::uint8_t { kNone, kFastrak, kHid };

struct SensorSetup {
  std::string source;  // the file, for messages
  std::string participant;
  TrackerKind tracker_kind = TrackerKind::kNone;
  TrackerConfig tracker;
  HidConfig hid;
  std::vector<GloveDeviceConfig> gloves;
  std::array<SensorMount, kBodySiteCount> mounts = defaultSensorMounts();
  SolverOptions solver;
  CalibrationOptions calibration;
  SimOptions sim;                      // [sim] options, used by sim: sources
  ForceFeedbackConfig force_feedback;  // [force_feedback]: where contact forces go
  std::string text;                    // the file's text (recorded into .vrec headers)
};

Result<SensorSetup> parseSensorSetup(std::string_view toml_text, std::string_view source_name);
Result<SensorSetup> loadSensorSetup(const std::string& path);
Result<GloveDeviceConfig> parseGloveConfig(std::string_view toml_text,
                                           std::string_view source_name);

}  // namespace vistel
