// Acoustic echo cancellation through speexdsp's echo canceller (an MDF adaptive filter in
// the frequency domain): what the speakers play reaches the microphone through the room
// and would be sent back to the people who said it. Each 20 ms tick the canceller is given
// the frame captured and the frame played at the same tick (mono), learns the path from
// speaker to microphone (the device's own latency and the room's echo, up to tail_ms) and
// subtracts its estimate of the echo from the capture.
//
// Only for a real microphone with real speakers: files in or out have no echo path.
// Samples are 48 kHz mono floats in [-1, 1] (int16 inside speexdsp). Each tick is filtered
// as two 10 ms blocks: the filter adapts per block, and 10 ms blocks converged about 4 dB
// further than 20 ms ones in the test's first seconds. speexdsp also high-passes the
// capture (a DC notch, about 140 Hz at 48 kHz). Cost: per block, a frequency-domain filter
// of tail_ms / 10 ms partitions; no allocation after create().
#pragma once

#include <cstdint>
#include <memory>
#include <span>
#include <vector>

#include "common/base/result.hpp"

struct SpeexEchoState_;

namespace vistel {

struct EchoCancellerSettings {
  int tail_ms = 120;  // the longest echo path learnt (device latency plus the room's echo)
};

class EchoCanceller {
 public:
  // Errors: tail_ms outside 20..1000, speexdsp failure.
  static Result<EchoCanceller> create(const EchoCancellerSettings& settings = {});

  // Removes the echo of `played` (the frame sent to the speakers this tick, mono,
  // kVoiceFrameSamples) from `captured` (the microphone's frame of the same tick), in place.
  void cancel(std::span<float> captured, std::span<const float> played);

  // Forgets the learnt path (e.g. after the devices changed).
  void reset();

 private:
  EchoCanceller() = default;  // through create() only

  struct Deleter {
    void operator()(SpeexEchoState_* state) const;
  };
  std::unique_ptr<SpeexEchoState_, Deleter> state_;
  std::vector<std::int16_t> captured_, played_, out_;  // int16 frames for speexdsp
};

}  // namespace vistel
