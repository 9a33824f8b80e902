#include "client/voice/voice_engine.hpp"

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <optional>

#include <fmt/format.h>
#include <spdlog/spdlog.h>

#include "client/voice/audio_device.hpp"
#include "common/base/file.hpp"
#include "common/voice/audio_compare.hpp"
#include "common/voice/echo_canceller.hpp"
#include "common/voice/mixer.hpp"
#include "common/voice/speaker_playout.hpp"
#include "common/voice/voice_activity.hpp"
#include "common/voice/voice_format.hpp"
#include "common/voice/wav_file.hpp"
#include "common/wire/voice_packets.hpp"

namespace vistel {
namespace {

using Clock = std::chrono::steady_clock;

constexpr double kFrameS = static_cast<double>(kVoiceFrameSamples) / kVoiceSampleRate;
constexpr std::size_t kMaxLatencySamples = 1u << 20;  // 5.8 hours of one speaker
constexpr double kForgetSpeakerS = 30.0;              // a speaker silent this long is dropped
constexpr int kClockSamplesBeforeFile = 3;            // pongs before a file input starts
constexpr std::size_t kMaxMouthSamples = 60 * 3600;   // an hour of jaw openings at 60 Hz

float rms(std::span<const float> x) {
  double sum = 0.0;
  for (float v : x) sum += static_cast<double>(v) * v;
  return x.empty() ? 0.0f : static_cast<float>(std::sqrt(sum / static_cast<double>(x.size())));
}

}  // namespace

double voicePercentile(std::vector<double> values, double p) {
  if (values.empty()) return 0.0;
  std::sort(values.begin(), values.end());
  const auto i = static_cast<std::size_t>(
      std::clamp(p / 100.0, 0.0, 1.0) * static_cast<double>(values.size() - 1) + 0.5);
  return values[std::min(i, values.size() - 1)];
}

std::string jawTimelinePath(const std::string& audio_out) {
  const std::size_t slash = audio_out.find_last_of('/');
  const std::size_t dot = audio_out.find_last_of('.');
  const bool has_ext = dot != std::string::npos && (slash == std::string::npos || dot > slash);
  return (has_ext ? audio_out.substr(0, dot) : audio_out) + ".jaw.csv";
}

struct VoiceEngine::Speaker {
  explicit Speaker(SpeakerPlayout p) : playout(std::move(p)) {}
  SpeakerPlayout playout;
  SpatialSourceState spatial;
  double last_packet = 0.0;  // engine clock, seconds
  glm::vec3 head_space{0.0f};
};

namespace {

SpeakerReport speakerReport(std::uint32_t id, const SpeakerPlayout& playout,
                            const glm::vec3& head_space) {
  SpeakerReport h;
  const JitterBufferStats& b = playout.buffer().stats();
  h.id = id;
  h.head_space = head_space;
  h.decoded = b.decoded, h.fec = b.fec, h.concealed = b.concealed, h.late = b.late;
  h.target_delay_ms = playout.buffer().jitterDelay() * 1000 / kVoiceSampleRate;
  return h;
}

// Adds what a speaker's buffer did to the totals.
void addTotals(const SpeakerPlayout& playout, VoiceReport& r) {
  const JitterBufferStats& b = playout.buffer().stats();
  r.decoded += b.decoded, r.fec += b.fec, r.concealed += b.concealed, r.late += b.late;
  r.dropped += b.dropped, r.inserted += b.inserted;
  r.decode_errors += playout.decodeErrors();
}

}  // namespace

struct VoiceEngine::Impl {
  std::shared_ptr<net::NetDriver> driver;
  VoiceOptions options;

