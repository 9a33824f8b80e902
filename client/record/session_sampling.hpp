// A client's session sampled into a room recording (common/record/room_recorder.hpp) as the
// client shows it: each remote member's posture from its jitter buffer at the playback time
// (as the frame loop samples it, the recorder's extrapolation limit included), the own
// avatar's latest posture (drawn ahead of the others, as on screen), each prop's centre.
#pragma once

#include "client/net/client_session.hpp"
#include "common/anim/posture.hpp"
#include "common/record/room_recorder.hpp"

namespace vistel::record {

// Called every frame with the session locked: when a sample is due at `now` (the caller's
// clock, seconds), records every member and prop as shown at `play_time` (server clock);
// `own` is the own avatar's posture (used for the member marked self). `scratch` holds a
// remote posture between calls (no allocation once sized).
void sampleSession(RoomRecorder& recorder, const net::ClientSession& session, double now,
                   double play_time, const Posture& own, Posture& scratch);

}  // namespace vistel::record
