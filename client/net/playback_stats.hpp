// What the viewer was shown of the remote members (the --stats-json "playback" object of
// vistel-client and of each vistel-bot participant): per shown frame of each remote
// member, whether its posture was interpolated, held or extrapolated
// (JitterBuffer::Shown), and the shown posture's age — server now minus the capture time
// of what is shown (JitterBuffer::sampleShown; the synchronised clock), so an
// interpolated frame is as old as the playback delay and a held or extrapolated one
// grows older until data arrives.
//
// Ages go into a histogram of 2%-wide bins from 1 ms to about 100 s (everything below
// 1 ms in the first bin, above in the last): percentiles to 2%, exact mean and max, 2.3 KiB
// per histogram, no allocation per frame (a member's first frame adds its entry).
#pragma once

#include <array>
#include <cstdint>
#include <map>
#include <string>

#include "client/net/jitter_buffer.hpp"
#include "client/net/motion_jerk.hpp"

namespace vistel::net {

class AgeHistogram {
 public:
  static constexpr std::size_t kBins = 582;

  void add(double ms);
  std::uint64_t count() const { return count_; }
  double mean() const { return count_ > 0 ? sum_ / static_cast<double>(count_) : 0.0; }
  double max() const { return max_; }
  // The p-th percentile, ms (p in [0, 100]); 0 without samples.
  double percentile(double p) const;
  void merge(const AgeHistogram& other);

 private:
  std::array<std::uint32_t, kBins> bins_{};
  std::uint64_t count_ = 0;
  double sum_ = 0.0;
  double max_ = 0.0;
};

// One remote member's frames, or all of them together.
struct ShownFigures {
  std::uint64_t interpolated = 0;
  std::uint64_t held = 0;
  std::uint64_t extrapolated = 0;
  AgeHistogram age_ms;
  // Jitter (issue 21): the jerk of the joint positions drawn (at the playback times) and of
  // those the member sent (at their capture times); drawn / sent near 1 when the viewer's
  // interpolation and extrapolation add none of their own.
  MotionJerk drawn_jerk;
  MotionJerk sent_jerk;
  std::uint64_t frames() const { return interpolated + held + extrapolated; }
  void add(JitterBuffer::Shown kind, double age_s);
  void merge(const ShownFigures& other);
};

class PlaybackStats {
 public:
  // A shown frame of a member (kNone is not counted): into its figures and the total.
  void add(const std::string& member, JitterBuffer::Shown kind, double age_s);
  // A member's joint positions (model space, metres) as drawn at playback time t, and as it
  // sent them (captured at t): into its jerk streams, and the values into the total.
  void addDrawn(const std::string& member, double t, std::span<const glm::vec3> joints);
  void addSent(const std::string& member, double t, std::span<const glm::vec3> joints);
  // Into the total only (callers that keep no per-member figures, e.g. bots).
  void add(JitterBuffer::Shown kind, double age_s) { total_.add(kind, age_s); }
  void merge(const PlaybackStats& other);

  const ShownFigures& total() const { return total_; }
  const std::map<std::string, ShownFigures>& members() const { return members_; }

 private:
  ShownFigures& member(const std::string& name);  // its figures (added on first use)

  ShownFigures total_;
  std::map<std::string, ShownFigures> members_;  // by member name
};

// {"frames": n, "interpolated": n, "held": n, "extrapolated": n,
//  "age_ms": {"p50": f, "p99": f, "mean": f, "max": f},
//  "jerk": {"drawn": f, "sent": f, "ratio": f},   (m/s^3; only where both were measured)
//  "members": {"<name>": {the same without "members"}}}   ("members" only when kept)
std::string playbackJson(const PlaybackStats& stats);
// One line for logs: "1234 frames: 98.1% interpolated, 12 held, 9 extrapolated; age p50
// 100.2 ms, p99 131.0 ms".
std::string playbackSummary(const ShownFigures& figures);

}  // namespace vistel::net