  // Input.
  std::vector<float> input_clip;  // audio_in, mono 48 kHz
  std::size_t input_pos = 0;
  std::shared_ptr<const std::vector<float>> scheduled;  // scheduled input, else null
  std::atomic<bool> origin_set{false};
  double origin = 0.0, period = 0.0;  // startInputAt (under mutex)
  bool input_started = false;
  bool input_done = false;
  std::unique_ptr<AudioDevice> device;  // microphone and/or speakers
  bool device_in = false;
  bool device_out = false;
  std::optional<VoiceActivity> vad;
  std::optional<EchoCanceller> echo;  // microphone and speakers both open
  std::vector<float> played = std::vector<float>(kVoiceFrameSamples);  // last tick's, mono
  std::optional<OpusVoiceEncoder> encoder;
  bool talking = false;            // the previous frame was sent
  std::uint32_t capture_time = 0;  // of the last frame sent
  std::vector<float> frame = std::vector<float>(kVoiceFrameSamples);
  std::vector<std::uint8_t> packet = std::vector<std::uint8_t>(kVoiceMaxPacketBytes);

  // Output.
  std::unordered_map<std::uint32_t, std::unique_ptr<Speaker>> speakers;
  std::vector<net::ReceivedVoice> inbox;
  VoiceMixer mixer;
  std::vector<float> mono = std::vector<float>(kVoiceFrameSamples);
  std::vector<float> stereo = std::vector<float>(2 * kVoiceFrameSamples);
  std::vector<float> output;  // audio_out, stereo interleaved

