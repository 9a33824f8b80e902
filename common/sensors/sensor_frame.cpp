#include "common/sensors/sensor_frame.hpp"

#include "common/sensors/sensor_source.hpp"

namespace vistel {
namespace {

constexpr std::array<std::string_view, kBodySiteCount> kSiteNames = {
    "head", "chest", "left_wrist", "right_wrist", "left_foot", "right_foot"};
constexpr std::array<std::string_view, kHandCount> kHandNames = {"left", "right"};

}  // namespace

std::string_view bodySiteName(BodySite site) { return kSiteNames[static_cast<int>(site)]; }

std::optional<BodySite> parseBodySite(std::string_view name) {
  for (int i = 0; i < kBodySiteCount; ++i) {
    if (kSiteNames[i] == name) return static_cast<BodySite>(i);
  }
  return std::nullopt;
}

std::string_view handName(Hand hand) { return kHandNames[static_cast<int>(hand)]; }

std::optional<Hand> parseHand(std::string_view name) {
  for (int i = 0; i < kHandCount; ++i) {
    if (kHandNames[i] == name) return static_cast<Hand>(i);
  }
  return std::nullopt;
}

const char* pollStatusName(PollStatus status) {
  switch (status) {
    case PollStatus::kFrame:
      return "frame";
    case PollStatus::kTimeout:
      return "timeout";
    case PollStatus::kEnd:
      return "end";
    case PollStatus::kUnplugged:
      return "unplugged";
    case PollStatus::kFailed:
      return "failed";
  }
  return "unknown";
}

}  // namespace vistel
