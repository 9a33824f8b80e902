#include "client/net/session_stats.hpp"

#include <algorithm>
#include <cmath>

#include <nlohmann/json.hpp>

namespace vistel::net {
namespace {

constexpr double kBinMs = 0.05;
constexpr std::size_t kBins = 40000;  // 2 s

}  // namespace

double MemberReceiveStats::rateHz() const {
  const double span = last_arrival - first_arrival;
  if (postures_received < 2 || span <= 0.0) return 0.0;
  return static_cast<double>(postures_received - 1) / span;
}

LatencyStats::LatencyStats() : bins_(kBins, 0) {}

void LatencyStats::add(double ms) {
  if (!std::isfinite(ms)) return;
  sum_ += ms;
  ++count_;
  const double bin = std::clamp(std::floor(ms / kBinMs), 0.0, static_cast<double>(kBins - 1));
  ++bins_[static_cast<std::size_t>(bin)];
}

double LatencyStats::percentile(double p) const {
  if (count_ == 0) return 0.0;
  const auto rank = static_cast<std::uint64_t>(
      std::ceil(std::clamp(p, 0.0, 100.0) / 100.0 * static_cast<double>(count_)));
  std::uint64_t seen = 0;
  for (std::size_t i = 0; i < bins_.size(); ++i) {
    seen += bins_[i];
    if (seen >= std::max<std::uint64_t>(rank, 1)) return (static_cast<double>(i) + 0.5) * kBinMs;
  }
  return static_cast<double>(kBins) * kBinMs;
}

void LatencyStats::merge(const LatencyStats& other) {
  for (std::size_t i = 0; i < bins_.size(); ++i) bins_[i] += other.bins_[i];
  count_ += other.count_;
  sum_ += other.sum_;
}

double LatencyStats::binMs() { return kBinMs; }

std::string statsJson(const SessionStats& stats, int frames_rendered, double clock_offset_s,
                      double clock_round_trip_s) {
  nlohmann::json doc;
  doc["members"] = nlohmann::json::object();
  for (const auto& [name, m] : stats.members) {
    doc["members"][name] = {{"postures_received", m.postures_received}, {"rate_hz", m.rateHz()}};
  }
  doc["latency_ms"] = {{"mean", stats.latency.mean()},
                       {"p50", stats.latency.percentile(50.0)},
                       {"p99", stats.latency.percentile(99.0)},
                       {"samples", stats.latency.count()}};
  doc["frames_rendered"] = frames_rendered;
  doc["postures_sent"] = stats.postures_sent;
  doc["posture_bytes_sent"] = stats.posture_bytes_sent;
  doc["snapshots_received"] = stats.snapshots_received;
  doc["datagram_bytes_received"] = stats.datagram_bytes_received;
  doc["datagrams_rejected"] = stats.datagrams_rejected;
  doc["reconnects"] = stats.reconnects;
  doc["udp_rehellos"] = stats.udp_rehellos;
  doc["udp_rebinds"] = stats.udp_rebinds;
  doc["dents"] = {{"sent", stats.dents_sent},
                  {"received", stats.dents_received},
                  {"rejected", stats.dents_rejected}};
  doc["clock"] = {{"offset_s", clock_offset_s}, {"round_trip_ms", clock_round_trip_s * 1e3}};
  return doc.dump(2) + "\n";
}

}  // namespace vistel::net
