// WAV (and any other libsndfile-readable) audio files for the voice pipeline.
//
// readAudioFile opens a mono or stereo file of any sample rate and sample format that
// libsndfile reads, and returns its samples as 48 kHz float in [-1, 1], interleaved when
// stereo; a file at another rate is resampled with speexdsp's resampler (quality 8, its
// input latency compensated so sample 0 stays at time 0). writeWavFile writes 16-bit PCM
// WAV at 48 kHz (samples clipped to [-1, 1]). Errors name the file and say why (missing,
// not audio, more than two channels, empty). Cost: one pass over the file, allocation of
// the result only.
#pragma once

#include <span>
#include <string>
#include <vector>

#include "common/base/result.hpp"

namespace vistel {

struct AudioClip {
  int channels = 1;            // 1 (mono) or 2 (stereo, interleaved L R)
  std::vector<float> samples;  // 48 kHz, frames * channels, in [-1, 1]

  size_t frames() const { return channels > 0 ? samples.size() / channels : 0; }
};

// Reads a mono or stereo file and resamples it to 48 kHz when its rate differs.
Result<AudioClip> readAudioFile(const std::string& path);

// Writes clip as 16-bit PCM WAV at 48 kHz (atomically: a temporary file then rename).
Status writeWavFile(const std::string& path, const AudioClip& clip);

// The mono mix (mean of the channels) of a clip.
std::vector<float> monoMix(const AudioClip& clip);

// Resamples interleaved float audio from from_rate to to_rate with speexdsp (quality 8),
// compensating its latency so that the output starts at the same instant as the input.
// Returns about frames * to_rate / from_rate frames. Errors: a rate outside 1..768000 Hz.
Result<std::vector<float>> resampleAudio(std::span<const float> interleaved, int channels,
                                         int from_rate, int to_rate);

}  // namespace vistel
