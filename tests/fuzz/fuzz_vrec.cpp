// libFuzzer target: decodeRecording (common/sensors/recording.hpp) on arbitrary bytes, as a
// .vrec file. Properties: nothing crashes, leaks or reads out of bounds; a rejected file
// gets a message naming the source; an accepted one keeps the header's invariants
// (complete <=> no damage <=> no stop reason; the damaged stretches inside the file, in
// order, apart, adding up to skipped_bytes, the first at stop_offset; calibrations placed
// between frames, finite times, unit orientations on valid stations, glove angles within
// 10 rad, voice packets of 1..1275 bytes at finite times), and re-encoding it record by
// record gives a complete recording that encodes to the same bytes again.
//
// Every record carries a CRC-32, so the custom mutator repairs the checksums of most
// mutants (fuzz_support.hpp). Seeds: small recordings written by the recording encoders,
// one with a voice track, one cut short and one with a damaged record in the middle (the
// resynchronisation).
#include <cmath>
#include <cstdint>
#include <span>
#include <string>
#include <vector>

#include "common/base/bytes.hpp"
#include "common/sensors/recording.hpp"
#include "common/sensors/sensor_frame.hpp"
#include "tests/fuzz/fuzz_support.hpp"

namespace {

using namespace vistel;
using fuzz::check;

constexpr std::size_t kFileHeader = 12;   // magic, version
constexpr std::size_t kRecordHeader = 5;  // payload size, type

// Recomputes the CRC-32 (of the type byte and the payload) of every record that lies
// within the input.
void repairRecords(std::uint8_t* data, std::size_t size) {
  std::size_t at = kFileHeader;
  while (at + kRecordHeader <= size) {
    const std::uint32_t payload = fuzz::loadU32(data + at);
    const std::size_t typed = at + 4;  // the type byte, then the payload
    if (payload > size - typed - 1 || size - typed - 1 - payload < 4) return;
    fuzz::storeU32(data + typed + 1 + payload, crc32({data + typed, payload + 1u}));
    at = typed + 1 + payload + 4;
  }
}

// ---- seeds -------------------------------------------------------------------------------

SensorFrame sampleFrame(int k) {
  SensorFrame f;
  f.time = 0.01 * k;
  f.sequence = static_cast<std::uint64_t>(k);
  for (int s = 0; s < kBodySiteCount; ++s) {
    StationReading& r = f.stations[static_cast<std::size_t>(s)];
    r.valid = (s + k) % 3 != 0;
    r.status = s == 1 ? 'w' : ' ';
    r.time = f.time - 0.001;
    r.position = glm::vec3(0.1f * s, 1.5f - 0.2f * s, 0.01f * k);
    r.orientation = glm::angleAxis(0.1f * (s + k), glm::vec3(0, 1, 0));
  }
  for (GloveReading& g : f.gloves) {
    g.valid = true;
    g.time = f.time;
    for (std::size_t i = 0; i < g.angles.size(); ++i) g.angles[i] = 0.05f * (i + k);
  }
  return f;
}

CalibrationRecord sampleCalibration() {
  CalibrationRecord c;
  c.start_time = 1.0;
  c.end_time = 2.5;
  c.pose = "standard";
  const SensorFrame f = sampleFrame(1);
  c.stations = f.stations;
  c.gloves = f.gloves;
  return c;
}

std::vector<fuzz::Seed> makeSeeds() {
  RecordingHeader header;
  header.participant = "fuzz";
  header.source = "sim:generated";
  header.stations = {{1, BodySite::kHead}, {2, BodySite::kChest}, {3, BodySite::kLeftWrist}};
  header.gloves = {{Hand::kLeft, 22}, {Hand::kRight, 18}};
  header.config_text = "participant = \"fuzz\"\n";

  std::vector<std::uint8_t> plain;
  encodeRecordingFileHeader(plain);
  encodeHeaderRecord(header, plain);
  const std::vector<std::uint8_t> header_only = plain;
  for (int k = 0; k < 3; ++k) encodeFrameRecord(sampleFrame(k), plain);
  encodeCalibrationRecord(sampleCalibration(), plain);
  encodeFrameRecord(sampleFrame(3), plain);
  std::vector<std::uint8_t> voiced = plain;  // a voice track between and after the frames
  const std::uint8_t opus[] = {0x78, 0x01, 0x02, 0x03, 0xfe, 0x55};
  encodeVoiceRecord(0.02, opus, voiced);
  encodeFrameRecord(sampleFrame(4), voiced);
  encodeVoiceRecord(0.04, std::span<const std::uint8_t>(opus).first(3), voiced);

  header.calibration = sampleCalibration();
  std::vector<std::uint8_t> calibrated;
  encodeRecordingFileHeader(calibrated);
  encodeHeaderRecord(header, calibrated);
  encodeFrameRecord(sampleFrame(0), calibrated);

  std::vector<std::uint8_t> cut = plain;  // killed mid-write: the last record is partial
  cut.resize(cut.size() - 7);
  check(decodeRecording(header_only, "seed")->complete, "a seed decodes");
  check(decodeRecording(plain, "seed")->frames.size() == 4, "a seed decodes");
  check(decodeRecording(calibrated, "seed")->header.calibration.has_value(), "a seed decodes");
  check(decodeRecording(voiced, "seed")->voice.size() == 2, "a seed decodes");
  std::vector<std::uint8_t> damaged = plain;  // a byte of the second frame overwritten
  const std::size_t second_frame = header_only.size() + (plain.size() - header_only.size()) / 5;
  damaged[second_frame + 30] ^= 0x5a;
  check(!decodeRecording(cut, "seed")->complete, "the cut seed is incomplete");
  const auto resynced = decodeRecording(damaged, "seed");
  check(resynced->damage.size() == 1 && resynced->frames.size() >= 3,
        "the damaged seed resynchronises");
  return {{"header_only.vrec", header_only},
          {"frames_and_calibration.vrec", plain},
          {"header_calibration.vrec", calibrated},
          {"voice_track.vrec", voiced},
          {"cut_short.vrec", cut},
          {"damaged_middle.vrec", damaged}};
}

// ---- properties --------------------------------------------------------------------------

void checkStation(const StationReading& s) {
  check(std::isfinite(s.time) && std::isfinite(s.position.x) && std::isfinite(s.position.y) &&
            std::isfinite(s.position.z),
        "finite station time and position");
  if (s.valid) check(std::abs(glm::length(s.orientation) - 1.0f) < 1e-3f, "valid => unit");
}

void checkGlove(const GloveReading& g) {
  check(std::isfinite(g.time), "finite glove time");
  for (float a : g.angles) check(std::isfinite(a) && std::abs(a) <= 10.0f, "glove angles");
}

void checkCalibration(const CalibrationRecord& c) {
  check(std::isfinite(c.start_time) && std::isfinite(c.end_time), "finite calibration times");
  for (const StationReading& s : c.stations) checkStation(s);
  for (const GloveReading& g : c.gloves) checkGlove(g);
}

// The recording's records in file order, as bytes.
std::vector<std::uint8_t> encode(const Recording& rec) {
  std::vector<std::uint8_t> out;
  encodeRecordingFileHeader(out);
  encodeHeaderRecord(rec.header, out);
  std::size_t next_calibration = 0;
  for (std::size_t f = 0; f <= rec.frames.size(); ++f) {
    while (next_calibration < rec.calibrations.size() &&
           rec.calibration_after[next_calibration] == f) {
      encodeCalibrationRecord(rec.calibrations[next_calibration++], out);
    }
    if (f < rec.frames.size()) encodeFrameRecord(rec.frames[f], out);
  }
  for (const VoiceRecord& v : rec.voice) encodeVoiceRecord(v.time, v.packet, out);
  return out;
}

}  // namespace

