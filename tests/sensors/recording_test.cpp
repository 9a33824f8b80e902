// .vrec recordings: round trip, truncated at every length, corrupted at every byte, and a
// writer process killed mid-stream: readers keep every record before the damage and say
// where and why they stopped.
#include <csignal>
#include <filesystem>
#include <thread>

#include <sys/wait.h>
#include <unistd.h>

#include <gtest/gtest.h>

#include "common/base/file.hpp"
#include "common/sensors/random.hpp"
#include "common/sensors/recording.hpp"
#include "tests/support/test_support.hpp"

namespace vistel {
namespace {

SensorFrame randomFrame(SimRandom& rng, std::uint64_t seq) {
  SensorFrame f;
  f.time = 0.01 * static_cast<double>(seq);
  f.sequence = seq;
  for (StationReading& s : f.stations) {
    s.valid = rng.uniform() > 0.1;
    s.status = rng.uniform() > 0.9 ? 'W' : ' ';
    s.time = f.time - 0.004;
    s.position = glm::vec3(static_cast<float>(rng.gaussian()), static_cast<float>(rng.gaussian()),
                           static_cast<float>(rng.gaussian()));
    s.orientation = glm::normalize(
        glm::quat(static_cast<float>(rng.gaussian()), static_cast<float>(rng.gaussian()),
                  static_cast<float>(rng.gaussian()), static_cast<float>(rng.gaussian())));
  }
  for (GloveReading& g : f.gloves) {
    g.valid = rng.uniform() > 0.5;
    g.time = f.time;
    for (float& a : g.angles) a = static_cast<float>(rng.uniform() * 1.5);
  }
  return f;
}

RecordingHeader sampleHeader() {
  RecordingHeader h;
  h.participant = "Ada";
  h.source = "fastrak /dev/ttyUSB0";
  h.stations = {{1, BodySite::kHead},
                {2, BodySite::kChest},
                {3, BodySite::kLeftWrist},
                {4, BodySite::kRightWrist}};
  h.gloves = {{Hand::kLeft, 18}, {Hand::kRight, 22}};
  CalibrationRecord c;
  c.start_time = 1.0;
  c.end_time = 1.5;
  c.pose = "standard";
  c.stations[1].valid = true;
  c.stations[1].position = glm::vec3(0.1f, 1.3f, 0.0f);
  h.calibration = c;
  h.config_text = "[tracker]\nport = \"/dev/ttyUSB0\"\n";
  return h;
}

void expectFrameEq(const SensorFrame& a, const SensorFrame& b) {
  EXPECT_EQ(a.time, b.time);
  EXPECT_EQ(a.sequence, b.sequence);
  for (int s = 0; s < kBodySiteCount; ++s) {
    EXPECT_EQ(a.stations[s].valid, b.stations[s].valid);
    EXPECT_EQ(a.stations[s].status, b.stations[s].status);
    EXPECT_EQ(a.stations[s].time, b.stations[s].time);
    EXPECT_EQ(a.stations[s].position, b.stations[s].position);
    EXPECT_EQ(a.stations[s].orientation, b.stations[s].orientation);
  }
  for (int h = 0; h < kHandCount; ++h) {
    EXPECT_EQ(a.gloves[h].valid, b.gloves[h].valid);
    EXPECT_EQ(a.gloves[h].angles, b.gloves[h].angles);
  }
}

// A recording in memory: file header, header record, 20 frames with a calibration record
// after the 8th. Also returns where each record ends.
std::vector<std::uint8_t> sampleBytes(std::vector<SensorFrame>& frames,
                                      std::vector<std::size_t>& ends, std::size_t& header_end) {
  SimRandom rng(21);
  std::vector<std::uint8_t> bytes;
  encodeRecordingFileHeader(bytes);
  encodeHeaderRecord(sampleHeader(), bytes);
  header_end = bytes.size();
  for (std::uint64_t i = 0; i < 20; ++i) {
    frames.push_back(randomFrame(rng, i));
    encodeFrameRecord(frames.back(), bytes);
    ends.push_back(bytes.size());
    if (i == 7) {
      CalibrationRecord c;
      c.start_time = 0.02;
      c.end_time = 0.07;
      c.pose = "clip frame 0";
      encodeCalibrationRecord(c, bytes);
      ends.push_back(bytes.size());
    }
  }
  return bytes;
}

TEST(Recording, RoundTripThroughTheWriter) {
  const std::string path = test::scratchDir() + "/take.vrec";
  SimRandom rng(3);
  std::vector<SensorFrame> frames;
  {
    auto writer = RecordingWriter::create(path, sampleHeader());
    ASSERT_TRUE(writer.ok()) << writer.error().message;
    for (std::uint64_t i = 0; i < 50; ++i) {
      frames.push_back(randomFrame(rng, i));
      ASSERT_TRUE((*writer)->append(frames.back()).ok());
      if (i == 24) {
        CalibrationRecord c;
        c.pose = "standard";
        c.start_time = 0.1;
        c.end_time = 0.2;
        c.gloves[0].valid = true;
        ASSERT_TRUE((*writer)->appendCalibration(c).ok());
      }
    }
    ASSERT_TRUE((*writer)->sync().ok());
    EXPECT_EQ((*writer)->framesWritten(), 50u);
  }
  auto rec = loadRecording(path);
  ASSERT_TRUE(rec.ok()) << rec.error().message;
  EXPECT_TRUE(rec->complete) << rec->stop_reason;
  const RecordingHeader want = sampleHeader();
  EXPECT_EQ(rec->header.participant, want.participant);
  EXPECT_EQ(rec->header.source, want.source);
  ASSERT_EQ(rec->header.stations.size(), 4u);
  EXPECT_EQ(rec->header.stations[2].station, 3);
  EXPECT_EQ(rec->header.stations[2].site, BodySite::kLeftWrist);
  ASSERT_EQ(rec->header.gloves.size(), 2u);
  EXPECT_EQ(rec->header.gloves[0].sensor_count, 18);
  ASSERT_TRUE(rec->header.calibration.has_value());
  EXPECT_EQ(rec->header.calibration->pose, "standard");
  EXPECT_EQ(rec->header.calibration->stations[1].position, want.calibration->stations[1].position);
  EXPECT_EQ(rec->header.config_text, want.config_text);
  ASSERT_EQ(rec->frames.size(), frames.size());
  for (std::size_t i = 0; i < frames.size(); ++i) expectFrameEq(frames[i], rec->frames[i]);
  ASSERT_EQ(rec->calibrations.size(), 1u);
  EXPECT_EQ(rec->calibration_after[0], 25u);
  EXPECT_TRUE(rec->calibrations[0].gloves[0].valid);

  // Replayed as a source.
  RecordingSource source(std::move(*rec), path);
  SensorFrame f;
  int n = 0;
  PollResult r;
  while ((r = source.poll(0.0, f)).isFrame())
    expectFrameEq(frames[static_cast<std::size_t>(n++)], f);
  EXPECT_EQ(n, 50);
  EXPECT_EQ(r.status, PollStatus::kEnd);
  EXPECT_FALSE(
      RecordingWriter::create(test::scratchDir() + "/no/such/dir/x.vrec", sampleHeader()).ok());
}

TEST(Recording, TruncatedAtEveryLength) {
  std::vector<SensorFrame> frames;
  std::vector<std::size_t> ends;
  std::size_t header_end = 0;
  const auto bytes = sampleBytes(frames, ends, header_end);
  for (std::size_t len = 0; len <= bytes.size(); ++len) {
    const auto rec = decodeRecording(std::span(bytes).first(len), "cut.vrec");
    if (len < header_end) {
      ASSERT_FALSE(rec.ok()) << len;
      EXPECT_NE(rec.error().message.find("cut.vrec"), std::string::npos);
      continue;
    }
    ASSERT_TRUE(rec.ok()) << len << ": " << rec.error().message;
    // Every record that ends within the cut is kept.
    std::size_t whole_records = 0;
    while (whole_records < ends.size() && ends[whole_records] <= len) ++whole_records;
    const std::size_t want_frames = whole_records > 8 ? whole_records - 1 : whole_records;
    EXPECT_EQ(rec->frames.size(), want_frames) << len;
    EXPECT_EQ(rec->calibrations.size(), whole_records > 8 ? 1u : 0u) << len;
    const std::size_t last_end = whole_records == 0 ? header_end : ends[whole_records - 1];
    EXPECT_EQ(rec->complete, len == last_end) << len;
    if (!rec->complete) {
      EXPECT_EQ(rec->stop_offset, last_end) << len;
      EXPECT_NE(rec->stop_reason.find("truncated"), std::string::npos) << rec->stop_reason;
    }
    for (std::size_t i = 0; i < rec->frames.size(); ++i) expectFrameEq(frames[i], rec->frames[i]);
  }
}

TEST(Recording, CorruptedAnywhereKeepsTheRecordsBefore) {
  std::vector<SensorFrame> frames;
  std::vector<std::size_t> ends;
  std::size_t header_end = 0;
  const auto bytes = sampleBytes(frames, ends, header_end);
  for (std::size_t at = 0; at < bytes.size(); ++at) {
    for (std::uint8_t flip : {std::uint8_t{0x01}, std::uint8_t{0x80}}) {
      std::vector<std::uint8_t> bad = bytes;
      bad[at] ^= flip;
      const auto rec = decodeRecording(bad, "bad.vrec");
      if (at < header_end) {
        EXPECT_FALSE(rec.ok()) << at;
        continue;
      }
      ASSERT_TRUE(rec.ok()) << at;
      std::size_t record = 0;  // the record the flipped byte is in
      while (ends[record] <= at) ++record;
      const std::size_t want_frames = record > 8 ? record - 1 : record;
      EXPECT_FALSE(rec->complete) << at;
      EXPECT_EQ(rec->frames.size(), want_frames) << at << ": " << rec->stop_reason;
      EXPECT_EQ(rec->stop_offset, record == 0 ? header_end : ends[record - 1]) << at;
      EXPECT_NE(rec->stop_reason.find("bad.vrec"), std::string::npos);
    }
  }
  // Not a recording at all.
  EXPECT_FALSE(decodeRecording(std::vector<std::uint8_t>(100, 'x'), "x").ok());
  std::vector<std::uint8_t> future = bytes;
  future[8] = 99;
  const auto rec = decodeRecording(future, "future.vrec");
  ASSERT_FALSE(rec.ok());
  EXPECT_NE(rec.error().message.find("version 99"), std::string::npos);
}

TEST(Recording, WriterKilledMidStreamLosesAtMostOneRecord) {
  const std::string path = test::scratchDir() + "/killed.vrec";
  const pid_t child = ::fork();
  ASSERT_GE(child, 0);
  if (child == 0) {
    // The child records as fast as it can until killed.
    auto writer = RecordingWriter::create(path, sampleHeader());
    if (!writer.ok()) ::_exit(2);
    SimRandom rng(1);
    for (std::uint64_t i = 0;; ++i) {
      if (!(*writer)->append(randomFrame(rng, i)).ok()) ::_exit(3);
    }
  }
  // Kill it once it has written a few hundred frames.
  for (int i = 0; i < 2000; ++i) {
    std::error_code ec;
    if (std::filesystem::exists(path, ec) && std::filesystem::file_size(path, ec) > 200000) break;
    std::this_thread::sleep_for(std::chrono::milliseconds(2));
  }
  ::kill(child, SIGKILL);
  int status = 0;
  ::waitpid(child, &status, 0);
  ASSERT_TRUE(WIFSIGNALED(status)) << "writer exited with " << WEXITSTATUS(status);
  const auto rec = loadRecording(path);
  ASSERT_TRUE(rec.ok()) << rec.error().message;
  EXPECT_GT(rec->frames.size(), 100u);
  if (!rec->complete) {
    EXPECT_NE(rec->stop_reason.find("truncated"), std::string::npos) << rec->stop_reason;
  }
  for (std::size_t i = 0; i < rec->frames.size(); ++i) ASSERT_EQ(rec->frames[i].sequence, i);
}

}  // namespace
}  // namespace vistel
