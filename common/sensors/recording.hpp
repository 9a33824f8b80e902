// .vrec recordings: a site's raw sensor stream (DESIGN.md §6), replayable through the
// solver (vistel-bot --recording FILE.vrec).
//
// Layout, little-endian:
//   file header  "VREC\r\n\x1a\n" (8 bytes; the CR LF and ^Z catch text-mode mangling),
//                u32 format version (kRecordingVersion)
//   records      u32 payload size, u8 type, payload, u32 CRC-32 of the type byte and the
//                payload (crc32 from common/base/bytes.hpp)
// Record types: 1 header (must come first: participant, sensor map, optional calibration,
// the sensors config text), 2 frame (one SensorFrame, fixed size), 3 calibration (a
// calibration taken during the session: its window and the averaged readings), 4 voice
// (one 20 ms Opus packet of the participant's voice as the client sent it: f64 capture
// time of the frame's first sample on the recording's sensor clock, the clock of
// SensorFrame::time; u16 packet bytes, 1..kRecordingMaxVoicePacket; the packet). Voice
// records sit between the frames in the order they were captured; a muted or silent
// stretch has none (the replay speaks silence there). How a client maps its voice clock
// onto the sensor clock: client/app/sensor_input.hpp.
// Versions: 1 stores four stations (head, chest, wrists) in every frame and calibration;
// 2 stores six (the feet too). The writer writes version 1 unless the header's sensor map
// names a foot station, so four-station files are what they always were; the reader reads
// both (a version 1 file's foot stations read as not valid). Voice records need no new
// version (they come in either): a build older than them skips each one as a damaged
// stretch ("unknown record type 4") and replays the motion without the voice.
//
// The writer appends each record with a single write() on an O_APPEND descriptor, so a
// process killed mid-write loses at most the record being written. The reader keeps every
// good record: after a damaged stretch (a bad size, a checksum mismatch, a cut tail, a
// record whose values are out of range) it resynchronises on the next record that frames
// and checks (size, type, CRC-32, then every value), and lists each skipped stretch with
// its record index, byte offset, length and reason.
#pragma once

#include <array>
#include <atomic>
#include <cstdint>
#include <memory>
#include <mutex>
#include <optional>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "common/base/result.hpp"
#include "common/sensors/sensor_frame.hpp"
#include "common/sensors/sensor_source.hpp"