extern "C" int LLVMFuzzerInitialize(int* argc, char*** argv) {
  fuzz::writeSeedsIfAsked(*argc, *argv, makeSeeds);
  return 0;
}

extern "C" std::size_t LLVMFuzzerCustomMutator(std::uint8_t* data, std::size_t size,
                                               std::size_t max_size, unsigned seed) {
  return fuzz::mutateThenRepair(data, size, max_size, seed, repairRecords);
}

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::span<const std::uint8_t> bytes(data, size);
  Result<Recording> rec = decodeRecording(bytes, "fuzz.vrec");
  if (!rec.ok()) {
    check(rec.error().message.starts_with("fuzz.vrec"), "a rejection names the source");
    return 0;
  }

  // Invariants of what was kept.
  check(rec->complete == rec->stop_reason.empty(), "complete <=> no stop reason");
  check(rec->complete == rec->damage.empty(), "complete <=> no damage");
  check(rec->complete || (rec->stop_offset >= kFileHeader && rec->stop_offset < size),
        "the stop offset lies inside the file");
  std::uint64_t skipped = 0;
  std::uint64_t previous_end = kFileHeader;
  for (const RecordingDamage& d : rec->damage) {
    check(d.bytes > 0 && d.offset >= previous_end && d.offset + d.bytes <= size && !d.why.empty(),
          "damaged stretches lie in the file, in order, apart, with a reason");
    previous_end = d.offset + d.bytes;
    skipped += d.bytes;
  }
  check(skipped == rec->skipped_bytes, "skipped_bytes adds up the stretches");
  check(rec->complete || rec->stop_offset == rec->damage.front().offset,
        "stop_offset is the first damage");
  check(rec->calibration_after.size() == rec->calibrations.size(), "a position per calibration");
  for (std::size_t i = 0; i < rec->calibration_after.size(); ++i) {
    check(rec->calibration_after[i] <= rec->frames.size() &&
              (i == 0 || rec->calibration_after[i - 1] <= rec->calibration_after[i]),
          "calibrations in order between frames");
  }
  for (const SensorMapEntry& e : rec->header.stations) {
    check(static_cast<int>(e.site) < kBodySiteCount, "known body sites");
  }
  for (const GloveMapEntry& g : rec->header.gloves) {
    check(g.sensor_count == 18 || g.sensor_count == 22, "18 or 22 glove sensors");
  }
  if (rec->header.calibration) checkCalibration(*rec->header.calibration);
  for (const CalibrationRecord& c : rec->calibrations) checkCalibration(c);
  for (const SensorFrame& f : rec->frames) {
    check(std::isfinite(f.time), "finite frame time");
    for (const StationReading& s : f.stations) checkStation(s);
    for (const GloveReading& g : f.gloves) checkGlove(g);
  }

  for (const VoiceRecord& v : rec->voice) {
    check(std::isfinite(v.time) && !v.packet.empty() && v.packet.size() <= kRecordingMaxVoicePacket,
          "voice packets of 1..1275 bytes at finite times");
  }

  // Round trip: the kept records encode to a complete recording that re-encodes the same.
  const std::vector<std::uint8_t> encoded = encode(*rec);
  Result<Recording> again = decodeRecording(encoded, "again.vrec");
  check(again.ok() && again->complete, "the kept records re-encode to a complete recording");
  check(again->frames.size() == rec->frames.size() &&
            again->calibrations.size() == rec->calibrations.size() &&
            again->voice.size() == rec->voice.size(),
        "the round trip keeps every record");
  check(encode(*again) == encoded, "decode(encode(recording)) encodes the same");
  return 0;
}
