#include "client/net/remote_jitter.hpp"

namespace vistel::net {

void RemoteJitter::collect(const RemoteMember& m) {
  Track& tr = tracks_[m.id];
  tr.frame = frame_;
  tr.count = 0;
  for (const Posture* p = m.buffer.firstAfter(tr.last_sent);
       p != nullptr && tr.count < kMaxSentPerFrame; p = m.buffer.firstAfter(p->time)) {
    if (static_cast<int>(tr.sent.size()) <= tr.count) tr.sent.emplace_back();
    tr.sent[static_cast<std::size_t>(tr.count++)] = *p;
    tr.last_sent = p->time;
  }
}

void RemoteJitter::positions(const Skeleton& skeleton, const Posture& posture, Track& tr) {
  const std::size_t n = skeleton.names.size();
  tr.model.resize(n);
  tr.points.resize(n);
  poseSkeleton(skeleton, posture, tr.model);
  for (std::size_t j = 0; j < n; ++j) tr.points[j] = glm::vec3(tr.model[j][3]);
}

void RemoteJitter::measure(std::uint32_t id, const std::string& name, const Skeleton& skeleton,
                           double t, const Posture& drawn, PlaybackStats& stats) {
  auto it = tracks_.find(id);
  if (it == tracks_.end()) return;
  Track& tr = it->second;
  const std::size_t n = skeleton.names.size();
  for (int i = 0; i < tr.count; ++i) {
    const Posture& p = tr.sent[static_cast<std::size_t>(i)];
    if (p.rotations.size() != n) continue;
    positions(skeleton, p, tr);
    stats.addSent(name, p.time, tr.points);
  }
  tr.count = 0;
  if (drawn.rotations.size() != n) return;
  positions(skeleton, drawn, tr);
  stats.addDrawn(name, t, tr.points);
}

void RemoteJitter::endFrame() {
  std::erase_if(tracks_, [&](const auto& kv) { return kv.second.frame != frame_; });
  ++frame_;
}

}  // namespace vistel::net