namespace vistel {

inline constexpr std::uint32_t kRecordingVersion = 2;              // the newest this build reads
inline constexpr std::uint32_t kRecordingVersionFourStations = 1;  // no foot stations
// Stations per frame and calibration record in a format version (1: 4, 2: 6), 0 if unknown.
int recordingStationCount(std::uint32_t version);
inline constexpr std::size_t kRecordingMaxPayload = 1u << 20;
inline constexpr std::size_t kRecordingMaxVoicePacket = 1275;  // Opus's largest packet

// Which tracker station was worn where, and which gloves were on.
struct SensorMapEntry {
  int station = 0;  // device station number (1..4), 0 for a simulated or HID source
  // (a version 1 file names only the four upper-body sites)
  BodySite site = BodySite::kHead;
};
struct GloveMapEntry {
  Hand hand = Hand::kLeft;
  int sensor_count = 22;
};

// A calibration: the participant held the calibration pose over [start, end]; the
// averaged readings of that window (what calibrateBody needs besides the skeleton).
struct CalibrationRecord {
  double start_time = 0.0;
  double end_time = 0.0;
  std::string pose;  // "standard" (arms down) or a description, e.g. "clip frame 0"
  std::array<StationReading, kBodySiteCount> stations{};
  std::array<GloveReading, kHandCount> gloves{};
};

// One 20 ms voice packet (Opus, 48 kHz mono, as common/voice/opus_voice encodes it).
struct VoiceRecord {
  double time = 0.0;                 // capture time of its first sample, sensor clock (s)
  std::vector<std::uint8_t> packet;  // 1..kRecordingMaxVoicePacket bytes
};

struct RecordingHeader {
  std::string participant;
  std::string source;  // what produced the frames ("fastrak /dev/ttyUSB0", "sim:clip.bvh")
  std::vector<SensorMapEntry> stations;
  std::vector<GloveMapEntry> gloves;
  std::optional<CalibrationRecord> calibration;
  std::string config_text;  // the sensors config in use (TOML), may be empty
};

// A stretch of the file the reader skipped: one record whose values were bad (well framed,
// so exactly its bytes), or bytes up to the next record that frames and checks (or to the
// end of the file: a cut tail).
struct RecordingDamage {
  std::size_t record = 0;    // records read before it (the header and any earlier stretch
                             // count one each): the index the record there would have had
  std::uint64_t offset = 0;  // first byte skipped, from the start of the file
  std::uint64_t bytes = 0;   // bytes skipped from there (> 0)
  std::string why;           // what was wrong with the record at `offset`
};

struct Recording {
  RecordingHeader header;
  std::vector<SensorFrame> frames;
  std::vector<CalibrationRecord> calibrations;  // taken during the session, in order
  std::vector<std::size_t> calibration_after;   // frames recorded before each calibration
  std::vector<VoiceRecord> voice;               // the voice track, in file order (may be empty)
  bool complete = true;                         // every byte was a good record (damage empty)
  std::vector<RecordingDamage> damage;          // skipped stretches, in file order, disjoint
  std::uint64_t skipped_bytes = 0;              // sum of damage[].bytes
  // Empty when complete; otherwise one line for the log: the source, how much was skipped
  // where and why (the first few stretches), and how many frames were kept.
  std::string stop_reason;
  std::uint64_t stop_offset = 0;  // byte offset of the first damage (0 when complete)
};

// Decodes a whole file's bytes. Fails (naming source, byte offset and reason) only when not
// even the file header and the header record are intact; otherwise returns every good
// record of the file, with complete = false and the damage listed when some bytes had to be
// skipped. Cost: linear in the file for intact records; a damaged stretch is rescanned byte
// by byte, with a CRC-32 over a record's length only where the bytes hold a frame,
// calibration or voice record's size and type (rare in damage; at worst about a record's
// length of work per damaged byte).
Result<Recording> decodeRecording(std::span<const std::uint8_t> bytes, std::string_view source);
Result<Recording> loadRecording(const std::string& path);

// The version the writer uses for a header: 2 when its sensor map names a foot station,
// else 1.
std::uint32_t recordingVersionFor(const RecordingHeader& header);

// Encodes records (the writer's format), for tests and tools, in a format version (1 or 2;
// version 1 leaves out the foot stations).
void encodeRecordingFileHeader(std::vector<std::uint8_t>& out,
                               std::uint32_t version = kRecordingVersionFourStations);
void encodeHeaderRecord(const RecordingHeader& header, std::vector<std::uint8_t>& out,
                        std::uint32_t version = kRecordingVersionFourStations);
void encodeFrameRecord(const SensorFrame& frame, std::vector<std::uint8_t>& out,
                       std::uint32_t version = kRecordingVersionFourStations);
void encodeCalibrationRecord(const CalibrationRecord& record, std::vector<std::uint8_t>& out,
                             std::uint32_t version = kRecordingVersionFourStations);
// The same in every version. The packet must hold 1..kRecordingMaxVoicePacket bytes (the
// caller's check; appendVoice makes it).
void encodeVoiceRecord(double time, std::span<const std::uint8_t> packet,
                       std::vector<std::uint8_t>& out);

class RecordingWriter {
 public:
  // Creates (truncates) the file and writes the file header and the header record.
  static Result<std::unique_ptr<RecordingWriter>> create(const std::string& path,
                                                         const RecordingHeader& header);
  // Opens an existing recording (its file header checked) to append more records at its
  // end, e.g. the voice beside the writer that a PostureSource owns: each record is one
  // write() on an O_APPEND descriptor, which Linux never interleaves with another
  // descriptor's on a regular file, so both writers' records stay whole.
  static Result<std::unique_ptr<RecordingWriter>> appendTo(const std::string& path);
  ~RecordingWriter();
  RecordingWriter(const RecordingWriter&) = delete;
  RecordingWriter& operator=(const RecordingWriter&) = delete;

  // One record per call, one write() each; allocation-free after the first frame.
  Status append(const SensorFrame& frame);
  Status appendCalibration(const CalibrationRecord& record);
  // A voice packet captured at `time` (the sensor clock, seconds). Errors: an empty or
  // oversized packet, a non-finite time, a failed write. May be called from another thread
  // than append() (records never interleave: the writer serialises them).
  Status appendVoice(double time, std::span<const std::uint8_t> packet);
  // Forces the data to the disk (fdatasync), beyond what a process crash needs.
  Status sync();
  std::uint64_t framesWritten() const { return frames_; }
  std::uint64_t voiceWritten() const { return voice_; }
  const std::string& path() const { return path_; }

 private:
  RecordingWriter() = default;
  Status writeRecord();

  std::mutex mutex_;  // one record at a time (frames and voice come from two threads)
  int fd_ = -1;
  std::uint32_t version_ = kRecordingVersionFourStations;
  std::string path_;
  std::vector<std::uint8_t> buffer_;
  std::atomic<std::uint64_t> frames_{0};
  std::atomic<std::uint64_t> voice_{0};
};

// Replays a recording's frames in order (as fast as polled; the frames keep their times):
// kEnd after the last one, naming where and why bytes were skipped when it was damaged.
class RecordingSource final : public SensorSource {
 public:
  explicit RecordingSource(Recording recording, std::string name);
  PollResult poll(double timeout_s, SensorFrame& frame) override;
  std::string describe() const override;
  const Recording& recording() const { return recording_; }
  std::size_t position() const { return next_; }

 private:
  Recording recording_;
  std::string name_;
  std::size_t next_ = 0;
};

}  // namespace vistel
