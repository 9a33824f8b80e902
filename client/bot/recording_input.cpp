#include "client/bot/recording_input.hpp"

#include <utility>

#include <fmt/format.h>

#include "common/sensors/recording.hpp"
#include "common/voice/opus_voice.hpp"
#include "common/voice/voice_format.hpp"

namespace vistel {

Result<std::unique_ptr<RecordingReplay>> RecordingReplay::open(const std::string& path,
                                                               const Skeleton& avatar, bool loop,
                                                               const std::string& config_dir) {
  // What the file holds (and where it breaks), for the messages and the pacing.
  Result<Recording> recording = loadRecording(path);
  if (!recording) return recording.error();
  if (recording->frames.empty()) {
    return fail("{}: no sensor frame recorded{}", path,
                recording->complete ? "" : " (" + recording->stop_reason + ")");
  }
  std::unique_ptr<RecordingReplay> replay(new RecordingReplay());
  replay->path_ = path;
  replay->avatar_ = avatar;
  replay->config_dir_ = config_dir;
  replay->loop_ = loop;
  replay->frame_count_ = recording->frames.size();
  replay->first_time_ = recording->frames.front().time;
  replay->duration_ = recording->frames.back().time - replay->first_time_;
  replay->rate_hz_ = replay->duration_ > 0.0
                         ? static_cast<double>(replay->frame_count_ - 1) / replay->duration_
                         : 30.0;
  if (!recording->complete) replay->damage_ = recording->stop_reason;
  const RecordingHeader& h = recording->header;
  replay->summary_ = fmt::format(
      "{}: {} frames, {:.1f} s at {:.0f} Hz, participant '{}', recorded from {}{}", path,
      replay->frame_count_, replay->duration_, replay->rate_hz_, h.participant,
      h.source.empty() ? "(unknown)" : h.source,
      h.calibration || !recording->calibrations.empty() ? ", calibrated" : ", never calibrated");
  // The voice track, decoded onto the replay's timeline.
  if (!recording->voice.empty()) {
    auto decoder = OpusVoiceDecoder::create();
    if (!decoder) return decoder.error();
    auto samples = std::make_shared<std::vector<float>>();
    ReplayVoice& v = replay->voice_;
    for (const VoiceRecord& r : recording->voice) {
      const std::int64_t at = voiceSamplesFromSeconds(r.time - replay->first_time_);
      if (at < 0) {
        ++v.dropped;
        continue;
      }
      const auto from = static_cast<std::size_t>(at);
      if (samples->size() < from + kVoiceFrameSamples) samples->resize(from + kVoiceFrameSamples);
      if (!decoder->decode(r.packet,
                           std::span<float>(*samples).subspan(from, kVoiceFrameSamples))) {
        ++v.dropped;
        continue;
      }
      if (v.packets++ == 0) v.first_offset_s = voiceSecondsFromSamples(at);
    }
    // Nothing past one pass: a looping replay restarts its voice with its motion.
    const auto pass = static_cast<std::size_t>(voiceSamplesFromSeconds(replay->passSeconds()));
    if (samples->size() > pass) samples->resize(pass);
    v.seconds = voiceSecondsFromSamples(static_cast<std::int64_t>(samples->size()));
    if (v.packets > 0) v.samples = std::move(samples);
    replay->summary_ +=
        fmt::format("; voice track: {} packets, first {:.3f} s after the first frame{}", v.packets,
                    v.first_offset_s, v.dropped > 0 ? fmt::format(" ({} dropped)", v.dropped) : "");
  }
  // The solver side: the same PostureSource as a live client, fed from the file.
  if (Status s = replay->openSource(); !s) return s.error();
  return replay;
}

Status RecordingReplay::openSource() {
  PostureSourceOptions options;
  options.config_dir = config_dir_;
  options.realtime = false;  // advanceTo paces
  Result<std::unique_ptr<PostureSource>> source =
      openPostureSource("recording:" + path_, avatar_, options);
  if (!source) return source.error();
  source_ = std::move(*source);
  started_ = false;
  return {};
}

bool RecordingReplay::advanceTo(double t, Posture& out) {
  if (ended_) return false;
  // Solve every frame due by t: the newest one is the posture to show.
  const double target = first_time_ + (t - pass_start_);
  while (!started_ || last_time_ < target) {
    const PollResult r = source_->poll(0.0, out);
    if (r.isFrame()) {
      started_ = true;
      last_time_ = source_->lastFrame().time;
      ++frames_solved_;
      continue;
    }
    end_message_ = r.message;
    if (!loop_ || r.status != PollStatus::kEnd) {
      ended_ = true;
      return false;
    }
    // Looping: the next pass starts one frame interval after this one's last frame; this
    // call keeps the last posture.
    pass_start_ += duration_ + 1.0 / rate_hz_;
    if (Status s = openSource(); !s) {
      end_message_ = s.error().message;
      ended_ = true;
      return false;
    }
    return true;
  }
  return true;
}

std::string RecordingReplay::describe() const { return summary_; }

}  // namespace vistel
