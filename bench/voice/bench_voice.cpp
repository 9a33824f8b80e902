// bench_voice: the voice pipeline's latency and CPU cost (issue 22, "Measures").
//
// MouthToEar/loopback and MouthToEar/loss10_jitter50 run 30 s of synthetic speech
// (common/voice/speech_synth, with pauses between phrases) through the whole path in
// simulated time (common/voice/voice_link_sim): capture in 20 ms frames -> voice activity
// (speexdsp) -> Opus at the default settings (16 kbit/s, wideband, FEC) -> a simulated
// network -> the playout buffer and decoder -> spatialiser and mixer -> a 20 ms device
// buffer. Loopback: no loss, no delay;
// the other: 10% random loss and a delay uniform in [0, 50 ms] (fixed seed). Latency of a
// frame = when its samples leave the device - when they were captured, including the 20 ms
// of capture framing and the 20 ms device buffer. Counters: p50_ms, p99_ms, max_ms,
// target_ms (the p99 target: 80 and 150), correlation (what was heard against what
// was said, after alignment, the worst of the runs; VAD and denoising included), kbps
// (Opus payload upstream while speaking), and per run: sent packets, fec and concealed
// frames. Each runs eight times with the receiver's tick at eight phases against the
// sender's frames, the latencies pooled. The wall time of these two is the simulation's,
// not a latency.
//
// Encode, Decode/N, SpatialiseMix/N and ReceiveTick/N: the CPU time of one 20 ms frame:
// one encoder; N speakers' decoders; N speakers spatialised (moving) and mixed with the
// limiter; and the whole receive tick for N talking speakers (playout buffer, decode,
// spatialise, mix). A frame must cost well under its 20 ms: compare the time column
// (microseconds per frame) with 20,000. Run from the project root.
#include <algorithm>
#include <cmath>
#include <vector>

#include <benchmark/benchmark.h>

#include "common/voice/audio_compare.hpp"
#include "common/voice/mixer.hpp"
#include "common/voice/opus_voice.hpp"
#include "common/voice/speaker_playout.hpp"
#include "common/voice/speech_synth.hpp"
#include "common/voice/voice_link_sim.hpp"

