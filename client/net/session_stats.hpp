// What a client measures about the stream it receives (the --stats-json numbers):
// distinct postures per sender and their rate, and end-to-end latency from the
// sender's capture time (server clock) to arrival here (local clock + measured offset).
#pragma once

#include <cstdint>
#include <map>
#include <string>
#include <vector>

namespace vistel::net {

struct MemberReceiveStats {
  std::uint64_t postures_received = 0;  // distinct postures (duplicates not counted)
  double first_arrival = 0.0;           // local clock, seconds
  double last_arrival = 0.0;
  // Arrivals per second between the first and the last (0 with fewer than two).
  double rateHz() const;
};

// Latency samples in a histogram (0.05 ms bins up to 2 s; beyond counts in the last):
// exact mean, percentiles to the bin width, constant memory.
class LatencyStats {
 public:
  LatencyStats();
  void add(double ms);
  std::uint64_t count() const { return count_; }
  double mean() const { return count_ > 0 ? sum_ / static_cast<double>(count_) : 0.0; }
  // The p-th percentile (p in [0, 100]), ms; 0 without samples.
  double percentile(double p) const;
  // Adds another's samples (the same bins), e.g. over a bot's participants.
  void merge(const LatencyStats& other);
  // The histogram: bin i counts samples in [i, i + 1) * binMs().
  const std::vector<std::uint32_t>& bins() const { return bins_; }
  static double binMs();

 private:
  std::vector<std::uint32_t> bins_;
  std::uint64_t count_ = 0;
  double sum_ = 0.0;
};

struct SessionStats {
  std::map<std::string, MemberReceiveStats> members;  // by member name
  LatencyStats latency;                               // over all remote postures
  std::uint64_t postures_sent = 0;
  std::uint64_t posture_bytes_sent = 0;  // UDP payload of the postures sent
  std::uint64_t snapshots_received = 0;
  std::uint64_t datagram_bytes_received = 0;  // UDP payload of every datagram from the server
  std::uint64_t datagrams_rejected = 0;       // malformed or unexpected datagrams from the server
  std::uint64_t reconnects = 0;               // lost sessions resumed (rejoined and live again)
  std::uint64_t udp_rehellos = 0;    // times the server's datagrams stopped and a hello got
                                     // an answer again (the UDP path re-verified)
  std::uint64_t udp_rebinds = 0;     // ... of which the server challenged a new address of ours
  std::uint64_t dents_sent = 0;      // Dents messages sent (own avatar, props it dented)
  std::uint64_t dents_received = 0;  // ... relayed by the server, well formed
  std::uint64_t dents_rejected = 0;  // ... malformed (ignored)
};

// The --stats-json document: {"members": {"<name>": {"postures_received": n,
// "rate_hz": f}}, "latency_ms": {"mean": f, "p50": f, "p99": f, "samples": n},
// "frames_rendered": n, "postures_sent": n, ..., "reconnects": n, "udp_rehellos": n,
// "udp_rebinds": n, "dents": {"sent": n, "received": n, "rejected": n}}.
std::string statsJson(const SessionStats& stats, int frames_rendered, double clock_offset_s,
                      double clock_round_trip_s);

}  // namespace vistel::net
