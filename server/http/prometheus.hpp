// Prometheus text exposition format, version 0.0.4 (what /metrics serves).
//
// A scrape is a list of metric families, each written as
//   # HELP <name> <help, with \ and newline escaped>
//   # TYPE <name> counter|gauge|histogram
//   <name>{<label>="<value, with \ " and newline escaped>",...} <value>
// Histograms become <name>_bucket{...,le="<bound>"} lines with cumulative counts (the
// last one le="+Inf", equal to the count), then <name>_sum and <name>_count.
//
// MetricsSnapshot is the server's own set of figures, filled by the server (the lead
// wires it) and turned into families by snapshotFamilies(). Everything here is pure:
// no sockets, no clocks, no locks except in AtomicHistogram.
#pragma once

#include <atomic>
#include <cstdint>
#include <map>
#include <memory>
#include <span>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

namespace vistel::server {

enum class MetricType { kCounter, kGauge, kHistogram };

// name="value" pairs, written in this order.
using MetricLabels = std::vector<std::pair<std::string, std::string>>;

// A histogram's state at one moment. bucket_counts[i] counts observations in
// (upper_bounds[i-1], upper_bounds[i]] (not cumulative); bucket_counts has one more entry
// than upper_bounds: the observations above the last bound (the +Inf bucket). Bounds are
// ascending and finite. count is the sum of bucket_counts; sum the sum of observations.
struct HistogramData {
  std::vector<double> upper_bounds;
  std::vector<std::uint64_t> bucket_counts;  // upper_bounds.size() + 1
  double sum = 0.0;
  std::uint64_t count = 0;
};

struct MetricSample {
  MetricLabels labels;
  double value = 0.0;       // counters and gauges
  HistogramData histogram;  // histograms
};

struct MetricFamily {
  std::string name;  // [a-zA-Z_:][a-zA-Z0-9_:]*; counters by convention end in _total
  std::string help;  // one line of prose (newlines are escaped)
  MetricType type = MetricType::kGauge;
  std::vector<MetricSample> samples;  // a family without samples is still written
};

// Writes families in order in the text format. Characters a metric or label name may not
// hold are replaced by '_' (names come from code, not from peers); label values and help
// are escaped, so any bytes are safe there. A histogram whose bucket_counts does not have
// upper_bounds.size() + 1 entries is written from what is there, with the +Inf bucket
// equal to count. Cost: linear in the output.
std::string formatPrometheus(std::span<const MetricFamily> families);

// Escaping and number spelling used by formatPrometheus (exposed for tests).
std::string escapeLabelValue(std::string_view value);  // \ -> \\, " -> \", LF -> \n
std::string escapeHelp(std::string_view help);         // \ -> \\, LF -> \n
std::string sanitizeMetricName(std::string_view name);
std::string sanitizeLabelName(std::string_view name);
std::string formatSampleValue(double value);  // shortest round-trip; +Inf, -Inf, NaN

// Default upper bounds of the tick-time histogram, seconds: 0.25 ms ... 64 ms.
std::vector<double> defaultTickBuckets();

// A histogram that several threads observe at once (each room ticks on its own strand):
// lock-free counters, sum kept in nanoseconds. Bounds fixed at construction (ascending,
// finite; checked by the caller: they come from code).
class AtomicHistogram {
 public:
  explicit AtomicHistogram(std::vector<double> upper_bounds);

  // Records one observation (seconds, or whatever unit the bounds are in; negative
  // values count in the first bucket and add 0 to the sum). Wait-free, no allocation.
  void observe(double value);
  // A consistent-enough copy for a scrape (buckets read one by one; count is their sum).
  HistogramData snapshot() const;

 private:
  std::vector<double> upper_bounds_;
  std::unique_ptr<std::atomic<std::uint64_t>[]> buckets_;  // upper_bounds_.size() + 1
  std::atomic<std::uint64_t> sum_nanos_{0};                // sum * 1e9, rounded
};

// What vistel-server reports on /metrics. The server fills it when scraped; every field
// has a fixed metric name (see snapshotFamilies), so dashboards can rely on them.
struct MetricsSnapshot {
  // Gauges: the state now.
  std::uint64_t members = 0;              // vistel_members: joined members, all rooms
  std::uint64_t rooms = 0;                // vistel_rooms: open rooms
  std::uint64_t connections = 0;          // vistel_connections: open TCP control connections
  std::uint64_t uploads_in_progress = 0;  // vistel_uploads_in_progress
  bool ready = false;                     // vistel_ready: 1 once accepting joins
  // Counters: totals since the process started.
  std::uint64_t ticks_total = 0;          // vistel_ticks_total: room ticks, all rooms
  HistogramData tick_seconds;             // vistel_tick_seconds: work per room tick
  std::uint64_t bytes_in_tcp = 0;         // vistel_received_bytes_total{transport="tcp"}
  std::uint64_t bytes_in_udp = 0;         // vistel_received_bytes_total{transport="udp"}
  std::uint64_t bytes_out_tcp = 0;        // vistel_sent_bytes_total{transport="tcp"}
  std::uint64_t bytes_out_udp = 0;        // vistel_sent_bytes_total{transport="udp"}
  std::uint64_t datagrams_in_total = 0;   // vistel_datagrams_received_total
  std::uint64_t datagrams_out_total = 0;  // vistel_datagrams_sent_total
  std::uint64_t joins_total = 0;          // vistel_joins_total: joins accepted
  // Keyed by a short fixed reason ("bad key", "SERVER_FULL"); one sample per key.
  std::map<std::string, std::uint64_t> datagrams_dropped;  // vistel_datagrams_dropped_total{reason}
  std::map<std::string, std::uint64_t> joins_refused;      // vistel_joins_refused_total{reason}
  std::map<std::string, std::uint64_t>
      connections_dropped;      // vistel_connections_dropped_total{reason}
  double uptime_seconds = 0.0;  // vistel_uptime_seconds
  // Anything else the server wants to add, written after the fixed families.
  std::vector<MetricFamily> extra;
};

// The families of a snapshot, in a fixed order, with HELP text.
std::vector<MetricFamily> snapshotFamilies(const MetricsSnapshot& snapshot);

// formatPrometheus(snapshotFamilies(snapshot)).
std::string formatMetrics(const MetricsSnapshot& snapshot);

// The Content-Type of the text format.
inline constexpr std::string_view kPrometheusContentType =
    "text/plain; version=0.0.4; charset=utf-8";

}  // namespace vistel::server
