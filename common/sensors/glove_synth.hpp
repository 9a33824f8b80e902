// Synthetic glove streams for the simulator and the emulators: hand shapes a CyberGlove
// would report, as joint angles (radians, GloveSensor order; 0 = straight fingers, the
// calibration posture's hand).
#pragma once

#include <array>
#include <cstdint>
#include <optional>
#include <string_view>

#include "common/sensors/sensor_frame.hpp"

namespace vistel {

enum class GlovePattern : std::uint8_t {
  kNeutral,  // relaxed, straight fingers
  kGrasp,    // closing and opening a fist, one cycle per period
  kPoint,    // index straight, the other fingers curled, thumb over them
  kSpread,   // fingers straight and spread apart
  kCycle,    // grasp, point, spread in turn, one per period, with smooth transitions
};

std::string_view glovePatternName(GlovePattern pattern);
std::optional<GlovePattern> parseGlovePattern(std::string_view name);

// Angles of a pattern at time t (seconds); the wrist angles (pitch, yaw) are left at 0.
void syntheticGlove(GlovePattern pattern, double t, double period_s,
                    std::array<float, kGloveSensorCount>& angles);

}  // namespace vistel
