// A participant's voice (issue 22, proto/VOICE.md): capture -> voice activity -> Opus ->
// the session's UDP, and the session's voice frames -> a playout buffer per speaker ->
// decode / FEC / concealment -> spatialiser -> mixer -> speakers or a WAV file.
//
// The engine runs its own thread on a 20 ms grid of the steady clock. Each tick it
//  1. takes one 20 ms frame of input (a WAV file read at real-time pace, or the default
//     microphone through PortAudio), and unless muted runs it through VoiceActivity (and
//     speexdsp's noise suppression for a microphone) and, while speech lasts, encodes it
//     (Opus, 20 ms, in-band FEC, 16..32 kbit/s) and sends it (NetDriver::sendVoice);
//  2. takes the frames the session received and pushes each into its speaker's
//     SpeakerPlayout with its arrival time;
//  3. pulls one frame per speaker, spatialises it from the speaker's head relative to the
//     listener's head and facing (setScene), mixes and limits, and writes the stereo frame
//     to the speakers or appends it to the output file (written at stop()).
//
// Capture clock: a frame's capture time is the server clock (the session's ClockSync
// estimate) at its first sample, in samples at 48 kHz, anchored at the start of each
// talkspurt and counted in frames within one (a frame read at tick t was captured during
// the 20 ms before t). Listeners use it only for their playout buffer's offsets (any sender
// clock would do) and to measure mouth-to-ear latency: the server time at which a frame
// leaves the listener's 20 ms output buffer minus its capture time (so capture framing,
// network, playout buffer and device buffer are all in it). A file input starts once the
// session is live and its clock has converged (3 pongs), so its first sample is sent.
//
// Scheduled input (a bot replaying a clip or a .vrec, client/bot): with scheduled_input
// the file (or input_samples) waits for startInputAt(origin, period): the frame captured
// during [T - 20 ms, T) on the engine's clock (net::monotonicSeconds) is the input's
// samples from (T - 20 ms - origin) * 48000 on, silence before the origin and past the
// input's end; with loop_input and a period P (the motion's pass) the input restarts at
// the first multiple of P at or after its end, so each of its passes starts with one of
// the motion's and none is cut. Frames before the session is live are not sent
// (lost, as a live speaker's would be).
//
// Recording what is sent (vistel-client --record): on_sent, if set, is called on the
// engine's thread with every frame sent — its capture time (the frame's first sample, s on
// net::monotonicSeconds) and its Opus packet — so muted or silent stretches have none.
//
// Devices: with no file given, the default PortAudio device for that direction; when
// there is none, the engine says so once and goes on without it (silent). Threads: every
// public call is thread-safe.
#pragma once

#include <atomic>
#include <cstdint>
#include <functional>
#include <memory>
#include <mutex>
#include <span>
#include <string>
#include <thread>
#include <unordered_map>
#include <vector>

#include <glm/glm.hpp>

#include "client/net/net_driver.hpp"
#include "common/base/result.hpp"
#include "common/voice/opus_voice.hpp"
#include "common/voice/spatialiser.hpp"

namespace vistel {

struct VoiceOptions {
  std::string audio_in;         // a WAV (any libsndfile file) instead of the microphone
  std::string audio_out;        // a stereo 16-bit WAV written at stop() instead of the speakers
  bool capture = true;          // send the own voice (false: listen only)
  bool playback = true;         // play the others (false: speak only)
  bool muted = false;           // start muted (setMuted / toggleMute)
  bool loop_input = false;      // a file input starts over at its end (else it ends in silence)
  bool vad = true;              // send only speech (VoiceActivity); false: every frame
  bool denoise = true;          // speexdsp noise suppression on a microphone (never on a file)
  bool echo_cancel = true;      // with a microphone and speakers: remove what the speakers
                                // play from the capture (common/voice/echo_canceller)
  OpusVoiceSettings opus;       // 16 kbit/s, wideband, FEC, 10% loss hint by default
  std::string label = "voice";  // names log lines
  // Instead of audio_in: mono 48 kHz samples to speak (shared, read-only).
  std::shared_ptr<const std::vector<float>> input_samples;
  bool scheduled_input = false;  // the input waits for startInputAt (see above)
  // Every frame sent: (capture time s on net::monotonicSeconds, Opus packet). Engine thread;
  // must not block for long (a tick is 20 ms).
  std::function<void(double, std::span<const std::uint8_t>)> on_sent;
};

// Where a speaker is: its head in room space (metres).
struct SpeakerSpot {
  std::uint32_t id = 0;
  glm::vec3 head{0.0f};
};

// One speaker as this listener last heard it.
struct SpeakerReport {
  std::uint32_t id = 0;
  glm::vec3 head_space{0.0f};  // its head in the listener's head space (+X left, +Z ahead), m
  std::int64_t decoded = 0, fec = 0, concealed = 0, late = 0;
  std::int64_t target_delay_ms = 0;  // the playout buffer's jitter delay
};

struct VoiceReport {
  std::uint64_t frames_captured = 0;  // input frames read
  std::uint64_t frames_sent = 0;
  std::uint64_t bytes_sent = 0;  // sealed datagram bytes
  std::uint64_t frames_received = 0;
  std::uint64_t bytes_received = 0;
  std::uint64_t frames_rejected = 0;
  int speakers = 0;  // heard so far
  std::int64_t decoded = 0, fec = 0, concealed = 0, late = 0, dropped = 0, inserted = 0;
  std::int64_t decode_errors = 0;
  std::uint64_t ticks = 0;
  std::uint64_t late_ticks = 0;         // ticks run more than 10 ms after their time
  std::vector<double> mouth_to_ear_ms;  // one per decoded/FEC frame (bounded)
  double seconds_written = 0.0;         // to audio_out
  double sent_kbps = 0.0;               // sealed datagrams while speaking (frames_sent * 20 ms)
  double payload_kbps = 0.0;            // the Opus payload alone, while speaking
  std::uint64_t mouth_samples = 0;      // jaw openings kept for the timeline (noteMouth)
  std::uint64_t payload_bytes_sent = 0;
  std::vector<SpeakerReport> heard;    // speakers still known, by id
  double first_sent_capture_s = -1.0;  // the first frame sent: its capture time
                                       // (net::monotonicSeconds), -1 before any
};

class VoiceEngine {
 public:
  // Starts the thread. Errors: an unreadable audio_in, an Opus or speexdsp failure. A
  // missing device is not an error (see above).
  static Result<std::unique_ptr<VoiceEngine>> start(std::shared_ptr<net::NetDriver> driver,
                                                    const VoiceOptions& options);
  ~VoiceEngine();
  VoiceEngine(const VoiceEngine&) = delete;
  VoiceEngine& operator=(const VoiceEngine&) = delete;

