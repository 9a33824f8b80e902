// Comparing what was heard with what was said: normalised correlation after alignment.
//
// alignedCorrelation finds the lag in [0, max_lag] samples by which `heard` trails
// `reference` (searching on the loudest quarter second of the reference), then returns the
// normalised correlation (Pearson, without mean removal) of reference[i] with
// heard[i + lag] over their overlap. Cost: O(12000 * max_lag) for the search plus O(n).
#pragma once

#include <cstddef>
#include <span>

namespace vistel {

struct AlignedCorrelation {
  double correlation = 0.0;  // in [-1, 1]; 0 when either side is silent
  int lag = 0;               // samples: heard[i + lag] matches reference[i]
};

AlignedCorrelation alignedCorrelation(std::span<const float> reference,
                                      std::span<const float> heard, int max_lag);

// Normalised correlation of a with b at the given lag (b[i + lag] against a[i]).
double correlationAtLag(std::span<const float> a, std::span<const float> b, int lag);

// RMS level of a span in dB full scale (-120 for silence).
double levelDbfs(std::span<const float> samples);

// Where sound starts: the first sample of the first 10 ms window (480 samples at 48 kHz,
// stepped by half a window) whose RMS exceeds `threshold` (linear full scale), or -1.
std::ptrdiff_t soundOnset(std::span<const float> samples, float threshold);

}  // namespace vistel
