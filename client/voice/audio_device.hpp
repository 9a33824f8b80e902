// The default audio devices through PortAudio: a microphone (mono) and speakers (stereo),
// 48 kHz, in 20 ms frames (common/voice/voice_format.hpp).
//
// PortAudio calls back on its own thread; each direction has a small ring between that
// callback and the voice engine's 20 ms tick (100 ms of capture, 60 ms of playback).
// Capture: the engine takes one frame per tick when one is there (readFrame); an overfull
// ring drops its oldest samples. Playback: the engine gives one stereo frame per tick
// (writeFrame); the callback plays silence when the ring runs dry, and samples past the
// ring's size push out the oldest, so a device clock that runs apart from the engine's
// costs a click, not a growing delay (at most 60 ms queued, plus PortAudio's own latency).
// open() fails, saying why, when PortAudio has no default device for a direction asked
// for (headless machines, containers).
#pragma once

#include <memory>
#include <mutex>
#include <span>
#include <string>
#include <vector>

#include "common/base/result.hpp"

namespace vistel {

class AudioDevice {
 public:
  // Opens the default input (capture) and/or output (playback) device.
  static Result<std::unique_ptr<AudioDevice>> open(bool capture, bool playback);
  ~AudioDevice();
  AudioDevice(const AudioDevice&) = delete;
  AudioDevice& operator=(const AudioDevice&) = delete;

  // One captured mono frame (kVoiceFrameSamples) into out; false when less is buffered.
  bool readFrame(std::span<float> out);
  // One stereo frame (2 * kVoiceFrameSamples, interleaved) to play.
  void writeFrame(std::span<const float> stereo);
  // Seconds from writeFrame to the speakers: what the ring holds plus PortAudio's output
  // latency (0 without playback).
  double playbackLatencySeconds();
  // "input: NAME, output: NAME".
  const std::string& description() const { return description_; }

  // The PortAudio callbacks' side (public for the C callbacks only).
  struct Ring {
    std::mutex mutex;
    std::vector<float> samples;  // capacity: a ring
    std::size_t head = 0;        // oldest sample
    std::size_t count = 0;
    void push(const float* data, std::size_t n);
    std::size_t pop(float* data, std::size_t n);  // returns how many were there
  };

 private:
  AudioDevice() = default;
  void* input_ = nullptr;   // PaStream*
  void* output_ = nullptr;  // PaStream*
  bool initialized_ = false;
  Ring capture_;
  Ring playback_;
  std::string description_;
};

}  // namespace vistel
