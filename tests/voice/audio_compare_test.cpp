// soundOnset: where a sound starts, to the half window.
#include "common/voice/audio_compare.hpp"

#include <cmath>
#include <vector>

#include <gtest/gtest.h>

namespace vistel {
namespace {

TEST(SoundOnset, FindsTheFirstLoudWindowAndNothingInSilence) {
  std::vector<float> samples(48000, 0.0f);
  EXPECT_EQ(soundOnset(samples, 0.01f), -1);

  // A 200 Hz tone at 0.1 full scale from sample 12000: the first window holding enough of it
  // starts within one window before that.
  for (std::size_t i = 12000; i < samples.size(); ++i) {
    samples[i] = 0.1f * static_cast<float>(std::sin(2.0 * M_PI * 200.0 * i / 48000.0));
  }
  const std::ptrdiff_t at = soundOnset(samples, 0.01f);
  EXPECT_GE(at, 12000 - 480);
  EXPECT_LE(at, 12000);
  EXPECT_EQ(soundOnset(samples, 0.2f), -1);                                      // never that loud
  EXPECT_EQ(soundOnset(std::span<const float>(samples.data(), 100), 0.0f), -1);  // < a window
}

}  // namespace
}  // namespace vistel
