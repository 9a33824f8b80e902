// .vrec recordings: round trip, truncated at every length, corrupted at every byte, bytes
// slipped in or out, random damage, and a writer process killed mid-stream: readers keep
// every good record, resynchronise after damage and say where and why they skipped bytes.
#include <algorithm>
#include <cmath>
#include <csignal>
#include <cstring>
#include <filesystem>
#include <random>
#include <thread>

#include <sys/wait.h>
#include <unistd.h>

#include <gtest/gtest.h>

#include "common/base/bytes.hpp"
#include "common/base/file.hpp"
#include "common/sensors/io/posture_source.hpp"
#include "common/sensors/random.hpp"
#include "common/sensors/recording.hpp"
#include "tests/sensors/humanoid.hpp"
#include "tests/support/test_support.hpp"

namespace vistel {
namespace {

// The four upper-body stations (what a version 1 file holds), or all six.
SensorFrame randomFrame(SimRandom& rng, std::uint64_t seq, int stations = kUpperBodySiteCount) {
  SensorFrame f;
  f.time = 0.01 * static_cast<double>(seq);
  f.sequence = seq;
  for (int k = 0; k < stations; ++k) {
    StationReading& s = f.stations[static_cast<std::size_t>(k)];
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
      ASSERT_EQ(rec->damage.size(), 1u) << len;
      EXPECT_EQ(rec->damage[0].bytes, len - last_end) << len;
    }
    for (std::size_t i = 0; i < rec->frames.size(); ++i) expectFrameEq(frames[i], rec->frames[i]);
  }
}

// Damage entries lie inside the file, in order, apart, and add up to skipped_bytes; the
// summary names the source and the first offset.
void expectConsistentDamage(const Recording& rec, std::size_t file_size, std::string_view source) {
  EXPECT_EQ(rec.complete, rec.damage.empty());
  EXPECT_EQ(rec.complete, rec.stop_reason.empty());
  std::uint64_t sum = 0;
  std::uint64_t previous_end = 12;
  for (const RecordingDamage& d : rec.damage) {
    EXPECT_GE(d.offset, previous_end);
    EXPECT_GT(d.bytes, 0u);
    EXPECT_LE(d.offset + d.bytes, file_size);
    EXPECT_FALSE(d.why.empty());
    previous_end = d.offset + d.bytes;
    sum += d.bytes;
  }
  EXPECT_EQ(sum, rec.skipped_bytes);
  if (!rec.complete) {
    EXPECT_EQ(rec.stop_offset, rec.damage.front().offset);
    EXPECT_NE(rec.stop_reason.find(source), std::string::npos) << rec.stop_reason;
    EXPECT_NE(rec.stop_reason.find(fmt::format("at byte {}", rec.stop_offset)), std::string::npos)
        << rec.stop_reason;
  }
}

TEST(Recording, CorruptedAnywhereLosesOnlyThatRecord) {
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
      std::size_t record = 0;  // the record the flipped byte is in (8 is the calibration)
      while (ends[record] <= at) ++record;
      const std::size_t start = record == 0 ? header_end : ends[record - 1];
      ASSERT_FALSE(rec->complete) << at;
      ASSERT_EQ(rec->damage.size(), 1u) << at << ": " << rec->stop_reason;
      EXPECT_EQ(rec->damage[0].offset, start) << at;
      EXPECT_EQ(rec->damage[0].bytes, ends[record] - start) << at;
      EXPECT_EQ(rec->damage[0].record, record + 1) << at;
      EXPECT_EQ(rec->frames.size(), record == 8 ? 20u : 19u) << at;
      EXPECT_EQ(rec->calibrations.size(), record == 8 ? 0u : 1u) << at;
      // The other frames, in order.
      std::size_t k = 0;
      for (std::size_t i = 0; i < frames.size(); ++i) {
        const std::size_t frame_record = i < 8 ? i : i + 1;
        if (frame_record == record) continue;
        ASSERT_LT(k, rec->frames.size());
        expectFrameEq(frames[i], rec->frames[k++]);
      }
      if (record != 8) {
        EXPECT_EQ(rec->calibration_after[0], record < 8 ? 7u : 8u) << at;
      }
      expectConsistentDamage(*rec, bad.size(), "bad.vrec");
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

// A session of 360 frames (12 s at 30 Hz) with a calibration record after frame 30.
std::vector<std::uint8_t> longSession(std::vector<SensorFrame>& frames,
                                      std::vector<std::size_t>& starts,
                                      const RecordingHeader& header = sampleHeader()) {
  SimRandom rng(5);
  std::vector<std::uint8_t> bytes;
  encodeRecordingFileHeader(bytes);
  encodeHeaderRecord(header, bytes);
  for (std::uint64_t i = 0; i < 360; ++i) {
    frames.push_back(randomFrame(rng, i));
    starts.push_back(bytes.size());
    encodeFrameRecord(frames.back(), bytes);
    if (i == 30) {
      CalibrationRecord c;
      c.pose = "standard";
      encodeCalibrationRecord(c, bytes);
    }
  }
  return bytes;
}

TEST(Recording, OneFlippedBitAtRecordFiveLosesOneFrame) {
  std::vector<SensorFrame> frames;
  std::vector<std::size_t> starts;
  const auto bytes = longSession(frames, starts);
  // Record 5 is frame 4 (record 0 is the header); flip a bit in its size, its payload
  // and its checksum in turn.
  const std::size_t start = starts[4];
  const std::size_t length = starts[5] - start;
  for (std::size_t at : {start + 1, start + 4, start + 100, start + length - 2}) {
    std::vector<std::uint8_t> bad = bytes;
    bad[at] ^= 0x10;
    const auto rec = decodeRecording(bad, "flipped.vrec");
    ASSERT_TRUE(rec.ok()) << rec.error().message;
    EXPECT_GE(rec->frames.size(), 355u);
    EXPECT_EQ(rec->frames.size(), 359u) << rec->stop_reason;
    EXPECT_EQ(rec->calibrations.size(), 1u);
    EXPECT_EQ(rec->calibration_after[0], 30u);
    ASSERT_EQ(rec->damage.size(), 1u) << rec->stop_reason;
    EXPECT_EQ(rec->damage[0].record, 5u);
    EXPECT_EQ(rec->damage[0].offset, start);
    EXPECT_EQ(rec->damage[0].bytes, length);
    EXPECT_EQ(rec->skipped_bytes, length);
    EXPECT_NE(rec->stop_reason.find(fmt::format("record 5 at byte {}", start)), std::string::npos)
        << rec->stop_reason;
    for (std::size_t i = 0; i < rec->frames.size(); ++i) {
      EXPECT_EQ(rec->frames[i].sequence, i < 4 ? i : i + 1);
    }
    expectConsistentDamage(*rec, bad.size(), "flipped.vrec");

    // Replayed: every good frame, then an end that names the damage.
    RecordingSource source(std::move(*rec), "flipped.vrec");
    SensorFrame f;
    int n = 0;
    PollResult r;
    while ((r = source.poll(0.0, f)).isFrame()) ++n;
    EXPECT_EQ(n, 359);
    EXPECT_EQ(r.status, PollStatus::kEnd);
    EXPECT_NE(r.message.find(fmt::format("at byte {}", start)), std::string::npos) << r.message;
    EXPECT_NE(source.describe().find("skipped"), std::string::npos) << source.describe();
  }
}

TEST(Recording, PostureSourceReportsWhatTheReaderSkipped) {
  std::vector<SensorFrame> frames;
  std::vector<std::size_t> starts;
  RecordingHeader header = sampleHeader();
  header.calibration.reset();  // (its random readings would not calibrate the humanoid)
  std::vector<std::uint8_t> bytes = longSession(frames, starts, header);
  bytes[starts[4] + 100] ^= 0x10;
  const std::string path = test::scratchDir() + "/damaged.vrec";
  ASSERT_TRUE(writeFileBytes(path, bytes).ok());
  PostureSourceOptions options;
  options.realtime = false;
  auto source = openPostureSource(path, test::makeHumanoid(false), options);
  ASSERT_TRUE(source.ok()) << source.error().message;
  // The caller's log gets where and why, before the first frame.
  const std::string status = (*source)->status();
  EXPECT_NE(status.find("recording damaged"), std::string::npos) << status;
  EXPECT_NE(status.find(fmt::format("record 5 at byte {}", starts[4])), std::string::npos)
      << status;
  EXPECT_NE((*source)->describe().find("skipped"), std::string::npos) << (*source)->describe();
  Posture p;
  int n = 0;
  PollResult r;
  while ((r = (*source)->poll(0.0, p)).isFrame()) ++n;
  EXPECT_EQ(n, 359);
  EXPECT_EQ(r.status, PollStatus::kEnd) << r.message;
}

TEST(Recording, CutInTheLastRecordKeepsEveryEarlierFrame) {
  std::vector<SensorFrame> frames;
  std::vector<std::size_t> starts;
  const auto bytes = longSession(frames, starts);
  const std::size_t last = starts.back();
  for (std::size_t len : {last + 1, last + 5, last + 100, bytes.size() - 1}) {
    const auto rec = decodeRecording(std::span(bytes).first(len), "cut.vrec");
    ASSERT_TRUE(rec.ok()) << rec.error().message;
    EXPECT_EQ(rec->frames.size(), 359u) << len;
    ASSERT_EQ(rec->damage.size(), 1u) << rec->stop_reason;
    EXPECT_EQ(rec->damage[0].offset, last);
    EXPECT_EQ(rec->damage[0].bytes, len - last);
    EXPECT_NE(rec->damage[0].why.find("truncated"), std::string::npos) << rec->damage[0].why;
    expectConsistentDamage(*rec, len, "cut.vrec");
  }
}

TEST(Recording, SlippedBytesResynchronise) {
  std::vector<SensorFrame> frames;
  std::vector<std::size_t> starts;
  const auto bytes = longSession(frames, starts);
  // Three bytes inserted in frame 100, seven dropped from frame 200, frame 300 zeroed.
  std::vector<std::uint8_t> bad(bytes.begin(), bytes.begin() + starts[100] + 50);
  bad.insert(bad.end(), {0xde, 0xad, 0x02});
  bad.insert(bad.end(), bytes.begin() + starts[100] + 50, bytes.begin() + starts[200] + 20);
  bad.insert(bad.end(), bytes.begin() + starts[200] + 27, bytes.end());
  const std::size_t frame_300 = starts[300] - 4;  // where it starts now (3 in, 7 out)
  std::fill(bad.begin() + static_cast<std::ptrdiff_t>(frame_300),
            bad.begin() + static_cast<std::ptrdiff_t>(frame_300 + starts[301] - starts[300]), 0);
  const auto rec = decodeRecording(bad, "slipped.vrec");
  ASSERT_TRUE(rec.ok()) << rec.error().message;
  EXPECT_EQ(rec->frames.size(), 357u) << rec->stop_reason;
  ASSERT_EQ(rec->damage.size(), 3u) << rec->stop_reason;
  EXPECT_EQ(rec->damage[0].offset, starts[100]);
  EXPECT_EQ(rec->damage[0].bytes, starts[101] - starts[100] + 3);
  EXPECT_EQ(rec->damage[1].offset, starts[200] + 3);
  EXPECT_EQ(rec->damage[2].offset, frame_300);
  EXPECT_NE(rec->stop_reason.find("skipped"), std::string::npos);
  std::uint64_t previous = 0;
  for (const SensorFrame& f : rec->frames) {
    EXPECT_TRUE(f.sequence == 0 || f.sequence > previous);
    EXPECT_NE(f.sequence, 100u);
    EXPECT_NE(f.sequence, 200u);
    EXPECT_NE(f.sequence, 300u);
    previous = f.sequence;
  }
  expectConsistentDamage(*rec, bad.size(), "slipped.vrec");
}

TEST(Recording, RecordWithBadValuesIsSkippedExactly) {
  SimRandom rng(9);
  std::vector<std::uint8_t> bytes;
  encodeRecordingFileHeader(bytes);
  encodeHeaderRecord(sampleHeader(), bytes);
  std::vector<std::size_t> starts;
  for (std::uint64_t i = 0; i < 6; ++i) {
    SensorFrame f = randomFrame(rng, i);
    if (i == 2) f.time = std::nan("");          // well framed, a bad value
    if (i == 4) f.gloves[0].angles[3] = 42.0f;  // out of range
    starts.push_back(bytes.size());
    encodeFrameRecord(f, bytes);
  }
  starts.push_back(bytes.size());
  // A record of a type this build does not know, with a good checksum.
  const std::size_t unknown = bytes.size();
  const std::uint8_t record[] = {3, 0, 0, 0, 9, 'a', 'b', 'c'};
  bytes.insert(bytes.end(), std::begin(record), std::end(record));
  const std::uint32_t crc = crc32(std::span<const std::uint8_t>(bytes).subspan(unknown + 4, 4));
  ByteWriter(bytes).u32(crc);
  encodeFrameRecord(randomFrame(rng, 6), bytes);

  const auto rec = decodeRecording(bytes, "values.vrec");
  ASSERT_TRUE(rec.ok()) << rec.error().message;
  EXPECT_EQ(rec->frames.size(), 5u);
  ASSERT_EQ(rec->damage.size(), 3u) << rec->stop_reason;
  EXPECT_EQ(rec->damage[0].offset, starts[2]);
  EXPECT_EQ(rec->damage[0].bytes, starts[3] - starts[2]);
  EXPECT_EQ(rec->damage[1].offset, starts[4]);
  EXPECT_NE(rec->damage[1].why.find("glove angle"), std::string::npos) << rec->damage[1].why;
  EXPECT_EQ(rec->damage[2].offset, unknown);
  EXPECT_EQ(rec->damage[2].bytes, 12u);
  EXPECT_NE(rec->damage[2].why.find("unknown record type 9"), std::string::npos);
  EXPECT_EQ(rec->frames.back().sequence, 6u);
  expectConsistentDamage(*rec, bytes.size(), "values.vrec");
}

// Random damage of every kind: flips, overwritten runs, cuts, slips, spliced copies. The
// reader never fails after an intact header, keeps only true frames in order, and reports
// consistently (run under ASan+UBSan by scripts/test).
TEST(Recording, RandomDamageNeverBreaksTheReader) {
  std::vector<SensorFrame> frames;
  std::vector<std::size_t> starts;
  const auto bytes = longSession(frames, starts);
  std::mt19937 rng(77);
  auto below = [&](std::size_t n) {
    return std::uniform_int_distribution<std::size_t>(0, n - 1)(rng);
  };
  for (int trial = 0; trial < 150; ++trial) {
    std::vector<std::uint8_t> bad = bytes;
    const int edits = 1 + static_cast<int>(below(12));
    for (int e = 0; e < edits && bad.size() > starts[0] + 16; ++e) {
      const std::size_t at = starts[0] + below(bad.size() - starts[0]);
      switch (below(5)) {
        case 0:
          bad[at] ^= static_cast<std::uint8_t>(1u << below(8));
          break;
        case 1:
          for (std::size_t k = at; k < std::min(bad.size(), at + 1 + below(600)); ++k)
            bad[k] = static_cast<std::uint8_t>(below(256));
          break;
        case 2:
          bad.erase(
              bad.begin() + static_cast<std::ptrdiff_t>(at),
              bad.begin() + static_cast<std::ptrdiff_t>(std::min(bad.size(), at + 1 + below(40))));
          break;
        case 3:
          bad.insert(bad.begin() + static_cast<std::ptrdiff_t>(at), 1 + below(40),
                     static_cast<std::uint8_t>(below(256)));
          break;
        default: {  // a copy of another stretch of the file
          const std::size_t from = starts[0] + below(bytes.size() - starts[0]);
          const std::size_t n = std::min(bytes.size() - from, 1 + below(1500));
          bad.insert(bad.begin() + static_cast<std::ptrdiff_t>(at),
                     bytes.begin() + static_cast<std::ptrdiff_t>(from),
                     bytes.begin() + static_cast<std::ptrdiff_t>(from + n));
          break;
        }
      }
    }
    if (below(4) == 0) bad.resize(starts[0] + below(bad.size() - starts[0]));
    const auto rec = decodeRecording(bad, "random.vrec");
    ASSERT_TRUE(rec.ok()) << trial << ": " << rec.error().message;
    for (const SensorFrame& f : rec->frames) {
      ASSERT_LT(f.sequence, frames.size()) << trial;
      expectFrameEq(frames[f.sequence], f);
    }
    expectConsistentDamage(*rec, bad.size(), "random.vrec");
    if (edits == 1 && bad.size() == bytes.size()) {
      EXPECT_GE(rec->frames.size(), 355u) << trial;
    }
  }
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
    EXPECT_EQ(rec->damage.size(), 1u) << rec->stop_reason;
  }
  for (std::size_t i = 0; i < rec->frames.size(); ++i) ASSERT_EQ(rec->frames[i].sequence, i);
}

// A version 1 file as the four-station build wrote it, put together byte by byte here (not by
// the encoders): the current reader still reads it, the feet not valid.
void putU32(std::vector<std::uint8_t>& b, std::uint32_t v) {
  for (int k = 0; k < 4; ++k) b.push_back(static_cast<std::uint8_t>(v >> (8 * k)));
}
void putF32(std::vector<std::uint8_t>& b, float f) {
  std::uint32_t v;
  std::memcpy(&v, &f, 4);
  putU32(b, v);
}
void putF64(std::vector<std::uint8_t>& b, double d) {
  std::uint64_t v;
  std::memcpy(&v, &d, 8);
  putU32(b, static_cast<std::uint32_t>(v));
  putU32(b, static_cast<std::uint32_t>(v >> 32));
}
void putRecord(std::vector<std::uint8_t>& b, std::uint8_t type,
               const std::vector<std::uint8_t>& payload) {
  putU32(b, static_cast<std::uint32_t>(payload.size()));
  const std::size_t crc_from = b.size();
  b.push_back(type);
  b.insert(b.end(), payload.begin(), payload.end());
  putU32(b, crc32(std::span<const std::uint8_t>(b).subspan(crc_from)));
}

TEST(Recording, VersionOneFourStationFileStillReads) {
  std::vector<std::uint8_t> bytes = {'V', 'R', 'E', 'C', '\r', '\n', 0x1a, '\n'};
  putU32(bytes, 1);
  std::vector<std::uint8_t> header;
  putU32(header, 2);  // participant
  header.insert(header.end(), {'a', 'b'});
  putU32(header, 3);  // source
  header.insert(header.end(), {'s', 'i', 'm'});
  putU32(header, 4);  // station map: number, site
  for (std::uint8_t st = 0; st < 4; ++st) header.insert(header.end(), {std::uint8_t(st + 1), st});
  putU32(header, 0);    // gloves
  header.push_back(0);  // no calibration
  putU32(header, 0);    // config text
  putRecord(bytes, 1, header);
  for (int k = 0; k < 3; ++k) {
    std::vector<std::uint8_t> frame;
    putF64(frame, 0.5 + k);                        // time
    putU32(frame, static_cast<std::uint32_t>(k));  // sequence, u64
    putU32(frame, 0);
    for (int st = 0; st < 4; ++st) {  // four stations, 38 bytes each
      frame.push_back(1);             // valid
      frame.push_back(' ');           // status
      putF64(frame, 0.49 + k);
      for (float v : {0.1f * static_cast<float>(st), 1.0f, static_cast<float>(k)}) putF32(frame, v);
      for (float v : {1.0f, 0.0f, 0.0f, 0.0f}) putF32(frame, v);
    }
    for (int h = 0; h < 2; ++h) {  // two gloves, 97 bytes each
      frame.push_back(0);
      putF64(frame, 0.0);
      for (int a = 0; a < kGloveSensorCount; ++a) putF32(frame, 0.0f);
    }
    ASSERT_EQ(frame.size(), 362u);
    putRecord(bytes, 2, frame);
  }
  auto rec = decodeRecording(bytes, "v1.vrec");
  ASSERT_TRUE(rec.ok()) << rec.error().message;
  EXPECT_TRUE(rec->complete) << rec->stop_reason;
  EXPECT_EQ(rec->header.participant, "ab");
  ASSERT_EQ(rec->header.stations.size(), 4u);
  EXPECT_EQ(rec->header.stations[3].site, BodySite::kRightWrist);
  ASSERT_EQ(rec->frames.size(), 3u);
  for (int k = 0; k < 3; ++k) {
    const SensorFrame& f = rec->frames[static_cast<std::size_t>(k)];
    EXPECT_EQ(f.sequence, static_cast<std::uint64_t>(k));
    EXPECT_TRUE(f.station(BodySite::kRightWrist).valid);
    EXPECT_EQ(f.station(BodySite::kRightWrist).position, glm::vec3(0.3f, 1.0f, k));
    EXPECT_FALSE(f.station(BodySite::kLeftFoot).valid);
    EXPECT_FALSE(f.station(BodySite::kRightFoot).valid);
  }
  // The encoders' version 1 is the same bytes.
  std::vector<std::uint8_t> again;
  encodeRecordingFileHeader(again);
  RecordingHeader h = rec->header;
  encodeHeaderRecord(h, again);
  for (const SensorFrame& f : rec->frames) encodeFrameRecord(f, again);
  EXPECT_EQ(again, bytes);
}

TEST(Recording, SixStationsRoundTripAsVersionTwo) {
  RecordingHeader header = sampleHeader();
  EXPECT_EQ(recordingVersionFor(header), 1u);
  header.stations.push_back({0, BodySite::kLeftFoot});
  header.stations.push_back({0, BodySite::kRightFoot});
  EXPECT_EQ(recordingVersionFor(header), 2u);
  header.calibration->stations[static_cast<std::size_t>(BodySite::kRightFoot)].valid = true;
  header.calibration->stations[static_cast<std::size_t>(BodySite::kRightFoot)].position =
      glm::vec3(0.1f, 0.08f, 0.05f);
  const std::string path = test::scratchDir() + "/feet.vrec";
  SimRandom rng(5);
  std::vector<SensorFrame> frames;
  {
    auto writer = RecordingWriter::create(path, header);
    ASSERT_TRUE(writer.ok()) << writer.error().message;
    for (std::uint64_t i = 0; i < 10; ++i) {
      frames.push_back(randomFrame(rng, i, kBodySiteCount));
      ASSERT_TRUE((*writer)->append(frames.back()).ok());
    }
  }
  auto bytes = readFileBytes(path);
  ASSERT_TRUE(bytes.ok());
  std::uint32_t version = 0;
  std::memcpy(&version, bytes->data() + 8, 4);
  EXPECT_EQ(version, 2u);
  auto rec = loadRecording(path);
  ASSERT_TRUE(rec.ok()) << rec.error().message;
  EXPECT_TRUE(rec->complete) << rec->stop_reason;
  ASSERT_EQ(rec->header.stations.size(), 6u);
  EXPECT_EQ(rec->header.stations[5].site, BodySite::kRightFoot);
  ASSERT_TRUE(rec->header.calibration.has_value());
  EXPECT_EQ(rec->header.calibration->stations[5].position, glm::vec3(0.1f, 0.08f, 0.05f));
  ASSERT_EQ(rec->frames.size(), frames.size());
  for (std::size_t i = 0; i < frames.size(); ++i) expectFrameEq(rec->frames[i], frames[i]);
  // A damaged six-station file resynchronises on its own record size.
  std::vector<std::uint8_t> damaged = *bytes;
  damaged[damaged.size() / 2] ^= 0x5a;
  auto partial = decodeRecording(damaged, "feet.vrec");
  ASSERT_TRUE(partial.ok()) << partial.error().message;
  EXPECT_FALSE(partial->complete);
  EXPECT_EQ(partial->frames.size(), frames.size() - 1);
  // A version 1 file cannot name a foot station.
  std::vector<std::uint8_t> v1;
  encodeRecordingFileHeader(v1);
  encodeHeaderRecord(header, v1);  // version 1 leaves the feet out of the map
  auto back = decodeRecording(v1, "v1.vrec");
  ASSERT_TRUE(back.ok()) << back.error().message;
  EXPECT_EQ(back->header.stations.size(), 4u);
  // An unknown version fails clearly.
  std::vector<std::uint8_t> v3;
  encodeRecordingFileHeader(v3, 3);
  auto bad = decodeRecording(v3, "v3.vrec");
  ASSERT_FALSE(bad.ok());
  EXPECT_NE(bad.error().message.find("version 3"), std::string::npos) << bad.error().message;
}

}  // namespace
}  // namespace vistel
