#include "client/record/session_sampling.hpp"

namespace vistel::record {

void sampleSession(RoomRecorder& recorder, const net::ClientSession& session, double now,
                   double play_time, const Posture& own, Posture& scratch) {
  if (!recorder.beginSample(now, session.tickRateHz())) return;
  // Members: the posture each shows now (remote: the jitter buffer at the playback time).
  for (const auto& member : session.members()) {
    const net::RemoteMember& m = *member;
    const Posture* posture = nullptr;
    if (m.is_self) {
      posture = own.rotations.empty() ? nullptr : &own;
    } else if (m.buffer.sampleShown(play_time, recorder.options().max_extrapolation_s, scratch) !=
               net::JitterBuffer::Shown::kNone) {
      posture = &scratch;
    }
    if (posture != nullptr) {
      recorder.addMember(m.name, m.avatar_hash, {m.seat.x, m.seat.z, m.seat.yaw}, *posture);
    }
  }
  // Props: their centres at the playback time.
  for (const auto& prop : session.props()) {
    net::PropSample state;
    if (prop->track.sample(play_time, state)) {
      recorder.addProp(prop->id, prop->ball, state.position);
    }
  }
  recorder.endSample();
}

}  // namespace vistel::record
