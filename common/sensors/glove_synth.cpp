#include "common/sensors/glove_synth.hpp"

#include <algorithm>
#include <cmath>

#include <glm/glm.hpp>

namespace vistel {
namespace {

using Angles = std::array<float, kGloveSensorCount>;

Angles fist() {
  Angles a{};
  const float mpj = glm::radians(75.0f), pij = glm::radians(95.0f), dij = glm::radians(60.0f);
  for (int base : {kIndexMpj, kMiddleMpj, kRingMpj, kPinkyMpj}) {
    a[base] = mpj;
    a[base + 1] = pij;
    a[base + 2] = dij;
  }
  a[kThumbRotation] = glm::radians(25.0f);
  a[kThumbMpj] = glm::radians(35.0f);
  a[kThumbIj] = glm::radians(45.0f);
  a[kThumbAbduction] = glm::radians(10.0f);
  a[kPalmArch] = glm::radians(10.0f);
  return a;
}

Angles point() {
  Angles a = fist();
  a[kIndexMpj] = a[kIndexPij] = a[kIndexDij] = 0.0f;
  a[kMiddleIndexAbduction] = glm::radians(8.0f);
  return a;
}

Angles spread() {
  Angles a{};
  a[kMiddleIndexAbduction] = glm::radians(15.0f);
  a[kRingMiddleAbduction] = glm::radians(12.0f);
  a[kPinkyRingAbduction] = glm::radians(15.0f);
  a[kThumbAbduction] = glm::radians(40.0f);
  return a;
}

void mixInto(const Angles& a, const Angles& b, float t, Angles& out) {
  for (int i = 0; i < kGloveSensorCount; ++i) out[i] = a[i] + (b[i] - a[i]) * t;
}

float smooth(float t) { return t * t * (3.0f - 2.0f * t); }

}  // namespace

std::string_view glovePatternName(GlovePattern p) {
  switch (p) {
    case GlovePattern::kNeutral:
      return "neutral";
    case GlovePattern::kGrasp:
      return "grasp";
    case GlovePattern::kPoint:
      return "point";
    case GlovePattern::kSpread:
      return "spread";
    case GlovePattern::kCycle:
      return "cycle";
  }
  return "neutral";
}

std::optional<GlovePattern> parseGlovePattern(std::string_view name) {
  for (GlovePattern p : {GlovePattern::kNeutral, GlovePattern::kGrasp, GlovePattern::kPoint,
                         GlovePattern::kSpread, GlovePattern::kCycle}) {
    if (glovePatternName(p) == name) return p;
  }
  return std::nullopt;
}

void syntheticGlove(GlovePattern pattern, double t, double period_s, Angles& angles) {
  static const Angles kZero{};
  static const Angles kFist = fist();
  static const Angles kPointShape = point();
  static const Angles kSpreadShape = spread();
  const double period = period_s > 1e-3 ? period_s : 1.0;
  switch (pattern) {
    case GlovePattern::kNeutral:
      angles = kZero;
      return;
    case GlovePattern::kPoint:
      angles = kPointShape;
      return;
    case GlovePattern::kSpread:
      angles = kSpreadShape;
      return;
    case GlovePattern::kGrasp: {
      const float phase = static_cast<float>(0.5 - 0.5 * std::cos(6.283185307179586 * t / period));
      mixInto(kZero, kFist, phase, angles);
      return;
    }
    case GlovePattern::kCycle: {
      const Angles* shapes[3] = {&kFist, &kPointShape, &kSpreadShape};
      const double u = std::max(0.0, t) / period;
      const int k = static_cast<int>(std::floor(u)) % 3;
      const float f = static_cast<float>(u - std::floor(u));
      // Hold for the first 70 % of each period, then blend into the next shape.
      const float blend = f < 0.7f ? 0.0f : smooth((f - 0.7f) / 0.3f);
      mixInto(*shapes[k], *shapes[(k + 1) % 3], blend, angles);
      return;
    }
  }
  angles = kZero;
}

}  // namespace vistel
