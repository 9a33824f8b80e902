// RecordingReplay: a site's raw sensor recording (.vrec) replayed through the same solver
// as live (openPostureSource "recording:"), for `vistel-bot --recording FILE.vrec`
// (DESIGN.md §6: bots are clients whose source is a recording).
//
// The caller paces: advanceTo(t) solves every recorded frame up to replay time t (seconds
// since the replay started, measured on the recording's own frame times) and gives the
// newest posture, so a bot sending at the room's tick rate shows the recording at its real
// speed whatever the recording's frame rate. The calibration is applied where the live
// session made it (or from the header), so the replay solves exactly as live did.
//
// The voice track (record type 4, common/sensors/recording.hpp), when the file has one:
// its Opus packets decoded at open() into one mono 48 kHz timeline whose sample 0 is the
// first frame's time (a packet recorded at sensor time t lands at (t - first frame) *
// 48000; gaps are silence; packets before the first frame are dropped, a packet that does
// not decode is silence; the timeline ends with the last frame's pass, passSeconds()), for
// the bot's VoiceEngine to speak from the replay's start
// (VoiceEngine::startInputAt).
//
// A damaged file (a process killed mid-write, a truncated copy) replays up to its last good
// record; damage() says where and why it broke. With loop, the recording starts over after
// its last frame (a fresh solver, so every pass is the same).
#pragma once

#include <cstddef>
#include <memory>
#include <string>
#include <vector>

#include "common/anim/posture.hpp"
#include "common/anim/skeleton.hpp"
#include "common/base/result.hpp"
#include "common/sensors/io/posture_source.hpp"

namespace vistel {

struct ReplayVoice {
  std::shared_ptr<const std::vector<float>> samples;  // null without a voice track
  std::size_t packets = 0;                            // decoded into samples
  std::size_t dropped = 0;                            // before the first frame, or not decodable
  double first_offset_s = 0.0;  // the first packet kept, after the first frame
  double seconds = 0.0;         // samples' length
};

class RecordingReplay {
 public:
  // Loads the recording for this avatar skeleton (joint maps from config_dir). Fails,
  // naming the file and the reason, when even its header is unreadable, it holds no frame,
  // or the avatar has no joints the solver can drive.
  static Result<std::unique_ptr<RecordingReplay>> open(const std::string& path,
                                                       const Skeleton& avatar, bool loop,
                                                       const std::string& config_dir = "config");

  // Solves the frames recorded up to replay time t (seconds, non-decreasing between calls)
  // and writes the newest posture into out (avatar joints; reuses out's storage). Before
  // the first frame out is the first frame's posture. Returns false once the replay is over
  // (not looping, past the last frame): out then keeps the last posture.
  bool advanceTo(double t, Posture& out);

  // Summary for a start-up line: "FILE: N frames, D s at R Hz, participant P, from S".
  std::string describe() const;
  // Where and why the file stopped being readable; empty when every record was good.
  const std::string& damage() const { return damage_; }
  // Why the replay ended (the source's end message), once advanceTo returned false.
  const std::string& endMessage() const { return end_message_; }
  double frameRateHz() const { return rate_hz_; }
  double duration() const { return duration_; }
  // One pass with loop: the last frame's time after the first plus one frame interval.
  double passSeconds() const { return duration_ + 1.0 / rate_hz_; }
  const ReplayVoice& voice() const { return voice_; }
  std::size_t frameCount() const { return frame_count_; }
  std::size_t framesSolved() const { return frames_solved_; }

 private:
  RecordingReplay() = default;
  Status openSource();

  std::string path_;
  Skeleton avatar_;
  std::string config_dir_;
  bool loop_ = false;
  std::unique_ptr<PostureSource> source_;
  std::string summary_;
  std::string damage_;
  std::string end_message_;
  std::size_t frame_count_ = 0;
  std::size_t frames_solved_ = 0;
  double first_time_ = 0.0;  // the recording's first frame time
  double duration_ = 0.0;    // last frame time - first frame time
  double rate_hz_ = 0.0;     // frames per second over the recording
  double pass_start_ = 0.0;  // replay time at which the current pass started
  double last_time_ = 0.0;   // recording time of the newest solved frame
  bool started_ = false;     // a frame of this pass has been solved
  bool ended_ = false;
  ReplayVoice voice_;
};

}  // namespace vistel
