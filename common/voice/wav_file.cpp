// WAV files through libsndfile, resampled to 48 kHz through speexdsp's resampler.
#include "common/voice/wav_file.hpp"

#include <algorithm>
#include <cstdio>
#include <memory>

#include <sndfile.h>
#include <speex/speex_resampler.h>

#include "common/voice/voice_format.hpp"

namespace vistel {
namespace {

struct SndfileCloser {
  void operator()(SNDFILE* file) const { sf_close(file); }
};
struct ResamplerDeleter {
  void operator()(SpeexResamplerState* state) const { speex_resampler_destroy(state); }
};

}  // namespace

Result<std::vector<float>> resampleAudio(std::span<const float> interleaved, int channels,
                                         int from_rate, int to_rate) {
  if (from_rate < 1 || from_rate > 768000 || to_rate < 1 || to_rate > 768000 || channels < 1) {
    return fail("resampling: unsupported rate {} -> {} Hz ({} channels)", from_rate, to_rate,
                channels);
  }
  const size_t in_frames = interleaved.size() / channels;
  if (from_rate == to_rate) return std::vector<float>(interleaved.begin(), interleaved.end());
  int err = 0;
  std::unique_ptr<SpeexResamplerState, ResamplerDeleter> state(
      speex_resampler_init(channels, from_rate, to_rate, 8, &err));
  if (!state || err != RESAMPLER_ERR_SUCCESS) {
    return fail("resampling {} -> {} Hz: {}", from_rate, to_rate, speex_resampler_strerror(err));
  }
  // Drop the filter's leading zeros, then flush its tail with zeros so nothing is lost.
  speex_resampler_skip_zeros(state.get());
  const int latency_in = speex_resampler_get_input_latency(state.get());
  const size_t out_frames =
      static_cast<size_t>((static_cast<double>(in_frames) * to_rate) / from_rate + 0.5);
  std::vector<float> padded(interleaved.begin(), interleaved.end());
  padded.resize((in_frames + latency_in) * channels, 0.0f);
  std::vector<float> out((out_frames + 16) * channels, 0.0f);
  spx_uint32_t in_len = static_cast<spx_uint32_t>(in_frames + latency_in);
  spx_uint32_t out_len = static_cast<spx_uint32_t>(out_frames + 16);
  speex_resampler_process_interleaved_float(state.get(), padded.data(), &in_len, out.data(),
                                            &out_len);
  out.resize(std::min<size_t>(out_len, out_frames) * channels);
  return out;
}

Result<AudioClip> readAudioFile(const std::string& path) {
  SF_INFO info{};
  std::unique_ptr<SNDFILE, SndfileCloser> file(sf_open(path.c_str(), SFM_READ, &info));
  if (!file) return fail("{}: cannot read audio: {}", path, sf_strerror(nullptr));
  if (info.channels < 1 || info.channels > 2) {
    return fail("{}: {} channels; voice files must be mono or stereo", path, info.channels);
  }
  if (info.frames <= 0) return fail("{}: no audio frames", path);
  if (info.samplerate < 1000 || info.samplerate > 768000) {
    return fail("{}: unsupported sample rate {} Hz", path, info.samplerate);
  }
  // Read every frame as float (libsndfile normalises integer formats to [-1, 1]).
  std::vector<float> raw(static_cast<size_t>(info.frames) * info.channels);
  const sf_count_t got = sf_readf_float(file.get(), raw.data(), info.frames);
  if (got <= 0) return fail("{}: reading samples failed: {}", path, sf_strerror(file.get()));
  raw.resize(static_cast<size_t>(got) * info.channels);

  AudioClip clip;
  clip.channels = info.channels;
  if (info.samplerate == kVoiceSampleRate) {
    clip.samples = std::move(raw);
    return clip;
  }
  auto resampled = resampleAudio(raw, info.channels, info.samplerate, kVoiceSampleRate);
  if (!resampled) return withContext(path, resampled.error());
  clip.samples = std::move(*resampled);
  return clip;
}

Status writeWavFile(const std::string& path, const AudioClip& clip) {
  if (clip.channels < 1 || clip.channels > 2) {
    return fail("{}: cannot write {} channels (mono or stereo only)", path, clip.channels);
  }
  const std::string temp = path + ".tmp";
  SF_INFO info{};
  info.samplerate = kVoiceSampleRate;
  info.channels = clip.channels;
  info.format = SF_FORMAT_WAV | SF_FORMAT_PCM_16;
  {
    std::unique_ptr<SNDFILE, SndfileCloser> file(sf_open(temp.c_str(), SFM_WRITE, &info));
    if (!file) return fail("{}: cannot create: {}", path, sf_strerror(nullptr));
    // Clip so that libsndfile's float to int16 conversion never wraps.
    sf_command(file.get(), SFC_SET_CLIPPING, nullptr, SF_TRUE);
    const sf_count_t frames = static_cast<sf_count_t>(clip.frames());
    if (sf_writef_float(file.get(), clip.samples.data(), frames) != frames) {
      std::remove(temp.c_str());
      return fail("{}: writing samples failed: {}", path, sf_strerror(file.get()));
    }
  }
  if (std::rename(temp.c_str(), path.c_str()) != 0) {
    std::remove(temp.c_str());
    return fail("{}: cannot rename the temporary file into place", path);
  }
  return {};
}

std::vector<float> monoMix(const AudioClip& clip) {
  if (clip.channels == 1) return clip.samples;
  std::vector<float> mono(clip.frames());
  for (size_t i = 0; i < mono.size(); ++i) {
    float sum = 0.0f;
    for (int c = 0; c < clip.channels; ++c) sum += clip.samples[i * clip.channels + c];
    mono[i] = sum / static_cast<float>(clip.channels);
  }
  return mono;
}

}  // namespace vistel
