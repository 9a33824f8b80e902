#include "client/voice/audio_device.hpp"

#include <fcntl.h>
#include <unistd.h>

#include <algorithm>
#include <cstdio>

#include <fmt/format.h>
#include <fmt/ranges.h>
#include <portaudio.h>

#include "common/voice/voice_format.hpp"

namespace vistel {
namespace {

constexpr std::size_t kCaptureRingFrames = 5;   // 100 ms of microphone
constexpr std::size_t kPlaybackRingFrames = 3;  // at most 60 ms queued before the speakers

int captureCallback(const void* input, void*, unsigned long frames, const PaStreamCallbackTimeInfo*,
                    PaStreamCallbackFlags, void* user) {
  auto* ring = static_cast<AudioDevice::Ring*>(user);
  if (input != nullptr) ring->push(static_cast<const float*>(input), frames);
  return paContinue;
}

int playbackCallback(const void*, void* output, unsigned long frames,
                     const PaStreamCallbackTimeInfo*, PaStreamCallbackFlags, void* user) {
  auto* ring = static_cast<AudioDevice::Ring*>(user);
  auto* out = static_cast<float*>(output);
  const std::size_t want = 2 * static_cast<std::size_t>(frames);
  const std::size_t got = ring->pop(out, want);
  std::fill(out + got, out + want, 0.0f);
  return paContinue;
}

// PortAudio's backends (ALSA, JACK) print pages of complaints to stderr while probing a
// machine without sound hardware: they are silenced while devices are opened (the engine
// says in one line what it found).
class QuietStderr {
 public:
  QuietStderr() {
    std::fflush(stderr);
    saved_ = ::dup(STDERR_FILENO);
    const int null = ::open("/dev/null", O_WRONLY);
    if (saved_ >= 0 && null >= 0) ::dup2(null, STDERR_FILENO);
    if (null >= 0) ::close(null);
  }
  ~QuietStderr() {
    std::fflush(stderr);
    if (saved_ >= 0) {
      ::dup2(saved_, STDERR_FILENO);
      ::close(saved_);
    }
  }
  QuietStderr(const QuietStderr&) = delete;
  QuietStderr& operator=(const QuietStderr&) = delete;

 private:
  int saved_ = -1;
};

std::string deviceName(PaDeviceIndex index) {
  const PaDeviceInfo* info = Pa_GetDeviceInfo(index);
  return info != nullptr && info->name != nullptr ? info->name : "?";
}

}  // namespace

void AudioDevice::Ring::push(const float* data, std::size_t n) {
  std::lock_guard lock(mutex);
  const std::size_t size = samples.size();
  for (std::size_t i = 0; i < n; ++i) {
    if (count == size) {  // full: the oldest goes
      head = (head + 1) % size;
      --count;
    }
    samples[(head + count) % size] = data[i];
    ++count;
  }
}

std::size_t AudioDevice::Ring::pop(float* data, std::size_t n) {
  std::lock_guard lock(mutex);
  const std::size_t size = samples.size();
  const std::size_t take = std::min(n, count);
  for (std::size_t i = 0; i < take; ++i) data[i] = samples[(head + i) % size];
  head = (head + take) % size;
  count -= take;
  return take;
}

Result<std::unique_ptr<AudioDevice>> AudioDevice::open(bool capture, bool playback) {
  QuietStderr quiet;
  std::unique_ptr<AudioDevice> d(new AudioDevice());
  if (const PaError e = Pa_Initialize(); e != paNoError) {
    return fail("audio: PortAudio: {}", Pa_GetErrorText(e));
  }
  d->initialized_ = true;
  std::vector<std::string> parts;
  if (capture) {
    const PaDeviceIndex index = Pa_GetDefaultInputDevice();
    if (index == paNoDevice) return fail("audio: no input device (microphone)");
    d->capture_.samples.resize(kCaptureRingFrames * kVoiceFrameSamples);
    PaStream* stream = nullptr;
    PaError e = Pa_OpenDefaultStream(&stream, 1, 0, paFloat32, kVoiceSampleRate, kVoiceFrameSamples,
                                     captureCallback, &d->capture_);
    if (e == paNoError) e = Pa_StartStream(stream);
    if (e != paNoError) {
      if (stream != nullptr) Pa_CloseStream(stream);
      return fail("audio: cannot capture from '{}': {}", deviceName(index), Pa_GetErrorText(e));
    }
    d->input_ = stream;
    parts.push_back("input: " + deviceName(index));
  }
  if (playback) {
    const PaDeviceIndex index = Pa_GetDefaultOutputDevice();
    if (index == paNoDevice) return fail("audio: no output device (speakers)");
    d->playback_.samples.resize(2 * kPlaybackRingFrames * kVoiceFrameSamples);
    PaStream* stream = nullptr;
    PaError e = Pa_OpenDefaultStream(&stream, 0, 2, paFloat32, kVoiceSampleRate, kVoiceFrameSamples,
                                     playbackCallback, &d->playback_);
    if (e == paNoError) e = Pa_StartStream(stream);
    if (e != paNoError) {
      if (stream != nullptr) Pa_CloseStream(stream);
      return fail("audio: cannot play on '{}': {}", deviceName(index), Pa_GetErrorText(e));
    }
    d->output_ = stream;
    parts.push_back("output: " + deviceName(index));
  }
  d->description_ = fmt::format("{}", fmt::join(parts, ", "));
  return d;
}

AudioDevice::~AudioDevice() {
  QuietStderr quiet;
  for (void* s : {input_, output_}) {
    if (s == nullptr) continue;
    Pa_StopStream(static_cast<PaStream*>(s));
    Pa_CloseStream(static_cast<PaStream*>(s));
  }
  if (initialized_) Pa_Terminate();
}

bool AudioDevice::readFrame(std::span<float> out) {
  {
    std::lock_guard lock(capture_.mutex);
    if (capture_.count < out.size()) return false;
  }
  return capture_.pop(out.data(), out.size()) == out.size();
}

double AudioDevice::playbackLatencySeconds() {
  if (output_ == nullptr) return 0.0;
  std::size_t queued = 0;
  {
    std::lock_guard lock(playback_.mutex);
    queued = playback_.count / 2;
  }
  const PaStreamInfo* info = Pa_GetStreamInfo(static_cast<PaStream*>(output_));
  return static_cast<double>(queued) / kVoiceSampleRate +
         (info != nullptr ? info->outputLatency : 0.0);
}

void AudioDevice::writeFrame(std::span<const float> stereo) {
  playback_.push(stereo.data(), stereo.size());
}

}  // namespace vistel