  // Shared with the other threads.
  mutable std::mutex mutex;
  HeadPose listener;
  std::vector<SpeakerSpot> spots;
  // What each speaker said in the last ticks (RMS), newest at `next - 1`; speakingLevel
  // reads it `level_lag` ticks back: the frames queued before the speakers are not heard yet.
  struct LevelHistory {
    std::array<float, 8> rms{};
    std::size_t next = 0;
  };
  std::unordered_map<std::uint32_t, LevelHistory> levels;
  int level_lag = 0;
  // Lip sync as drawn (noteMouth), with audio_out only.
  struct MouthSample {
    double wav_time = 0.0;  // s in audio_out's timeline
    std::uint32_t id = 0;
    float opening = 0.0f;
  };
  std::vector<MouthSample> mouth;
  Clock::time_point start_point;  // the engine's tick 0
  double t0 = 0.0;                // the same moment, net::monotonicSeconds()
  VoiceReport report;
  net::VoiceCounters counters;
  std::vector<double> latency_ms;
};

Result<std::unique_ptr<VoiceEngine>> VoiceEngine::start(std::shared_ptr<net::NetDriver> driver,
                                                        const VoiceOptions& options) {
  std::unique_ptr<VoiceEngine> engine(new VoiceEngine());
  engine->impl_ = std::make_unique<Impl>();
  Impl& m = *engine->impl_;
  m.driver = std::move(driver);
  m.options = options;
  engine->muted_ = options.muted;

  if (options.capture) {
    if (!options.audio_in.empty()) {
      auto clip = readAudioFile(options.audio_in);
      if (!clip) return clip.error();
      m.input_clip = monoMix(*clip);
    }
    if (options.input_samples) m.input_clip = *options.input_samples;
    if (options.scheduled_input) {
      m.scheduled = std::make_shared<const std::vector<float>>(std::move(m.input_clip));
      m.input_clip.clear();
    }
    VoiceActivitySettings vad_settings;
    vad_settings.denoise = options.denoise && options.audio_in.empty();
    auto vad = VoiceActivity::create(vad_settings);
    if (!vad) return vad.error();
    m.vad.emplace(std::move(*vad));
    auto encoder = OpusVoiceEncoder::create(options.opus);
    if (!encoder) return encoder.error();
    m.encoder.emplace(std::move(*encoder));
  }
  // Devices for the directions without a file; none: said once, carried on silent.
  const bool want_in = options.capture && options.audio_in.empty() && !options.input_samples;
  const bool want_out = options.playback && options.audio_out.empty();
  if (want_in || want_out) {
    auto device = AudioDevice::open(want_in, want_out);
    if (!device && want_in && want_out) {
      // Perhaps only one direction exists.
      device = AudioDevice::open(false, true);
      if (device) {
        spdlog::warn("{}: no microphone: not sending voice (use --audio-in FILE.wav)",
                     options.label);
      } else {
        device = AudioDevice::open(true, false);
        if (device)
          spdlog::warn("{}: no speakers: voice is not played (use --audio-out FILE.wav)",
                       options.label);
      }
    }
    if (device) {
      m.device = std::move(*device);
      m.device_in = want_in && m.device->description().find("input:") != std::string::npos;
      m.device_out = want_out && m.device->description().find("output:") != std::string::npos;
      spdlog::info("{}: audio device {}", options.label, m.device->description());
      if (m.device_in && m.device_out && options.echo_cancel) {
        auto echo = EchoCanceller::create();
        if (!echo) return echo.error();
        m.echo.emplace(std::move(*echo));
      }
    } else {
      spdlog::warn("{}: {}; carrying on without audio device ({})", options.label,
                   device.error().message,
                   want_in && want_out ? "use --audio-in / --audio-out FILE.wav"
                   : want_in           ? "use --audio-in FILE.wav"
                                       : "use --audio-out FILE.wav");
    }
  }
  m.latency_ms.reserve(4096);
  // A file's frame k is mixed at tick k and heard from tick k + 1 (speakingLevel).
  if (options.playback && !options.audio_out.empty()) {
    m.level_lag = 1;
    m.mouth.reserve(60 * 600);  // ten minutes of one speaker before it grows
  }
  m.start_point = Clock::now();
  m.t0 = net::monotonicSeconds();
  engine->thread_ = std::thread([e = engine.get()] { e->run(); });
  return engine;
}

VoiceEngine::~VoiceEngine() {
  if (Status st = stop(); !st) spdlog::warn("{}", st.error().message);
}

double VoiceEngine::startInputAt(double origin_s, double period_s) {
  Impl& m = *impl_;
  // Frame k of the engine covers [t0 + (k - 1) * 20 ms, t0 + k * 20 ms).
  const double frames = std::ceil((origin_s - m.t0) / kFrameS - 1e-9);
  const double origin = m.t0 + frames * kFrameS;
  std::lock_guard lock(m.mutex);
  m.origin = origin;
  m.period = std::max(0.0, period_s);
  m.origin_set = true;
  return origin;
}

void VoiceEngine::setScene(const HeadPose& listener, std::span<const SpeakerSpot> speakers) {
  std::lock_guard lock(impl_->mutex);
  impl_->listener = listener;
  impl_->spots.assign(speakers.begin(), speakers.end());
}

float VoiceEngine::speakingLevel(std::uint32_t id) const {
  std::lock_guard lock(impl_->mutex);
  auto it = impl_->levels.find(id);
  if (it == impl_->levels.end()) return 0.0f;
  const Impl::LevelHistory& h = it->second;
  const std::size_t n = h.rms.size();
  return h.rms[(h.next + n - 1 - static_cast<std::size_t>(impl_->level_lag)) % n];
}

void VoiceEngine::noteMouth(std::uint32_t id, float opening) {
  Impl& m = *impl_;
  if (!m.options.playback || m.options.audio_out.empty()) return;
  const double wav_time = net::monotonicSeconds() - (m.t0 + kFrameS);
  std::lock_guard lock(m.mutex);
  if (m.mouth.size() < kMaxMouthSamples && m.levels.count(id) != 0) {  // speakers heard only
    m.mouth.push_back({wav_time, id, opening});
  }
}

void VoiceEngine::run() {
  Impl& m = *impl_;
  const Clock::time_point start = m.start_point;
  const double t0 = m.t0;
  const std::int64_t base = voiceSamplesFromSeconds(t0);
  HeadPose listener;
  std::vector<SpeakerSpot> spots;
  for (std::int64_t k = 0; !stop_; ++k) {
    const Clock::time_point due =
        start + std::chrono::duration_cast<Clock::duration>(
                    std::chrono::duration<double>(static_cast<double>(k) * kFrameS));
    std::this_thread::sleep_until(due);
    const double late = std::chrono::duration<double>(Clock::now() - due).count();
    const double tick_time = t0 + static_cast<double>(k) * kFrameS;  // engine clock
    const std::int64_t tick_samples = base + k * kVoiceFrameSamples;

    // The session's state and clock.
    struct SessionView {
      bool live = false;
      int clock_samples = 0;
      double offset = 0.0;  // server minus local
    };
    const SessionView session = m.driver->withSession([](const net::ClientSession& s, double) {
      return SessionView{s.state() == net::SessionState::kLive, s.clock().sampleCount(),
                         s.clock().offset()};
    });

    // 1. Capture and send.
    bool have_frame = false;
    if (m.options.capture) {
      if (m.scheduled) {
        // The input's timeline from the origin: this tick's frame began 20 ms ago.
        if (m.origin_set && session.live) {
          double origin = 0.0, period = 0.0;
          {
            std::lock_guard lock(m.mutex);
            origin = m.origin;
            period = m.period;
          }
          const std::vector<float>& in = *m.scheduled;
          const std::int64_t size = static_cast<std::int64_t>(in.size());
          std::int64_t wrap = 0;  // samples per pass (0: no wrapping)
          if (m.options.loop_input) {
            const std::int64_t pass = period > 0.0 ? voiceSamplesFromSeconds(period) : size;
            wrap = pass > 0 ? pass * std::max<std::int64_t>(1, (size + pass - 1) / pass) : 0;
          }
          const std::int64_t pos = voiceSamplesFromSeconds(tick_time - kFrameS - origin);
          for (int i = 0; i < kVoiceFrameSamples; ++i) {
            std::int64_t at = pos + i;
            if (at >= 0 && wrap > 0) at %= wrap;
            m.frame[static_cast<std::size_t>(i)] =
                at >= 0 && at < size ? in[static_cast<std::size_t>(at)] : 0.0f;
          }
          have_frame = pos + kVoiceFrameSamples > 0;
        }
      } else if (!m.input_clip.empty()) {
        if (!m.input_started && session.live && session.clock_samples >= kClockSamplesBeforeFile) {
          m.input_started = true;
        }
        if (m.input_started && !m.input_done) {
          for (int i = 0; i < kVoiceFrameSamples; ++i) {
            if (m.input_pos >= m.input_clip.size()) {
              if (m.options.loop_input) {
                m.input_pos = 0;
              } else {
                m.input_done = true;
              }
            }
            m.frame[static_cast<std::size_t>(i)] =
                m.input_done ? 0.0f : m.input_clip[m.input_pos++];
          }
          have_frame = true;
        }
      } else if (m.device_in) {
        have_frame = m.device->readFrame(m.frame);
        // The speakers' last frame reaches the microphone through the room: removed here,
        // the device's latency learnt by the canceller's filter.
        if (have_frame && m.echo) m.echo->cancel(m.frame, m.played);
      }
    }
    bool sent = false;
    if (have_frame && !muted_ && session.live) {
      VoiceActivityDecision d;
      if (m.options.vad) {
        d = m.vad->process(m.frame);
      } else {
        d.send = true;
        d.level_dbfs = static_cast<float>(levelDbfs(m.frame));
      }
      if (d.send) {
        // The capture clock: the server's at the frame's first sample (20 ms before this
        // tick), anchored per talkspurt.
        if (!m.talking) {
          const double server_capture = tick_time - kFrameS + session.offset;
          m.capture_time = static_cast<std::uint32_t>(
              static_cast<std::uint64_t>(voiceSamplesFromSeconds(server_capture)));
        } else {
          m.capture_time += kVoiceFrameSamples;
        }
        auto size = m.encoder->encode(m.frame, m.packet);
        if (size) {
          net::OutgoingVoice out;
          out.capture_time = m.capture_time;
          out.level = wire::voiceLevelField(d.level_dbfs);
          out.payload = std::span<const std::uint8_t>(m.packet.data(), *size);
          sent = m.driver->sendVoice(out);
          if (sent) {
            if (m.options.on_sent) m.options.on_sent(tick_time - kFrameS, out.payload);
            std::lock_guard lock(m.mutex);
            m.report.payload_bytes_sent += *size;
            if (m.report.first_sent_capture_s < 0.0) {
              m.report.first_sent_capture_s = tick_time - kFrameS;
            }
          }
        }
      }
    }
    m.talking = sent;

    // 2. Receive.
    m.inbox.clear();
    net::VoiceCounters counters;
    m.driver->takeVoice(m.inbox, &counters);
    if (m.options.playback) {
      for (const net::ReceivedVoice& f : m.inbox) {
        auto it = m.speakers.find(f.speaker_id);
        if (it == m.speakers.end()) {
          auto playout = SpeakerPlayout::create();
          if (!playout) {
            spdlog::warn("{}: {}", m.options.label, playout.error().message);
            continue;
          }
          it = m.speakers.emplace(f.speaker_id, std::make_unique<Speaker>(std::move(*playout)))
                   .first;
          spdlog::info("{}: hearing member {:#x}", m.options.label, f.speaker_id);
        }
        it->second->playout.push({f.sequence, f.capture_time, f.bytes()},
                                 voiceSamplesFromSeconds(f.arrival));
        it->second->last_packet = tick_time;
      }
    }

    // 3. Play: every speaker's frame, spatialised from where it stands, mixed.
    {
      std::lock_guard lock(m.mutex);
      listener = m.listener;
      spots = m.spots;
    }
    m.mixer.beginBlock();
    const double heard_at = tick_time + kFrameS + session.offset;  // leaving a 20 ms buffer
    for (auto it = m.speakers.begin(); it != m.speakers.end();) {
      Speaker& s = *it->second;
      const PlayoutDecision d = s.playout.pull(tick_samples, m.mono);
      const float level = d.kind == PlayoutKind::kSilence ? 0.0f : rms(m.mono);
      if ((d.kind == PlayoutKind::kDecode || d.kind == PlayoutKind::kFec) && d.capture_time >= 0 &&
          session.clock_samples > 0) {
        // Capture times are server-clock samples modulo 2^32: the wrapped difference.
        const auto heard = static_cast<std::uint32_t>(
            static_cast<std::uint64_t>(voiceSamplesFromSeconds(heard_at)));
        const auto diff = static_cast<std::int32_t>(
            heard - static_cast<std::uint32_t>(static_cast<std::uint64_t>(d.capture_time)));
        if (m.latency_ms.size() < kMaxLatencySamples) {
          m.latency_ms.push_back(1e3 * static_cast<double>(diff) / kVoiceSampleRate);
        }
      }
      glm::vec3 where = listener.position + listener.orientation * glm::vec3(0.0f, 0.0f, 1.0f);
      for (const SpeakerSpot& spot : spots) {
        if (spot.id != it->first) continue;
        where = spot.head;
        if (d.kind != PlayoutKind::kSilence) {  // where it was last heard from
          s.head_space = glm::inverse(listener.orientation) * (where - listener.position);
        }
      }
      if (d.kind != PlayoutKind::kSilence || s.spatial.primed) {
        m.mixer.addSpeaker(listener, where, m.mono, s.spatial);
      }
      {
        std::lock_guard lock(m.mutex);
        Impl::LevelHistory& h = m.levels[it->first];
        h.rms[h.next] = level;
        h.next = (h.next + 1) % h.rms.size();
      }
      if (tick_time - s.last_packet > kForgetSpeakerS && !s.playout.buffer().playing()) {
        std::lock_guard lock(m.mutex);
        m.levels.erase(it->first);
        addTotals(s.playout, m.report);
        m.report.heard.push_back(speakerReport(it->first, s.playout, s.head_space));
        it = m.speakers.erase(it);
        continue;
      }
      ++it;
    }
    m.mixer.finishBlock(m.stereo);
    if (m.options.playback) {
      if (!m.options.audio_out.empty()) {
        m.output.insert(m.output.end(), m.stereo.begin(), m.stereo.end());
      } else if (m.device_out) {
        m.device->writeFrame(m.stereo);
        for (int i = 0; i < kVoiceFrameSamples; ++i) {
          m.played[static_cast<std::size_t>(i)] =
              0.5f * (m.stereo[2 * static_cast<std::size_t>(i)] +
                      m.stereo[2 * static_cast<std::size_t>(i) + 1]);
        }
        // Lip sync: what the speakers play now left the mixer this many ticks ago.
        const double queued = m.device->playbackLatencySeconds();
        std::lock_guard lock(m.mutex);
        m.level_lag = std::clamp(static_cast<int>(queued / kFrameS + 0.5), 0, 7);
      }
    }

    {
      std::lock_guard lock(m.mutex);
      VoiceReport& r = m.report;
      ++r.ticks;
      if (late > 0.010) ++r.late_ticks;
      if (have_frame) ++r.frames_captured;
      m.counters = counters;
    }
  }
}

Status VoiceEngine::stop() {
  if (stopped_) return {};
  stopped_ = true;
  stop_ = true;
  if (thread_.joinable()) thread_.join();
  Impl& m = *impl_;
  // What each speaker's buffer did, into the report.
  {
    std::lock_guard lock(m.mutex);
    for (auto& [id, s] : m.speakers) {
      addTotals(s->playout, m.report);
      m.report.heard.push_back(speakerReport(id, s->playout, s->head_space));
    }
    m.speakers.clear();
    m.device.reset();
  }
  if (!m.options.audio_out.empty() && m.options.playback) {
    AudioClip clip;
    clip.channels = 2;
    clip.samples = std::move(m.output);
    {
      std::lock_guard lock(m.mutex);
      m.report.seconds_written = static_cast<double>(clip.frames()) / kVoiceSampleRate;
    }
    if (Status st = writeWavFile(m.options.audio_out, clip); !st) return st;
    std::string csv = "wav_time_s,member,opening\n";
    {
      std::lock_guard lock(m.mutex);
      csv.reserve(csv.size() + 32 * m.mouth.size());
      for (const Impl::MouthSample& s : m.mouth) {
        csv += fmt::format("{:.4f},{},{:.4f}\n", s.wav_time, s.id, s.opening);
      }
    }
    if (Status st = writeFileText(jawTimelinePath(m.options.audio_out), csv); !st) return st;
  }
  return {};
}

VoiceReport VoiceEngine::report() const {
  const Impl& m = *impl_;
  std::lock_guard lock(m.mutex);
  VoiceReport r = m.report;
  r.frames_sent = m.counters.sent;
  r.bytes_sent = m.counters.bytes_sent;
  r.frames_received = m.counters.received;
  r.bytes_received = m.counters.bytes_received;
  r.frames_rejected = m.counters.rejected;
  r.speakers = static_cast<int>(m.report.heard.size() + m.speakers.size());
  r.mouth_to_ear_ms = m.latency_ms;
  r.mouth_samples = m.mouth.size();
  for (const auto& [id, s] : m.speakers) {
    addTotals(s->playout, r);
    r.heard.push_back(speakerReport(id, s->playout, s->head_space));
  }
  std::sort(r.heard.begin(), r.heard.end(),
            [](const SpeakerReport& a, const SpeakerReport& b) { return a.id < b.id; });
  if (r.frames_sent > 0) {
    const double seconds = static_cast<double>(r.frames_sent) * kFrameS;
    r.sent_kbps = 8.0 * static_cast<double>(r.bytes_sent) / seconds / 1e3;
    r.payload_kbps = 8.0 * static_cast<double>(r.payload_bytes_sent) / seconds / 1e3;
  }
  return r;
}

std::string VoiceEngine::summary() const {
  const VoiceReport r = report();
  std::string line = fmt::format(
      "voice: sent {} frames ({:.1f} kbit/s of datagrams while speaking, Opus {:.1f}), "
      "received {}",
      r.frames_sent, r.sent_kbps, r.payload_kbps, r.frames_received);
  if (!r.mouth_to_ear_ms.empty()) {
    line +=
        fmt::format("; mouth to ear p50 {:.1f} ms, p99 {:.1f} ms",
                    voicePercentile(r.mouth_to_ear_ms, 50), voicePercentile(r.mouth_to_ear_ms, 99));
  }
  line += fmt::format("; frames decoded {}, FEC {}, concealed {}, late {}", r.decoded, r.fec,
                      r.concealed, r.late);
  if (r.seconds_written > 0.0) {
    line += fmt::format("; wrote {:.1f} s to {}", r.seconds_written, impl_->options.audio_out);
  }
  return line;
}

std::string VoiceEngine::json() const {
  const VoiceReport r = report();
  // The jaw timeline's file (a JSON string) and rows (noteMouth), or null without audio_out.
  std::string jaw = "null";
  if (impl_->options.playback && !impl_->options.audio_out.empty()) {
    std::string path;
    for (const char c : jawTimelinePath(impl_->options.audio_out)) {
      if (c == '"' || c == '\\') path += '\\';
      if (static_cast<unsigned char>(c) >= 0x20) path += c;
    }
    jaw = fmt::format(R"({{"csv": "{}", "rows": {}}})", path, r.mouth_samples);
  }
  std::string speakers;
  for (const SpeakerReport& h : r.heard) {
    if (!speakers.empty()) speakers += ", ";
    speakers += fmt::format(
        "{{\"id\": {}, \"head_space_m\": [{:.3f}, {:.3f}, {:.3f}], \"decoded\": {}, \"fec\": {}, "
        "\"concealed\": {}, \"late\": {}, \"jitter_delay_ms\": {}}}",
        h.id, h.head_space.x, h.head_space.y, h.head_space.z, h.decoded, h.fec, h.concealed, h.late,
        h.target_delay_ms);
  }
  return fmt::format(
      "{{\"frames_captured\": {}, \"frames_sent\": {}, \"bytes_sent\": {}, \"sent_kbps\": {:.2f}, "
      "\"frames_received\": {}, \"bytes_received\": {}, \"frames_rejected\": {}, "
      "\"decoded\": {}, \"fec\": {}, \"concealed\": {}, \"late\": {}, \"dropped\": {}, "
      "\"inserted\": {}, \"decode_errors\": {}, \"ticks\": {}, \"late_ticks\": {}, "
      "\"mouth_to_ear_ms\": {{\"count\": {}, \"p50\": {:.2f}, \"p99\": {:.2f}, \"max\": {:.2f}}}, "
      "\"seconds_written\": {:.3f}, \"payload_kbps\": {:.2f}, \"jaw_timeline\": {}, "
      "\"speakers\": [{}]}}",
      r.frames_captured, r.frames_sent, r.bytes_sent, r.sent_kbps, r.frames_received,
      r.bytes_received, r.frames_rejected, r.decoded, r.fec, r.concealed, r.late, r.dropped,
      r.inserted, r.decode_errors, r.ticks, r.late_ticks, r.mouth_to_ear_ms.size(),
      voicePercentile(r.mouth_to_ear_ms, 50), voicePercentile(r.mouth_to_ear_ms, 99),
      voicePercentile(r.mouth_to_ear_ms, 100), r.seconds_written, r.payload_kbps, jaw, speakers);
}

}  // namespace vistel
