// WAV files: round trip, resampling to 48 kHz, and errors that name the file.
#include "common/voice/wav_file.hpp"

#include <cmath>
#include <fstream>

#include <gtest/gtest.h>
#include <sndfile.h>

#include "common/voice/audio_compare.hpp"
#include "common/voice/voice_format.hpp"
#include "tests/support/test_support.hpp"

namespace vistel {
namespace {

std::vector<float> sine(double hz, double seconds, int rate, float amplitude) {
  std::vector<float> out(static_cast<size_t>(seconds * rate));
  for (size_t i = 0; i < out.size(); ++i) {
    out[i] = amplitude * static_cast<float>(std::sin(6.283185307179586 * hz * i / rate));
  }
  return out;
}

TEST(WavFile, StereoRoundTripKeepsSamplesWithin16BitQuantisation) {
  AudioClip clip;
  clip.channels = 2;
  const auto left = sine(440.0, 0.5, kVoiceSampleRate, 0.5f);
  const auto right = sine(660.0, 0.5, kVoiceSampleRate, 0.25f);
  for (size_t i = 0; i < left.size(); ++i) {
    clip.samples.push_back(left[i]);
    clip.samples.push_back(right[i]);
  }
  const std::string path = test::scratchDir() + "/stereo.wav";
  ASSERT_TRUE(writeWavFile(path, clip).ok());
  auto read = readAudioFile(path);
  ASSERT_TRUE(read.ok()) << read.error().message;
  ASSERT_EQ(read->channels, 2);
  ASSERT_EQ(read->samples.size(), clip.samples.size());
  float worst = 0.0f;
  for (size_t i = 0; i < clip.samples.size(); ++i) {
    worst = std::max(worst, std::abs(read->samples[i] - clip.samples[i]));
  }
  EXPECT_LT(worst, 1.5f / 32768.0f);
  const auto mono = monoMix(*read);
  ASSERT_EQ(mono.size(), left.size());
  EXPECT_NEAR(mono[100], 0.5f * (left[100] + right[100]), 1e-4f);
}

TEST(WavFile, WritingClipsInsteadOfWrapping) {
  AudioClip clip;
  clip.samples = {0.0f, 1.5f, -1.5f, 0.25f};
  const std::string path = test::scratchDir() + "/loud.wav";
  ASSERT_TRUE(writeWavFile(path, clip).ok());
  auto read = readAudioFile(path);
  ASSERT_TRUE(read.ok());
  EXPECT_GT(read->samples[1], 0.99f);
  EXPECT_LT(read->samples[2], -0.99f);
}

TEST(WavFile, A16kHzFileIsResampledTo48kHz) {
  // Write a 16 kHz mono 440 Hz tone with libsndfile directly.
  const std::string path = test::scratchDir() + "/tone16k.wav";
  const auto tone16 = sine(440.0, 1.0, 16000, 0.5f);
  SF_INFO info{};
  info.samplerate = 16000;
  info.channels = 1;
  info.format = SF_FORMAT_WAV | SF_FORMAT_FLOAT;
  SNDFILE* file = sf_open(path.c_str(), SFM_WRITE, &info);
  ASSERT_NE(file, nullptr);
  ASSERT_EQ(sf_writef_float(file, tone16.data(), static_cast<sf_count_t>(tone16.size())),
            static_cast<sf_count_t>(tone16.size()));
  sf_close(file);

  auto read = readAudioFile(path);
  ASSERT_TRUE(read.ok()) << read.error().message;
  EXPECT_EQ(read->channels, 1);
  EXPECT_NEAR(static_cast<double>(read->samples.size()), 48000.0, 2.0);
  // Same tone, same phase (latency compensated), away from the edges.
  const auto tone48 = sine(440.0, 1.0, kVoiceSampleRate, 0.5f);
  const std::span<const float> inner_ref(tone48.data() + 2000, 40000);
  const std::span<const float> inner_read(read->samples.data() + 2000, 40000);
  EXPECT_GT(correlationAtLag(inner_ref, inner_read, 0), 0.999);
}

TEST(WavFile, ErrorsNameTheFile) {
  auto missing = readAudioFile("no/such/voice.wav");
  ASSERT_FALSE(missing.ok());
  EXPECT_NE(missing.error().message.find("no/such/voice.wav"), std::string::npos);

  const std::string text = test::scratchDir() + "/not_audio.wav";
  std::ofstream(text) << "this is not a RIFF file at all";
  auto garbage = readAudioFile(text);
  ASSERT_FALSE(garbage.ok());
  EXPECT_NE(garbage.error().message.find("not_audio.wav"), std::string::npos);

  // Three channels: readable by libsndfile, refused by the voice pipeline.
  const std::string three = test::scratchDir() + "/three.wav";
  SF_INFO info{};
  info.samplerate = 48000;
  info.channels = 3;
  info.format = SF_FORMAT_WAV | SF_FORMAT_PCM_16;
  SNDFILE* file = sf_open(three.c_str(), SFM_WRITE, &info);
  ASSERT_NE(file, nullptr);
  const float frame[3] = {0.1f, 0.2f, 0.3f};
  sf_writef_float(file, frame, 1);
  sf_close(file);
  auto refused = readAudioFile(three);
  ASSERT_FALSE(refused.ok());
  EXPECT_NE(refused.error().message.find("three.wav"), std::string::npos);
  EXPECT_NE(refused.error().message.find("3 channels"), std::string::npos);

  AudioClip clip;
  EXPECT_FALSE(writeWavFile("no/such/folder/out.wav", clip).ok());
}

}  // namespace
}  // namespace vistel
