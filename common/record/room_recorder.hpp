// What a room showed, recorded for export as a skinned glTF animation (room_glb.hpp writes
// it): by a client of what it drew (vistel-client --record-room FILE.glb, client/record's
// sampleSession) or by the server of what spectators see (vistel-server --record-room DIR,
// server/record).
//
// Every sample (at the room's tick rate by default) takes, for each member shown, its seat
// and posture, and each prop's centre (beginSample, addMember, addProp, endSample). Tracks per
// member (keyed by name and avatar hash, so a member who reconnects continues its tracks):
// the seat (translation and yaw), the root translation, every joint's local rotation (and
// local translations when the postures carry them), each reduced online to keyframes
// (keyframe_track.hpp). A member or prop that is absent from a sample (not yet joined, left,
// or nothing received yet) is outside its span; the export scales it to zero there.
//
// Time: the caller's monotonic clock in seconds (steady across reconnections, unlike the
// server clock); the recording starts (t = 0) at the first sample that shows anyone.
//
// Memory: the keys (a few per second per moving joint) and a bounded window per track.
// Not thread-safe: call from one thread (the frame loop).
#pragma once

#include <cstdint>
#include <functional>
#include <memory>
#include <string>
#include <unordered_map>
#include <utility>
#include <vector>

#include "common/anim/posture.hpp"
#include "common/avatar/avatar_model.hpp"
#include "common/base/result.hpp"
#include "common/deform/prop.hpp"
#include "common/record/keyframe_track.hpp"
#include "common/scene/seat_layout.hpp"

namespace vistel::record {

struct RecorderOptions {
  double rate_hz = 0.0;                         // samples per second; 0: the room's tick rate
  double max_extrapolation_s = 0.1;             // a client's, as its frame loop's ([playback])
  float rotation_tolerance_rad = 0.004363323f;  // 0.25 degree per joint
  float translation_tolerance_m = 0.0005f;      // 0.5 mm (root, seat, props)
};

// A time span [start, end) in recording seconds during which something was shown.
struct Span {
  double start = 0.0;
  double end = 0.0;
};

struct RecordedMember {
  std::string name;
  std::string avatar_hash;
  std::vector<Span> spans;
  Vec3Track seat_translation;                 // room space, metres (x, 0, z)
  QuatTrack seat_rotation;                    // yaw about +Y
  Vec3Track root_translation;                 // model space (Posture::root_translation)
  std::vector<QuatTrack> rotations;           // local rotation per joint (njoint)
  std::vector<Vec3Track> translations;        // local translation per joint, or empty (rest)
  std::shared_ptr<const AvatarModel> avatar;  // filled when exporting (null: not found)
};

struct RecordedProp {
  std::uint32_t id = 0;
  std::string name;  // "ball 1", "ball 2", ... in order of appearance
  BallSpec ball;
  std::vector<Span> spans;
  Vec3Track position;                        // centre, room space, metres
  std::shared_ptr<const AvatarModel> model;  // filled when exporting (its icosphere skin)
};

struct RoomRecording {
  double duration_s = 0.0;  // time of the last sample
  std::int64_t samples = 0;
  std::vector<RecordedMember> members;  // in order of appearance
  std::vector<RecordedProp> props;
};

struct RecordingSummary {
  int members = 0;          // written as skins
  int members_skipped = 0;  // avatar never received (named in warnings)
  int props = 0;
  double duration_s = 0.0;
  std::int64_t samples = 0;
  std::int64_t keys = 0;  // over all written channels
  std::size_t bytes = 0;
  std::vector<std::string> warnings;
};

// Checks at start what write() will need: `path` is not a folder and its folder exists
// (the error names it). Nothing is created.
Status checkRecordPath(const std::string& path);

class RoomRecorder {
 public:
  explicit RoomRecorder(RecorderOptions options = {});

  // One sample: beginSample() when a sample is due at `now` (the caller's clock, seconds;
  // rate_hz: the room's rate, used when options.rate_hz is 0), then addMember() / addProp()
  // for everything shown at that moment, then endSample(). beginSample() returns false when
  // no sample is due (call neither of the others then). A member is keyed by name and
  // avatar hash. Allocation-free once every track exists, but for keys and window growth.
  bool beginSample(double now, double rate_hz);
  void addMember(const std::string& name, const std::string& avatar_hash, const SeatPlacement& seat,
                 const Posture& posture);
  void addProp(std::uint32_t id, const BallSpec& ball, const glm::vec3& position);
  void endSample();

  // True when beginSample() would record at `now` (to skip copying postures otherwise).
  bool due(double now) const { return now >= next_due_ - 0.25 * interval_; }

  // Closes open spans at the last sample and flushes every track's window. Idempotent.
  const RoomRecording& finish();

  // finish(), then resolves the avatars (`avatar_of(hash)`, null: unknown) and the props'
  // models, encodes the .glb (room_glb.hpp) and writes it atomically to `path`.
  Result<RecordingSummary> write(
      const std::string& path,
      const std::function<std::shared_ptr<const AvatarModel>(const std::string&)>& avatar_of);

  const RoomRecording& recording() const { return recording_; }
  const RecorderOptions& options() const { return options_; }

 private:
  RecordedMember& memberFor(const std::string& name, const std::string& avatar_hash);
  RecordedProp& propFor(std::uint32_t id, const BallSpec& ball);
  void addPosture(RecordedMember& rec, const SeatPlacement& seat, const Posture& posture, double t);

  RecorderOptions options_;
  RoomRecording recording_;
  std::unordered_map<std::string, std::size_t> member_index_;  // name + '\n' + hash
  std::unordered_map<std::uint32_t, std::size_t> prop_index_;
  std::vector<std::int64_t> member_seen_;  // last sample index each member was shown
  std::vector<std::int64_t> prop_seen_;
  std::int64_t stamp_ = 0;   // samples taken so far
  double start_ = -1.0;      // caller's time of recording t = 0 (< 0: not started)
  double last_t_ = 0.0;      // recording time of the last sample
  double next_due_ = 0.0;    // caller's time of the next grid point
  double interval_ = 0.0;    // seconds between samples (0: none taken yet)
  double sample_now_ = 0.0;  // the sample in progress (beginSample): caller's time ...
  double sample_t_ = 0.0;    // ... and recording time (0 until the recording starts)
};

}  // namespace vistel::record
