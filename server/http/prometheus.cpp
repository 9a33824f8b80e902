// Prometheus text exposition format 0.0.4 (the format's rules: one HELP and one TYPE
// line per family, label values escaped, histogram buckets cumulative with a final
// le="+Inf" equal to _count).
#include "server/http/prometheus.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

#include <fmt/format.h>

namespace vistel::server {
namespace {

bool isNameStart(char c) { return (c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') || c == '_'; }
bool isDigit(char c) { return c >= '0' && c <= '9'; }

// Keeps allowed characters, replaces the rest with '_' (and a leading digit too).
std::string sanitize(std::string_view name, bool allow_colon) {
  std::string out;
  out.reserve(name.size() + 1);
  for (char c : name) {
    bool ok = isNameStart(c) || isDigit(c) || (allow_colon && c == ':');
    out.push_back(ok ? c : '_');
  }
  if (out.empty() || isDigit(out.front())) out.insert(out.begin(), '_');
  return out;
}

const char* typeName(MetricType type) {
  switch (type) {
    case MetricType::kCounter:
      return "counter";
    case MetricType::kGauge:
      return "gauge";
    case MetricType::kHistogram:
      return "histogram";
  }
  return "untyped";
}

// {a="x",b="y"} plus an optional trailing le="..." (nothing when both are empty).
void appendLabels(std::string& out, const MetricLabels& labels, std::string_view le = {}) {
  if (labels.empty() && le.empty()) return;
  out.push_back('{');
  bool first = true;
  for (const auto& [name, value] : labels) {
    if (!first) out.push_back(',');
    first = false;
    out += sanitizeLabelName(name);
    out += "=\"";
    out += escapeLabelValue(value);
    out.push_back('"');
  }
  if (!le.empty()) {
    if (!first) out.push_back(',');
    out += "le=\"";
    out += le;
    out.push_back('"');
  }
  out.push_back('}');
}

void appendSample(std::string& out, std::string_view name, std::string_view suffix,
                  const MetricLabels& labels, std::string_view le, std::string_view value) {
  out += name;
  out += suffix;
  appendLabels(out, labels, le);
  out.push_back(' ');
  out += value;
  out.push_back('\n');
}

void appendHistogram(std::string& out, const std::string& name, const MetricSample& sample) {
  const HistogramData& h = sample.histogram;
  std::uint64_t cumulative = 0;
  for (std::size_t i = 0; i < h.upper_bounds.size(); ++i) {
    if (i < h.bucket_counts.size()) cumulative += h.bucket_counts[i];
    appendSample(out, name, "_bucket", sample.labels, formatSampleValue(h.upper_bounds[i]),
                 fmt::format("{}", cumulative));
  }
  appendSample(out, name, "_bucket", sample.labels, "+Inf", fmt::format("{}", h.count));
  appendSample(out, name, "_sum", sample.labels, {}, formatSampleValue(h.sum));
  appendSample(out, name, "_count", sample.labels, {}, fmt::format("{}", h.count));
}

MetricFamily gauge(std::string name, std::string help, double value) {
  return MetricFamily{std::move(name), std::move(help), MetricType::kGauge, {{{}, value, {}}}};
}

MetricFamily counter(std::string name, std::string help, double value) {
  return MetricFamily{std::move(name), std::move(help), MetricType::kCounter, {{{}, value, {}}}};
}

MetricFamily byReason(std::string name, std::string help,
                      const std::map<std::string, std::uint64_t>& counts) {
  MetricFamily family{std::move(name), std::move(help), MetricType::kCounter, {}};
  for (const auto& [reason, count] : counts) {
    family.samples.push_back({{{"reason", reason}}, static_cast<double>(count), {}});
  }
  return family;
}

}  // namespace

std::string escapeLabelValue(std::string_view value) {
  std::string out;
  out.reserve(value.size());
  for (char c : value) {
    if (c == '\\') {
      out += "\\\\";
    } else if (c == '"') {
      out += "\\\"";
    } else if (c == '\n') {
      out += "\\n";
    } else {
      out.push_back(c);
    }
  }
  return out;
}

std::string escapeHelp(std::string_view help) {
  std::string out;
  out.reserve(help.size());
  for (char c : help) {
    if (c == '\\') {
      out += "\\\\";
    } else if (c == '\n') {
      out += "\\n";
    } else {
      out.push_back(c);
    }
  }
  return out;
}

std::string sanitizeMetricName(std::string_view name) { return sanitize(name, true); }

std::string sanitizeLabelName(std::string_view name) {
  std::string out = sanitize(name, false);
  // Names beginning with __ are reserved for Prometheus itself.
  if (out.size() >= 2 && out[0] == '_' && out[1] == '_') out.insert(out.begin(), 'x');
  return out;
}

std::string formatSampleValue(double value) {
  if (std::isnan(value)) return "NaN";
  if (std::isinf(value)) return value > 0 ? "+Inf" : "-Inf";
  return fmt::format("{}", value);
}

std::string formatPrometheus(std::span<const MetricFamily> families) {
  std::string out;
  for (const MetricFamily& family : families) {
    const std::string name = sanitizeMetricName(family.name);
    out += "# HELP ";
    out += name;
    out.push_back(' ');
    out += escapeHelp(family.help);
    out += "\n# TYPE ";
    out += name;
    out.push_back(' ');
    out += typeName(family.type);
    out.push_back('\n');
    for (const MetricSample& sample : family.samples) {
      if (family.type == MetricType::kHistogram) {
        appendHistogram(out, name, sample);
      } else {
        appendSample(out, name, {}, sample.labels, {}, formatSampleValue(sample.value));
      }
    }
  }
  return out;
}

std::vector<double> defaultTickBuckets() {
  return {0.00025, 0.0005, 0.001, 0.002, 0.004, 0.008, 0.016, 0.032, 0.064};
}

AtomicHistogram::AtomicHistogram(std::vector<double> upper_bounds)
    : upper_bounds_(std::move(upper_bounds)),
      buckets_(std::make_unique<std::atomic<std::uint64_t>[]>(upper_bounds_.size() + 1)) {
  for (std::size_t i = 0; i <= upper_bounds_.size(); ++i) buckets_[i].store(0);
}

void AtomicHistogram::observe(double value) {
  // The first bucket whose upper bound is >= value (Prometheus buckets are inclusive).
  auto it = std::lower_bound(upper_bounds_.begin(), upper_bounds_.end(), value);
  std::size_t index = static_cast<std::size_t>(it - upper_bounds_.begin());
  buckets_[index].fetch_add(1, std::memory_order_relaxed);
  if (value > 0.0 && std::isfinite(value)) {
    double nanos = std::min(value * 1e9, 1e18);
    sum_nanos_.fetch_add(static_cast<std::uint64_t>(std::llround(nanos)),
                         std::memory_order_relaxed);
  }
}

HistogramData AtomicHistogram::snapshot() const {
  HistogramData data;
  data.upper_bounds = upper_bounds_;
  data.bucket_counts.resize(upper_bounds_.size() + 1);
  for (std::size_t i = 0; i <= upper_bounds_.size(); ++i) {
    data.bucket_counts[i] = buckets_[i].load(std::memory_order_relaxed);
    data.count += data.bucket_counts[i];
  }
  data.sum = static_cast<double>(sum_nanos_.load(std::memory_order_relaxed)) * 1e-9;
  return data;
}

std::vector<MetricFamily> snapshotFamilies(const MetricsSnapshot& s) {
  std::vector<MetricFamily> families;
  auto d = [](std::uint64_t v) { return static_cast<double>(v); };
  families.push_back(gauge("vistel_ready",
                           "1 once the server accepts joins, 0 while starting or "
                           "shutting down.",
                           s.ready ? 1.0 : 0.0));
  families.push_back(gauge("vistel_members", "Joined members over all rooms.", d(s.members)));
  families.push_back(gauge("vistel_rooms", "Open rooms.", d(s.rooms)));
  families.push_back(
      gauge("vistel_connections", "Open TCP control connections.", d(s.connections)));
  families.push_back(gauge("vistel_uploads_in_progress", "Avatar uploads not yet complete.",
                           d(s.uploads_in_progress)));
  families.push_back(
      gauge("vistel_uptime_seconds", "Seconds since the server started.", s.uptime_seconds));
  families.push_back(counter("vistel_ticks_total", "Room ticks run, all rooms.", d(s.ticks_total)));
  families.push_back(MetricFamily{"vistel_tick_seconds",
                                  "Work time of one room tick in seconds.",
                                  MetricType::kHistogram,
                                  {MetricSample{{}, 0.0, s.tick_seconds}}});
  families.push_back(MetricFamily{"vistel_received_bytes_total",
                                  "Bytes received from peers, by transport.",
                                  MetricType::kCounter,
                                  {{{{"transport", "tcp"}}, d(s.bytes_in_tcp), {}},
                                   {{{"transport", "udp"}}, d(s.bytes_in_udp), {}}}});
  families.push_back(MetricFamily{"vistel_sent_bytes_total",
                                  "Bytes sent to peers, by transport.",
                                  MetricType::kCounter,
                                  {{{{"transport", "tcp"}}, d(s.bytes_out_tcp), {}},
                                   {{{"transport", "udp"}}, d(s.bytes_out_udp), {}}}});
  families.push_back(counter("vistel_datagrams_received_total", "UDP datagrams received.",
                             d(s.datagrams_in_total)));
  families.push_back(
      counter("vistel_datagrams_sent_total", "UDP datagrams sent.", d(s.datagrams_out_total)));
  families.push_back(byReason("vistel_datagrams_dropped_total", "UDP datagrams dropped, by reason.",
                              s.datagrams_dropped));
  families.push_back(counter("vistel_joins_total", "Joins accepted.", d(s.joins_total)));
  families.push_back(
      byReason("vistel_joins_refused_total", "Joins refused, by reason.", s.joins_refused));
  families.push_back(byReason("vistel_connections_dropped_total",
                              "Control connections dropped by the server, by reason.",
                              s.connections_dropped));
  for (const MetricFamily& extra : s.extra) families.push_back(extra);
  return families;
}

std::string formatMetrics(const MetricsSnapshot& snapshot) {
  std::vector<MetricFamily> families = snapshotFamilies(snapshot);
  return formatPrometheus(families);
}

}  // namespace vistel::server
