#include "client/bot/bot_report.hpp"

#include <nlohmann/json.hpp>

namespace vistel::net {

std::string botReportJson(const std::vector<ParticipantReport>& participants) {
  nlohmann::json doc;
  doc["participants"] = nlohmann::json::array();
  LatencyStats all;
  PlaybackStats shown;
  for (const ParticipantReport& p : participants) {
    std::uint64_t received = 0;
    for (const auto& [name, m] : p.stats.members) received += m.postures_received;
    doc["participants"].push_back({{"name", p.name},
                                   {"state", p.state},
                                   {"error", p.error},
                                   {"join_s", p.join_s},
                                   {"rejoins", p.rejoins},
                                   {"reconnects", p.stats.reconnects},
                                   {"udp_rehellos", p.stats.udp_rehellos},
                                   {"udp_rebinds", p.stats.udp_rebinds},
                                   {"live_s", p.live_s},
                                   {"postures_sent", p.stats.postures_sent},
                                   {"posture_bytes_sent", p.stats.posture_bytes_sent},
                                   {"datagram_bytes_received", p.stats.datagram_bytes_received},
                                   {"snapshots_received", p.stats.snapshots_received},
                                   {"datagrams_rejected", p.stats.datagrams_rejected},
                                   {"postures_received", received},
                                   {"latency_ms",
                                    {{"p50", p.stats.latency.percentile(50.0)},
                                     {"p99", p.stats.latency.percentile(99.0)},
                                     {"samples", p.stats.latency.count()}}},
                                   {"playback", nlohmann::json::parse(playbackJson(p.playback))}});
    all.merge(p.stats.latency);
    shown.merge(p.playback);
  }
  doc["latency_ms"] = {{"p50", all.percentile(50.0)},
                       {"p99", all.percentile(99.0)},
                       {"mean", all.mean()},
                       {"samples", all.count()}};
  doc["playback"] = nlohmann::json::parse(playbackJson(shown));
  nlohmann::json bins = nlohmann::json::array();
  for (std::size_t i = 0; i < all.bins().size(); ++i) {
    if (all.bins()[i] != 0) bins.push_back({i, all.bins()[i]});
  }
  doc["latency_histogram"] = {{"bin_ms", LatencyStats::binMs()}, {"bins", bins}};
  return doc.dump() + "\n";
}

}  // namespace vistel::net