  // With scheduled_input: the input's sample 0 is captured at the start of the engine's
  // first 20 ms frame that begins at or after origin_s (net::monotonicSeconds), so the first
  // frame sent is whole, as a live talkspurt's is; returns that time (at most 20 ms after
  // origin_s), for the caller to start its motion there too. With loop_input the input
  // restarts at the first multiple of period_s (> 0; 0: the input's own length) at or after
  // its end. Thread-safe; a later call moves the origin.
  double startInputAt(double origin_s, double period_s);

  void setMuted(bool muted) { muted_ = muted; }
  bool muted() const { return muted_; }
  void toggleMute() { muted_ = !muted_; }

  // The listener's head and the speakers' heads (room space), as of the latest frame.
  // Speakers without a spot are heard 1 m in front of the listener.
  void setScene(const HeadPose& listener, std::span<const SpeakerSpot> speakers);
  // The RMS (linear, 0..1) of what a speaker is heard saying in the frame audible now: 0
  // when silent or unknown. Lip sync follows it. "Audible now" is on the clock of the
  // mouth-to-ear latency: a frame mixed at tick k is heard from tick k + 1 (it leaves a
  // 20 ms output buffer), so with audio_out this is the frame written one tick before the
  // latest; with speakers, the one written as many ticks ago as are queued before them (the
  // ring plus PortAudio's output latency, rounded to ticks).
  float speakingLevel(std::uint32_t id) const;
  // Lip sync, as drawn: the frame loop says how far it opened a speaker's mouth (0..1, what
  // applyVoiceToPosture applied) on the posture it is about to draw, now. With audio_out the
  // engine keeps these for members it has heard (216000 rows, an hour of one speaker at
  // 60 Hz; later ones are dropped) with the time in audio_out's own timeline, and stop()
  // writes them as jawTimelinePath(audio_out): CSV, a header line then
  // `wav_time_s,member,opening` per drawn frame and speaker heard, where
  // wav_time_s is the time (s) of audio_out's sample at wav_time_s * 48000 as heard (its
  // sample 0 is heard one tick after the engine started), measured on the same monotonic
  // clock as the engine's ticks. Without audio_out: nothing is kept. Thread-safe, O(1).
  void noteMouth(std::uint32_t id, float opening);

  // Stops the thread and writes audio_out (if given). Idempotent.
  Status stop();
  VoiceReport report() const;
  // One line (no newline), and the report as a JSON object.
  std::string summary() const;
  std::string json() const;

 private:
  struct Speaker;
  struct Impl;
  VoiceEngine() = default;
  void run();

  std::unique_ptr<Impl> impl_;
  std::atomic<bool> muted_{false};
  std::atomic<bool> stop_{false};
  std::thread thread_;
  bool stopped_ = false;
};

// Where the jaw timeline of an audio_out file goes: "DIR/heard.wav" -> "DIR/heard.jaw.csv"
// (the extension, if any, replaced).
std::string jawTimelinePath(const std::string& audio_out);

// p-th percentile (0..100) of values (copied and sorted); 0 for none.
double voicePercentile(std::vector<double> values, double p);

}  // namespace vistel
