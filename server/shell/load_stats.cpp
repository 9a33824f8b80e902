#include "server/shell/load_stats.hpp"

#include <algorithm>
#include <ctime>

#include <fmt/format.h>

namespace vistel::server {

double LoadStats::processCpuSeconds() {
  timespec ts{};
  if (clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &ts) != 0) return 0.0;
  return static_cast<double>(ts.tv_sec) + 1e-9 * static_cast<double>(ts.tv_nsec);
}

LoadStats::LoadStats() : interval_cpu_(processCpuSeconds()), cpu_at_start_(interval_cpu_) {}

void LoadStats::add(Interval& interval, double seconds, int members) {
  const int bin = std::clamp(static_cast<int>(seconds * 1e5), 0, kBins - 1);
  ++interval.bins[static_cast<std::size_t>(bin)];
  ++interval.ticks;
  interval.member_ticks += static_cast<std::uint64_t>(std::max(0, members));
  interval.max_s = std::max(interval.max_s, seconds);
}

void LoadStats::addTick(double seconds, int members) {
  tick_histogram_.observe(seconds);
  ticks_.fetch_add(1, std::memory_order_relaxed);
  std::lock_guard lock(mutex_);
  add(total_, seconds, members);
  add(interval_, seconds, members);
}

void LoadStats::setPopulation(int rooms, int members) {
  std::lock_guard lock(mutex_);
  rooms_ = rooms;
  members_ = members;
  rooms_peak_ = std::max(rooms_peak_, rooms);
  members_peak_ = std::max(members_peak_, members);
}

TickPercentiles LoadStats::percentiles(const Interval& interval) {
  TickPercentiles p;
  p.ticks = interval.ticks;
  p.max_ms = interval.max_s * 1e3;
  if (interval.ticks == 0) return p;
  // The upper edge of the bin holding the q-quantile.
  const auto quantile = [&](double q) {
    const auto rank = static_cast<std::uint64_t>(q * static_cast<double>(interval.ticks - 1));
    std::uint64_t seen = 0;
    for (int b = 0; b < kBins; ++b) {
      seen += interval.bins[static_cast<std::size_t>(b)];
      if (seen > rank) return std::min(p.max_ms, 0.01 * (b + 1));
    }
    return p.max_ms;
  };
  p.p50_ms = quantile(0.50);
  p.p99_ms = quantile(0.99);
  return p;
}

std::string LoadStats::report(double now) {
  std::lock_guard lock(mutex_);
  const double cpu = processCpuSeconds();
  const double span = std::max(1e-9, now - interval_start_);
  const TickPercentiles p = percentiles(interval_);
  const std::uint64_t sent = datagrams_sent_.load(std::memory_order_relaxed);
  const std::uint64_t bytes = bytes_sent_.load(std::memory_order_relaxed);
  const double cpu_us =
      interval_.member_ticks == 0
          ? 0.0
          : 1e6 * (cpu - interval_cpu_) / static_cast<double>(interval_.member_ticks);
  std::string line = fmt::format(
      "load: {} rooms, {} members; {} ticks, tick p50 {:.2f} ms p99 {:.2f} ms max {:.2f} ms; "
      "{:.1f} us CPU per member-tick ({:.0f}% of a core); {:.0f} datagrams/s, {:.2f} MB/s out",
      rooms_, members_, p.ticks, p.p50_ms, p.p99_ms, p.max_ms, cpu_us,
      100.0 * (cpu - interval_cpu_) / span, static_cast<double>(sent - interval_sent_) / span,
      static_cast<double>(bytes - interval_bytes_sent_) / span / 1e6);
  interval_ = Interval{};
  interval_start_ = now;
  interval_cpu_ = cpu;
  interval_sent_ = sent;
  interval_bytes_sent_ = bytes;
  return line;
}

void LoadStats::fillMetrics(MetricsSnapshot& out) const {
  out.ticks_total = ticks_.load(std::memory_order_relaxed);
  out.tick_seconds = tick_histogram_.snapshot();
  out.bytes_in_udp = bytes_received_.load(std::memory_order_relaxed);
  out.bytes_out_udp = bytes_sent_.load(std::memory_order_relaxed);
  out.datagrams_in_total = datagrams_received_.load(std::memory_order_relaxed);
  out.datagrams_out_total = datagrams_sent_.load(std::memory_order_relaxed);
  out.datagrams_dropped = datagram_drops_.byReason();
}

std::string LoadStats::totalsJson(double now) const {
  std::lock_guard lock(mutex_);
  const TickPercentiles p = percentiles(total_);
  const double cpu = processCpuSeconds() - cpu_at_start_;
  const double cpu_us =
      total_.member_ticks == 0 ? 0.0 : 1e6 * cpu / static_cast<double>(total_.member_ticks);
  return fmt::format(
      "{{\"uptime_s\": {:.3f}, \"rooms_peak\": {}, \"members_peak\": {}, \"ticks\": {}, "
      "\"member_ticks\": {}, \"tick_ms\": {{\"p50\": {:.3f}, \"p99\": {:.3f}, \"max\": {:.3f}}}, "
      "\"cpu_s\": {:.3f}, \"cpu_us_per_member_tick\": {:.3f}, \"datagrams_sent\": {}, "
      "\"bytes_sent\": {}, \"send_failures\": {}, \"datagrams_received\": {}, "
      "\"bytes_received\": {}}}",
      now, rooms_peak_, members_peak_, p.ticks, total_.member_ticks, p.p50_ms, p.p99_ms, p.max_ms,
      cpu, cpu_us, datagrams_sent_.load(), bytes_sent_.load(), send_failures_.load(),
      datagrams_received_.load(), bytes_received_.load());
}

}  // namespace vistel::server
