// What `vistel-bot --stats-json FILE` writes: per participant, how long its join took,
// how often it was refused and retried, what it sent and received; over all of them, the
// latency histogram (so that scripts/bench-room can merge several bot processes into
// exact room-wide percentiles).
//
//   {"participants": [{"name": s, "state": s, "error": s, "join_s": f (negative: never
//     live), "rejoins": n, "live_s": f, "postures_sent": n, "posture_bytes_sent": n,
//     "datagram_bytes_received": n, "snapshots_received": n, "postures_received": n,
//     "latency_ms": {"p50": f, "p99": f, "samples": n},
//     "playback": {"frames": n, "interpolated": n, "held": n, "extrapolated": n,
//                  "age_ms": {"p50": f, "p99": f, "mean": f, "max": f}}}, ...],
//    "latency_ms": {"p50": f, "p99": f, "mean": f, "samples": n},
//    "playback": {as a participant's, over all of them},
//    "latency_histogram": {"bin_ms": f, "bins": [[index, count], ...]}}   (non-empty bins)
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "client/net/playback_stats.hpp"
#include "client/net/session_stats.hpp"

namespace vistel::net {

struct ParticipantReport {
  std::string name;
  std::string state;  // sessionStateName at the end
  std::string error;  // why it closed, if it did
  double join_s = -1.0;
  int rejoins = 0;
  double live_s = 0.0;  // seconds from going live to the end
  SessionStats stats;
  PlaybackStats playback;  // the remote members as this participant would have shown them
};

std::string botReportJson(const std::vector<ParticipantReport>& participants);

}  // namespace vistel::net