namespace vistel {
namespace {

void mouthToEar(benchmark::State& state, double loss, double jitter_s, double target_ms) {
  const auto speech = synthesizeSpeech(30.0, {.seed = 21});
  VoiceLinkSettings settings;
  settings.use_vad = true;
  settings.loss = loss;
  settings.jitter_s = jitter_s;
  settings.seed = 5;
  // Eight phases of the receiver's 20 ms tick against the sender's frames (a real pair
  // of sound cards has any phase): the latencies of all eight runs together.
  std::vector<double> latency_s;
  double worst_correlation = 1.0;
  int64_t packets_sent = 0, bytes_sent = 0, fec = 0, concealed = 0;
  for (auto _ : state) {
    for (int phase = 0; phase < 8; ++phase) {
      settings.pull_phase_samples = 60 + phase * kVoiceFrameSamples / 8;
      auto run = simulateVoiceLink(speech, settings);
      if (!run) {
        state.SkipWithError(run.error().message.c_str());
        return;
      }
      latency_s.insert(latency_s.end(), run->latency_s.begin(), run->latency_s.end());
      worst_correlation =
          std::min(worst_correlation, alignedCorrelation(speech, run->heard, 2000).correlation);
      packets_sent += run->packets_sent;
      bytes_sent += run->bytes_sent;
      fec += run->stats.fec;
      concealed += run->stats.concealed;
    }
  }
  const double speaking_s = 0.02 * static_cast<double>(packets_sent);
  state.counters["p50_ms"] = 1000.0 * quantile(latency_s, 0.50);
  state.counters["p99_ms"] = 1000.0 * quantile(latency_s, 0.99);
  state.counters["max_ms"] = 1000.0 * quantile(latency_s, 1.0);
  state.counters["target_ms"] = target_ms;
  state.counters["correlation"] = worst_correlation;
  state.counters["kbps"] =
      speaking_s > 0 ? 8.0 * static_cast<double>(bytes_sent) / speaking_s / 1000.0 : 0.0;
  state.counters["fec"] = static_cast<double>(fec) / 8.0;
  state.counters["concealed"] = static_cast<double>(concealed) / 8.0;
  state.counters["sent"] = static_cast<double>(packets_sent) / 8.0;
}

void BM_MouthToEarLoopback(benchmark::State& state) { mouthToEar(state, 0.0, 0.0, 80.0); }
void BM_MouthToEarLoss10Jitter50(benchmark::State& state) { mouthToEar(state, 0.10, 0.050, 150.0); }
BENCHMARK(BM_MouthToEarLoopback)
    ->Name("MouthToEar/loopback")
    ->Iterations(1)
    ->Unit(benchmark::kMillisecond);
BENCHMARK(BM_MouthToEarLoss10Jitter50)
    ->Name("MouthToEar/loss10_jitter50")
    ->Iterations(1)
    ->Unit(benchmark::kMillisecond);

// Encoded packets of continuous speech, for the decode benchmarks.
std::vector<std::vector<uint8_t>> encodeSpeech(const std::vector<float>& speech) {
  auto encoder = OpusVoiceEncoder::create({});
  std::vector<std::vector<uint8_t>> packets;
  std::vector<uint8_t> bytes(kVoiceMaxPacketBytes);
  for (size_t at = 0; at + kVoiceFrameSamples <= speech.size(); at += kVoiceFrameSamples) {
    auto size =
        encoder->encode(std::span<const float>(speech.data() + at, kVoiceFrameSamples), bytes);
    packets.emplace_back(bytes.begin(), bytes.begin() + static_cast<std::ptrdiff_t>(*size));
  }
  return packets;
}

void BM_Encode(benchmark::State& state) {
  const auto speech = synthesizeSpeech(5.0, {.pauses = false});
  auto encoder = OpusVoiceEncoder::create({});
  std::vector<uint8_t> bytes(kVoiceMaxPacketBytes);
  const size_t frames = speech.size() / kVoiceFrameSamples;
  size_t k = 0;
  for (auto _ : state) {
    auto size =
        encoder->encode(std::span<const float>(speech.data() + (k++ % frames) * kVoiceFrameSamples,
                                               kVoiceFrameSamples),
                        bytes);
    benchmark::DoNotOptimize(size);
  }
  state.SetItemsProcessed(state.iterations());
}
BENCHMARK(BM_Encode)->Name("Encode")->Unit(benchmark::kMicrosecond);

void BM_Decode(benchmark::State& state) {
  const int speakers = static_cast<int>(state.range(0));
  const auto packets = encodeSpeech(synthesizeSpeech(5.0, {.pauses = false}));
  std::vector<OpusVoiceDecoder> decoders;
  for (int s = 0; s < speakers; ++s) decoders.push_back(std::move(*OpusVoiceDecoder::create()));
  std::vector<float> out(kVoiceFrameSamples);
  size_t k = 0;
  for (auto _ : state) {
    for (int s = 0; s < speakers; ++s) {
      (void)decoders[s].decode(packets[(k + 37 * s) % packets.size()], out);
    }
    benchmark::DoNotOptimize(out.data());
    ++k;
  }
  state.SetItemsProcessed(state.iterations() * speakers);
}
BENCHMARK(BM_Decode)->Name("Decode")->Arg(1)->Arg(16)->Unit(benchmark::kMicrosecond);

// Speaker s walks on a circle around the listener, one turn every 10 s.
glm::vec3 speakerPosition(int s, size_t frame) {
  const float angle = 0.39f * static_cast<float>(s) + 0.0126f * static_cast<float>(frame);
  const float radius = 1.0f + 0.25f * static_cast<float>(s % 8);
  return {radius * std::sin(angle), 0.1f, radius * std::cos(angle)};
}

void BM_SpatialiseMix(benchmark::State& state) {
  const int speakers = static_cast<int>(state.range(0));
  const auto speech = synthesizeSpeech(2.0, {.pauses = false});
  const size_t frames = speech.size() / kVoiceFrameSamples;
  VoiceMixer mixer;
  std::vector<SpatialSourceState> states(static_cast<size_t>(speakers));
  std::vector<float> out(2 * kVoiceFrameSamples);
  const HeadPose listener;
  size_t k = 0;
  for (auto _ : state) {
    mixer.beginBlock();
    for (int s = 0; s < speakers; ++s) {
      const size_t frame = (k + 7 * static_cast<size_t>(s)) % frames;
      mixer.addSpeaker(
          listener, speakerPosition(s, k),
          std::span<const float>(speech.data() + frame * kVoiceFrameSamples, kVoiceFrameSamples),
          states[static_cast<size_t>(s)]);
    }
    mixer.finishBlock(out);
    benchmark::DoNotOptimize(out.data());
    ++k;
  }
  state.SetItemsProcessed(state.iterations() * speakers);
}
BENCHMARK(BM_SpatialiseMix)->Name("SpatialiseMix")->Arg(1)->Arg(16)->Unit(benchmark::kMicrosecond);

void BM_ReceiveTick(benchmark::State& state) {
  const int speakers = static_cast<int>(state.range(0));
  const auto packets = encodeSpeech(synthesizeSpeech(5.0, {.pauses = false}));
  std::vector<SpeakerPlayout> playouts;
  for (int s = 0; s < speakers; ++s) playouts.push_back(std::move(*SpeakerPlayout::create()));
  std::vector<SpatialSourceState> states(static_cast<size_t>(speakers));
  VoiceMixer mixer;
  std::vector<float> mono(kVoiceFrameSamples), out(2 * kVoiceFrameSamples);
  const HeadPose listener;
  int64_t k = 0;
  for (auto _ : state) {
    // Each speaker's packet k arrives just in time (the network's part is not timed).
    state.PauseTiming();
    for (int s = 0; s < speakers; ++s) {
      const auto& packet = packets[static_cast<size_t>(k + 37 * s) % packets.size()];
      playouts[static_cast<size_t>(s)].push(
          {static_cast<uint16_t>(k), static_cast<uint32_t>(k * kVoiceFrameSamples), packet},
          (k + 1) * kVoiceFrameSamples);
    }
    state.ResumeTiming();
    const int64_t now = (k + 1) * kVoiceFrameSamples + 300;
    mixer.beginBlock();
    for (int s = 0; s < speakers; ++s) {
      playouts[static_cast<size_t>(s)].pull(now, mono);
      mixer.addSpeaker(listener, speakerPosition(s, static_cast<size_t>(k)), mono,
                       states[static_cast<size_t>(s)]);
    }
    mixer.finishBlock(out);
    benchmark::DoNotOptimize(out.data());
    ++k;
  }
  state.SetItemsProcessed(state.iterations() * speakers);
}
BENCHMARK(BM_ReceiveTick)->Name("ReceiveTick")->Arg(1)->Arg(16)->Unit(benchmark::kMicrosecond);

}  // namespace
}  // namespace vistel

BENCHMARK_MAIN();
