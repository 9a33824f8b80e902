// Correlation after alignment, for tests and benchmarks of the voice pipeline.
#include "common/voice/audio_compare.hpp"

#include <algorithm>
#include <cmath>

#include "common/voice/voice_format.hpp"

namespace vistel {

double correlationAtLag(std::span<const float> a, std::span<const float> b, int lag) {
  double ab = 0.0, aa = 0.0, bb = 0.0;
  for (size_t i = 0; i < a.size(); ++i) {
    const std::ptrdiff_t j = static_cast<std::ptrdiff_t>(i) + lag;
    if (j < 0) continue;
    if (j >= static_cast<std::ptrdiff_t>(b.size())) break;
    ab += static_cast<double>(a[i]) * b[static_cast<size_t>(j)];
    aa += static_cast<double>(a[i]) * a[i];
    bb += static_cast<double>(b[static_cast<size_t>(j)]) * b[static_cast<size_t>(j)];
  }
  return aa > 0.0 && bb > 0.0 ? ab / std::sqrt(aa * bb) : 0.0;
}

AlignedCorrelation alignedCorrelation(std::span<const float> reference,
                                      std::span<const float> heard, int max_lag) {
  // The loudest quarter second of the reference (5 ms steps) carries the search.
  const size_t window = std::min<size_t>(reference.size(), kVoiceSampleRate / 4);
  size_t best_start = 0;
  double best_energy = -1.0;
  for (size_t start = 0; start + window <= reference.size(); start += 240) {
    double energy = 0.0;
    for (size_t i = start; i < start + window; i += 4) energy += reference[i] * reference[i];
    if (energy > best_energy) {
      best_energy = energy;
      best_start = start;
    }
  }
  const auto segment = reference.subspan(best_start, window);
  AlignedCorrelation result;
  double best = -2.0;
  for (int lag = 0; lag <= max_lag; ++lag) {
    const std::ptrdiff_t offset = static_cast<std::ptrdiff_t>(best_start) + lag;
    if (offset >= static_cast<std::ptrdiff_t>(heard.size())) break;
    const double c = correlationAtLag(segment, heard.subspan(static_cast<size_t>(offset)), 0);
    if (c > best) {
      best = c;
      result.lag = lag;
    }
  }
  result.correlation = correlationAtLag(reference, heard, result.lag);
  return result;
}

double levelDbfs(std::span<const float> samples) {
  double energy = 0.0;
  for (float x : samples) energy += static_cast<double>(x) * x;
  if (samples.empty() || energy <= 0.0) return -120.0;
  return std::max(-120.0, 10.0 * std::log10(energy / static_cast<double>(samples.size())));
}

std::ptrdiff_t soundOnset(std::span<const float> samples, float threshold) {
  constexpr std::size_t kWindow = 480;
  for (std::size_t i = 0; i + kWindow <= samples.size(); i += kWindow / 2) {
    double sum = 0.0;
    for (std::size_t k = 0; k < kWindow; ++k) {
      sum += static_cast<double>(samples[i + k]) * samples[i + k];
    }
    if (std::sqrt(sum / kWindow) > threshold) return static_cast<std::ptrdiff_t>(i);
  }
  return -1;
}

}  // namespace vistel
