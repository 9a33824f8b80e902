// The server's own measure of its load (issue 19): how long each room tick's work takes
// (stepping the world and sending its datagrams), how many member-ticks it served, the
// datagrams and bytes it moved, and the process's CPU time, so that an operator sees the
// load in the log (LoadStats::report, every [session] stats_interval_s) and a benchmark
// reads it from `vistel-server --stats-json`.
//
// Thread-safe: rooms on several strands record ticks; counters are atomics, the tick
// histograms sit behind a mutex (one lock per tick). Tick times go into 10 µs bins up to
// 100 ms (longer ones in the last bin), so percentiles are exact to 10 µs.
#pragma once

#include <array>
#include <atomic>
#include <cstdint>
#include <mutex>
#include <optional>
#include <string>
#include <string_view>

#include "server/http/prometheus.hpp"
#include "server/shell/datagram_drops.hpp"

namespace vistel::server {

// Percentiles of a set of durations, milliseconds.
struct TickPercentiles {
  std::uint64_t ticks = 0;
  double p50_ms = 0.0;
  double p99_ms = 0.0;
  double max_ms = 0.0;
};

class LoadStats {
 public:
  LoadStats();

  // One room tick that took `seconds` of wall time for a room of `members`.
  void addTick(double seconds, int members);
  void addSent(std::size_t bytes) {
    datagrams_sent_.fetch_add(1, std::memory_order_relaxed);
    bytes_sent_.fetch_add(bytes, std::memory_order_relaxed);
  }
  void addSendFailure() { send_failures_.fetch_add(1, std::memory_order_relaxed); }
  void addReceived(std::size_t bytes) {
    datagrams_received_.fetch_add(1, std::memory_order_relaxed);
    bytes_received_.fetch_add(bytes, std::memory_order_relaxed);
  }
  // A datagram dropped for `reason` (a phrase of routeDatagram or Room), counted by class
  // (DatagramDrops); returns a summary line to log at info at most once per 10 s.
  std::optional<std::string> addDatagramDrop(std::string_view reason, double now) {
    return datagram_drops_.add(reason, now);
  }
  const DatagramDrops& datagramDrops() const { return datagram_drops_; }
  // The lobby's counts, sampled by whoever calls report().
  void setPopulation(int rooms, int members);

  // One log line about the time since the last report (then starts a new interval):
  // rooms, members, tick p50/p99, CPU per member-tick, datagrams and bytes per second.
  std::string report(double now);
  // Everything since the start, as one JSON object (see README "vistel-server").
  std::string totalsJson(double now) const;

  // Process CPU time (user + system), seconds.
  static double processCpuSeconds();

  // The totals a /metrics scrape reports (ticks, tick histogram, datagrams and bytes,
  // datagrams dropped by class).
  void fillMetrics(MetricsSnapshot& out) const;

 private:
  static constexpr int kBins = 10000;  // 10 µs each
  using Histogram = std::array<std::uint32_t, kBins>;
  struct Interval {
    Histogram bins{};
    std::uint64_t ticks = 0;
    std::uint64_t member_ticks = 0;
    double max_s = 0.0;
  };
  static TickPercentiles percentiles(const Interval& interval);
  static void add(Interval& interval, double seconds, int members);

  mutable std::mutex mutex_;
  Interval total_;
  Interval interval_;
  double interval_start_ = 0.0;
  double interval_cpu_ = 0.0;
  std::uint64_t interval_sent_ = 0;
  std::uint64_t interval_bytes_sent_ = 0;
  int rooms_ = 0;
  int members_ = 0;
  int rooms_peak_ = 0;
  int members_peak_ = 0;
  double cpu_at_start_ = 0.0;

  AtomicHistogram tick_histogram_{defaultTickBuckets()};
  std::atomic<std::uint64_t> ticks_{0};
  std::atomic<std::uint64_t> datagrams_sent_{0};
  std::atomic<std::uint64_t> bytes_sent_{0};
  std::atomic<std::uint64_t> send_failures_{0};
  std::atomic<std::uint64_t> datagrams_received_{0};
  std::atomic<std::uint64_t> bytes_received_{0};
  DatagramDrops datagram_drops_;
};

}  // namespace vistel::server
