// What the frame loop of the client (or the bot) tells its VoiceEngine, and what it takes
// back: the heads of the listener and of every other member (for the spatialiser), and the
// lip sync of a speaking avatar.
//
// VoiceScene: begin(), add() each roster member (self included: it is the listener) with
// its avatar's skeleton and posture when known (else its seat alone gives a head 1.6 m above
// it), then commit() to the engine. Keeps a HeadPoser per skeleton (by address: the
// skeletons must outlive the scene). Allocation-free once warm.
//
// Lip sync (applyVoiceToPosture): a speaking avatar's jaw opens with the level of what the
// listener hears from it now (VoiceEngine::speakingLevel: the RMS of the 20 ms frame
// playing), so mouth and sound move together within a frame or two; an avatar without a jaw
// joint (the canonical humanoid has none) lifts its chin instead, a few degrees. The frame
// loop reports each opening it draws (VoiceEngine::noteMouth) for the jaw timeline that
// tests/voice_session cross-correlates with the audio written.
#pragma once

#include <cstdint>
#include <unordered_map>
#include <vector>

#include <glm/glm.hpp>

#include "client/voice/head_pose.hpp"
#include "client/voice/voice_engine.hpp"

namespace vistel {

class VoiceScene {
 public:
  void begin();
  // skeleton and posture may be null (then the seat's head).
  void add(std::uint32_t id, bool is_self, const Skeleton* skeleton, const Posture* posture,
           const glm::mat4& placement);
  void commit(VoiceEngine& engine);

 private:
  std::unordered_map<const Skeleton*, HeadPoser> posers_;
  HeadPose listener_;
  std::vector<SpeakerSpot> spots_;
};

// How far a voice at `rms` (linear) opens a mouth: 0 at -50 dBFS or below, 1 at -20 dBFS.
float mouthOpening(float rms);
// Opens the jaw (a joint whose name contains "jaw", up to 20 degrees) or else lifts the
// head (up to 6 degrees) by `opening` (0..1), on the posture's local rotations. Returns the
// opening applied (0..1): 0 when the posture was left as it is (no opening, a posture of
// another joint count, neither a jaw nor a head joint).
float applyVoiceToPosture(const Skeleton& skeleton, float opening, Posture& posture);

}  // namespace vistel
