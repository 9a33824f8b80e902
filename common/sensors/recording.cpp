#include "common/sensors/recording.hpp"

#include <cerrno>
#include <cmath>
#include <cstring>

#include <fcntl.h>
#include <unistd.h>

#include "common/base/bytes.hpp"
#include "common/base/file.hpp"

namespace vistel {
namespace {

constexpr std::uint8_t kMagic[8] = {'V', 'R', 'E', 'C', '\r', '\n', 0x1a, '\n'};
constexpr std::uint8_t kTypeHeader = 1;
constexpr std::uint8_t kTypeFrame = 2;
constexpr std::uint8_t kTypeCalibration = 3;
constexpr std::uint8_t kTypeVoice = 4;
constexpr std::size_t kVoiceBase = 10;  // f64 time, u16 packet bytes
constexpr std::size_t kFileHeaderSize = 12;
constexpr std::size_t kMaxPose = 1024;  // bytes of CalibrationRecord::pose

// ---- payload writers ---------------------------------------------------------------------

void writeStation(ByteWriter& w, const StationReading& r) {
  w.u8(r.valid ? 1 : 0);
  w.u8(static_cast<std::uint8_t>(r.status));
  w.f64(r.time);
  w.f32(r.position.x);
  w.f32(r.position.y);
  w.f32(r.position.z);
  w.f32(r.orientation.w);
  w.f32(r.orientation.x);
  w.f32(r.orientation.y);
  w.f32(r.orientation.z);
}

void writeGlove(ByteWriter& w, const GloveReading& g) {
  w.u8(g.valid ? 1 : 0);
  w.f64(g.time);
  for (float a : g.angles) w.f32(a);
}

// Starts a record: size placeholder and type; finish() patches the size and appends the CRC.
std::size_t beginRecord(std::vector<std::uint8_t>& out, std::uint8_t type) {
  const std::size_t start = out.size();
  ByteWriter w(out);
  w.u32(0);
  w.u8(type);
  return start;
}

void finishRecord(std::vector<std::uint8_t>& out, std::size_t start) {
  const std::size_t payload = out.size() - start - 5;
  ByteWriter w(out);
  w.patchU32(start, static_cast<std::uint32_t>(payload));
  w.u32(crc32(std::span<const std::uint8_t>(out).subspan(start + 4, payload + 1)));
}

// ---- payload readers (every value checked) -------------------------------------------------

bool finite(double v) { return std::isfinite(v); }

bool readStation(ByteReader& r, StationReading& out, std::string& why) {
  const std::uint8_t flags = r.u8();
  out.status = static_cast<char>(r.u8());
  out.time = r.f64();
  out.position.x = r.f32();
  out.position.y = r.f32();
  out.position.z = r.f32();
  out.orientation.w = r.f32();
  out.orientation.x = r.f32();
  out.orientation.y = r.f32();
  out.orientation.z = r.f32();
  out.valid = (flags & 1) != 0;
  if (!r.ok()) {
    why = "station reading cut short";
    return false;
  }
  if (flags > 1) {
    why = fmt::format("station flags {:#x}", flags);
    return false;
  }
  if (!finite(out.time) || !finite(out.position.x) || !finite(out.position.y) ||
      !finite(out.position.z)) {
    why = "non-finite station time or position";
    return false;
  }
  const float n = glm::length(out.orientation);
  if (out.valid && !(std::abs(n - 1.0f) < 1e-3f)) {
    why = fmt::format("station orientation of length {}", n);
    return false;
  }
  return true;
}

bool readGlove(ByteReader& r, GloveReading& out, std::string& why) {
  const std::uint8_t flags = r.u8();
  out.time = r.f64();
  for (float& a : out.angles) a = r.f32();
  out.valid = (flags & 1) != 0;
  if (!r.ok()) {
    why = "glove reading cut short";
    return false;
  }
  if (flags > 1 || !finite(out.time)) {
    why = "bad glove flags or time";
    return false;
  }
  for (float a : out.angles) {
    if (!finite(a) || std::abs(a) > 10.0f) {
      why = "glove angle out of range";
      return false;
    }
  }
  return true;
}

bool readCalibration(ByteReader& r, CalibrationRecord& out, int stations, std::string& why) {
  out.start_time = r.f64();
  out.end_time = r.f64();
  out.pose = r.string(kMaxPose);
  for (int s = 0; s < stations; ++s) {
    if (!readStation(r, out.stations[static_cast<std::size_t>(s)], why)) return false;
  }
  for (GloveReading& g : out.gloves) {
    if (!readGlove(r, g, why)) return false;
  }
  if (!r.ok() || !finite(out.start_time) || !finite(out.end_time)) {
    why = "calibration cut short or with a non-finite time";
    return false;
  }
  return true;
}

bool readHeader(ByteReader& r, RecordingHeader& out, int station_count, std::string& why) {
  out.participant = r.string(4096);
  out.source = r.string(4096);
  const std::uint32_t stations = r.u32();
  if (!r.ok() || stations > 16) {
    why = "bad station count";
    return false;
  }
  for (std::uint32_t i = 0; i < stations; ++i) {
    SensorMapEntry e;
    e.station = r.u8();
    const std::uint8_t site = r.u8();
    if (site >= station_count) {
      why = fmt::format("unknown body site {}", site);
      return false;
    }
    e.site = static_cast<BodySite>(site);
    out.stations.push_back(e);
  }
  const std::uint32_t gloves = r.u32();
  if (!r.ok() || gloves > 2) {
    why = "bad glove count";
    return false;
  }
  for (std::uint32_t i = 0; i < gloves; ++i) {
    GloveMapEntry g;
    const std::uint8_t hand = r.u8();
    g.sensor_count = r.u8();
    if (hand >= kHandCount || (g.sensor_count != 18 && g.sensor_count != 22)) {
      why = "bad glove entry";
      return false;
    }
    g.hand = static_cast<Hand>(hand);
    out.gloves.push_back(g);
  }
  const std::uint8_t has_calibration = r.u8();
  if (has_calibration > 1) {
    why = "bad calibration flag";
    return false;
  }
  if (has_calibration == 1) {
    CalibrationRecord c;
    if (!readCalibration(r, c, station_count, why)) return false;
    out.calibration = std::move(c);
  }
  out.config_text = r.string(kRecordingMaxPayload);
  if (!r.ok()) {
    why = "header cut short";
    return false;
  }
  return true;
}

bool readFrame(ByteReader& r, SensorFrame& out, int stations, std::string& why) {
  out.time = r.f64();
  out.sequence = r.u64();
  if (!r.ok() || !finite(out.time)) {
    why = "frame time cut short or not finite";
    return false;
  }
  for (int s = 0; s < stations; ++s) {
    if (!readStation(r, out.stations[static_cast<std::size_t>(s)], why)) return false;
  }
  for (GloveReading& g : out.gloves) {
    if (!readGlove(r, g, why)) return false;
  }
  return true;
}

bool readVoice(ByteReader& r, VoiceRecord& out, std::string& why) {
  out.time = r.f64();
  const std::uint16_t size = r.u16();
  if (!r.ok() || !finite(out.time)) {
    why = "voice time cut short or not finite";
    return false;
  }
  if (size == 0 || size > kRecordingMaxVoicePacket || size != r.remaining()) {
    why = fmt::format("voice packet of {} bytes in {} ({} allowed)", size, r.remaining(),
                      kRecordingMaxVoicePacket);
    return false;
  }
  const std::span<const std::uint8_t> packet = r.bytes(size);
  out.packet.assign(packet.begin(), packet.end());
  return r.ok();
}

}  // namespace

int recordingStationCount(std::uint32_t version) {
  return version == 1 ? kUpperBodySiteCount : version == 2 ? kBodySiteCount : 0;
}

std::uint32_t recordingVersionFor(const RecordingHeader& header) {
  for (const SensorMapEntry& e : header.stations) {
    if (isFootSite(e.site)) return 2;
  }
  return kRecordingVersionFourStations;
}

void encodeRecordingFileHeader(std::vector<std::uint8_t>& out, std::uint32_t version) {
  out.insert(out.end(), std::begin(kMagic), std::end(kMagic));
  ByteWriter(out).u32(version);
}

void encodeHeaderRecord(const RecordingHeader& h, std::vector<std::uint8_t>& out,
                        std::uint32_t version) {
  const std::size_t stations = static_cast<std::size_t>(recordingStationCount(version));
  const std::size_t start = beginRecord(out, kTypeHeader);
  ByteWriter w(out);
  w.string(h.participant);
  w.string(h.source);
  std::uint32_t listed = 0;
  for (const SensorMapEntry& e : h.stations) listed += static_cast<std::size_t>(e.site) < stations;
  w.u32(listed);
  for (const SensorMapEntry& e : h.stations) {
    if (static_cast<std::size_t>(e.site) >= stations) continue;  // not in this version
    w.u8(static_cast<std::uint8_t>(e.station));
    w.u8(static_cast<std::uint8_t>(e.site));
  }
  w.u32(static_cast<std::uint32_t>(h.gloves.size()));
  for (const GloveMapEntry& g : h.gloves) {
    w.u8(static_cast<std::uint8_t>(g.hand));
    w.u8(static_cast<std::uint8_t>(g.sensor_count));
  }
  w.u8(h.calibration ? 1 : 0);
  if (h.calibration) {
    w.f64(h.calibration->start_time);
    w.f64(h.calibration->end_time);
    w.string(h.calibration->pose);
    for (std::size_t s = 0; s < stations; ++s) writeStation(w, h.calibration->stations[s]);
    for (const GloveReading& g : h.calibration->gloves) writeGlove(w, g);
  }
  w.string(h.config_text);
  finishRecord(out, start);
}

void encodeFrameRecord(const SensorFrame& f, std::vector<std::uint8_t>& out,
                       std::uint32_t version) {
  const std::size_t stations = static_cast<std::size_t>(recordingStationCount(version));
  const std::size_t start = beginRecord(out, kTypeFrame);
  ByteWriter w(out);
  w.f64(f.time);
  w.u64(f.sequence);
  for (std::size_t s = 0; s < stations; ++s) writeStation(w, f.stations[s]);
  for (const GloveReading& g : f.gloves) writeGlove(w, g);
  finishRecord(out, start);
}

void encodeCalibrationRecord(const CalibrationRecord& c, std::vector<std::uint8_t>& out,
                             std::uint32_t version) {
  const std::size_t stations = static_cast<std::size_t>(recordingStationCount(version));
  const std::size_t start = beginRecord(out, kTypeCalibration);
  ByteWriter w(out);
  w.f64(c.start_time);
  w.f64(c.end_time);
  w.string(c.pose);
  for (std::size_t s = 0; s < stations; ++s) writeStation(w, c.stations[s]);
  for (const GloveReading& g : c.gloves) writeGlove(w, g);
  finishRecord(out, start);
}

void encodeVoiceRecord(double time, std::span<const std::uint8_t> packet,
                       std::vector<std::uint8_t>& out) {
  const std::size_t start = beginRecord(out, kTypeVoice);
  ByteWriter w(out);
  w.f64(time);
  w.u16(static_cast<std::uint16_t>(packet.size()));
  w.array(packet);
  finishRecord(out, start);
}

namespace {

constexpr std::size_t kRecordOverhead = 9;  // u32 size, u8 type, u32 CRC
constexpr std::size_t kListedDamage = 3;    // stretches named in stop_reason

// Payload sizes of the fixed-layout records (a calibration adds its pose's bytes).
std::size_t framePayloadSize(std::uint32_t version) {
  static const std::array<std::size_t, 2> sizes = [] {
    std::array<std::size_t, 2> out_sizes{};
    for (std::uint32_t v = 1; v <= 2; ++v) {
      std::vector<std::uint8_t> out;
      encodeFrameRecord(SensorFrame{}, out, v);
      out_sizes[v - 1] = out.size() - kRecordOverhead;
    }
    return out_sizes;
  }();
  return sizes[version == 2 ? 1 : 0];
}
std::size_t calibrationPayloadBase(std::uint32_t version) {
  static const std::array<std::size_t, 2> sizes = [] {
    std::array<std::size_t, 2> out_sizes{};
    for (std::uint32_t v = 1; v <= 2; ++v) {
      std::vector<std::uint8_t> out;
      encodeCalibrationRecord(CalibrationRecord{}, out, v);
      out_sizes[v - 1] = out.size() - kRecordOverhead;
    }
    return out_sizes;
  }();
  return sizes[version == 2 ? 1 : 0];
}

// How the bytes at a position frame as a record.
struct Framing {
  bool ok = false;         // size fits, the CRC matches
  std::uint32_t size = 0;  // payload bytes
  std::uint8_t type = 0;
  std::string why;  // when not ok
};

Framing frameAt(std::span<const std::uint8_t> bytes, std::size_t pos) {
  Framing f;
  const std::size_t left = bytes.size() - pos;
  if (left < kRecordOverhead) {
    f.why = fmt::format("truncated ({} bytes left, a record needs at least 9)", left);
    return f;
  }
  std::memcpy(&f.size, bytes.data() + pos, 4);
  f.type = bytes[pos + 4];
  if (f.size > kRecordingMaxPayload) {
    f.why = fmt::format("record size {} exceeds {}", f.size, kRecordingMaxPayload);
    return f;
  }
  if (left < static_cast<std::size_t>(f.size) + kRecordOverhead) {
    f.why = fmt::format("truncated (the record needs {} bytes, {} left)", f.size + 9, left);
    return f;
  }
  std::uint32_t stored;
  std::memcpy(&stored, bytes.data() + pos + 5 + f.size, 4);
  if (crc32(bytes.subspan(pos + 4, f.size + 1u)) != stored) {
    f.why = "checksum mismatch";
    return f;
  }
  f.ok = true;
  return f;
}

// Where a frame, calibration or voice record starts at or after `from` (the resynchronisation
// after a damaged stretch), or bytes.size(). Only a size that fits the type is checked
// with the CRC, so random bytes cost little.
std::size_t nextRecord(std::span<const std::uint8_t> bytes, std::size_t from,
                       std::uint32_t version) {
  const std::size_t frame = framePayloadSize(version);
  const std::size_t calibration = calibrationPayloadBase(version);
  for (std::size_t q = from; q + kRecordOverhead <= bytes.size(); ++q) {
    const std::uint8_t type = bytes[q + 4];
    if (type != kTypeFrame && type != kTypeCalibration && type != kTypeVoice) continue;
    std::uint32_t size;
    std::memcpy(&size, bytes.data() + q, 4);
    const bool fits = type == kTypeFrame ? size == frame
                      : type == kTypeVoice
                          ? size > kVoiceBase && size <= kVoiceBase + kRecordingMaxVoicePacket
                          : size >= calibration && size <= calibration + kMaxPose;
    if (fits && frameAt(bytes, q).ok) return q;
  }
  return bytes.size();
}

// One log line for a damaged recording.
std::string damageSummary(const Recording& rec, std::string_view source) {
  std::string s = fmt::format("{}: skipped {} bytes in {} place{}", source, rec.skipped_bytes,
                              rec.damage.size(), rec.damage.size() == 1 ? "" : "s");
  for (std::size_t i = 0; i < rec.damage.size() && i < kListedDamage; ++i) {
    const RecordingDamage& d = rec.damage[i];
    s += fmt::format("{} record {} at byte {} ({} bytes): {}", i == 0 ? ":" : ";", d.record,
                     d.offset, d.bytes, d.why);
  }
  if (rec.damage.size() > kListedDamage) {
    s += fmt::format("; and {} more", rec.damage.size() - kListedDamage);
  }
  s += fmt::format("; kept {} frames", rec.frames.size());
  return s;
}

}  // namespace

Result<Recording> decodeRecording(std::span<const std::uint8_t> bytes, std::string_view source) {
  if (bytes.size() < kFileHeaderSize) {
    return fail("{}: not a recording: {} bytes, shorter than the 12-byte file header", source,
                bytes.size());
  }
  if (std::memcmp(bytes.data(), kMagic, sizeof kMagic) != 0) {
    return fail("{}: not a recording (bad magic at byte 0)", source);
  }
  std::uint32_t version;
  std::memcpy(&version, bytes.data() + 8, 4);
  const int station_count = recordingStationCount(version);
  if (station_count == 0) {
    return fail("{}: recording format version {} (this build reads 1 to {})", source, version,
                kRecordingVersion);
  }
  Recording rec;
  std::size_t pos = kFileHeaderSize;

  // The header record must come first and be intact: without it there is no recording.
  {
    const Framing f = frameAt(bytes, pos);
    if (!f.ok) return fail("{}: header record at byte {}: {}", source, pos, f.why);
    if (f.type != kTypeHeader) {
      return fail("{}: header record at byte {}: expected the header record, found type {}", source,
                  pos, f.type);
    }
    ByteReader r(bytes.subspan(pos + 5, f.size));
    std::string why;
    if (!readHeader(r, rec.header, station_count, why)) {
      return fail("{}: header record at byte {}: {}", source, pos, why);
    }
    if (r.remaining() != 0) {
      return fail("{}: header record at byte {}: {} unexpected bytes at the end of the record",
                  source, pos, r.remaining());
    }
    pos += f.size + kRecordOverhead;
  }

  // Then every record that frames and checks; a bad one is skipped (with its reason),
  // either exactly (framed, bad values) or up to the next record that frames.
  std::size_t index = 1;
  auto skip = [&](std::size_t to, std::string why) {
    rec.damage.push_back({index, pos, to - pos, std::move(why)});
    rec.skipped_bytes += to - pos;
    pos = to;
  };
  while (pos < bytes.size()) {
    const Framing f = frameAt(bytes, pos);
    if (!f.ok) {
      skip(nextRecord(bytes, pos + 1, version), f.why);
      ++index;
      continue;
    }
    // A record that frames: kept when its values check, else skipped exactly.
    const std::size_t end = pos + f.size + kRecordOverhead;
    ByteReader r(bytes.subspan(pos + 5, f.size));
    std::string why;
    SensorFrame frame;
    CalibrationRecord calibration;
    VoiceRecord voice;
    bool good = false;
    if (f.type == kTypeFrame) {
      good = readFrame(r, frame, station_count, why);
    } else if (f.type == kTypeCalibration) {
      good = readCalibration(r, calibration, station_count, why);
    } else if (f.type == kTypeVoice) {
      good = readVoice(r, voice, why);
    } else {
      why = f.type == kTypeHeader ? std::string("a second header record")
                                  : fmt::format("unknown record type {}", f.type);
    }
    if (good && r.remaining() != 0) {
      good = false;
      why = fmt::format("{} unexpected bytes at the end of the record", r.remaining());
    }
    if (!good) {
      skip(end, std::move(why));
    } else if (f.type == kTypeFrame) {
      rec.frames.push_back(frame);
    } else if (f.type == kTypeVoice) {
      rec.voice.push_back(std::move(voice));
    } else {
      rec.calibrations.push_back(std::move(calibration));
      rec.calibration_after.push_back(rec.frames.size());
    }
    pos = end;
    ++index;
  }

  if (!rec.damage.empty()) {
    rec.complete = false;
    rec.stop_offset = rec.damage.front().offset;
    rec.stop_reason = damageSummary(rec, source);
  }
  return rec;
}

Result<Recording> loadRecording(const std::string& path) {
  Result<std::vector<std::uint8_t>> bytes = readFileBytes(path);
  if (!bytes) return bytes.error();
  return decodeRecording(*bytes, path);
}

Result<std::unique_ptr<RecordingWriter>> RecordingWriter::create(const std::string& path,
                                                                 const RecordingHeader& header) {
  std::unique_ptr<RecordingWriter> w(new RecordingWriter());
  w->path_ = path;
  w->fd_ = ::open(path.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_APPEND | O_CLOEXEC, 0644);
  if (w->fd_ < 0) return fail("{}: cannot create recording: {}", path, std::strerror(errno));
  w->buffer_.reserve(4096);
  w->version_ = recordingVersionFor(header);
  encodeRecordingFileHeader(w->buffer_, w->version_);
  encodeHeaderRecord(header, w->buffer_, w->version_);
  if (Status s = w->writeRecord(); !s) return s.error();
  return w;
}

Result<std::unique_ptr<RecordingWriter>> RecordingWriter::appendTo(const std::string& path) {
  std::unique_ptr<RecordingWriter> w(new RecordingWriter());
  w->path_ = path;
  w->fd_ = ::open(path.c_str(), O_RDWR | O_APPEND | O_CLOEXEC);
  if (w->fd_ < 0) return fail("{}: cannot open the recording: {}", path, std::strerror(errno));
  std::uint8_t head[kFileHeaderSize];
  if (::pread(w->fd_, head, sizeof head, 0) != static_cast<ssize_t>(sizeof head) ||
      std::memcmp(head, kMagic, sizeof kMagic) != 0) {
    return fail("{}: not a recording (no file header) to append to", path);
  }
  std::memcpy(&w->version_, head + 8, 4);
  if (recordingStationCount(w->version_) == 0) {
    return fail("{}: recording format version {} (this build writes 1 or 2)", path, w->version_);
  }
  w->buffer_.reserve(4096);
  return w;
}

RecordingWriter::~RecordingWriter() {
  if (fd_ >= 0) ::close(fd_);
}

Status RecordingWriter::writeRecord() {
  std::size_t done = 0;
  while (done < buffer_.size()) {
    const ssize_t n = ::write(fd_, buffer_.data() + done, buffer_.size() - done);
    if (n < 0) {
      if (errno == EINTR) continue;
      const int err = errno;
      buffer_.clear();
      return fail("{}: write failed: {}", path_, std::strerror(err));
    }
    done += static_cast<std::size_t>(n);
  }
  buffer_.clear();
  return {};
}

Status RecordingWriter::append(const SensorFrame& frame) {
  std::lock_guard lock(mutex_);
  encodeFrameRecord(frame, buffer_, version_);
  if (Status s = writeRecord(); !s) return s;
  ++frames_;
  return {};
}

Status RecordingWriter::appendCalibration(const CalibrationRecord& record) {
  std::lock_guard lock(mutex_);
  encodeCalibrationRecord(record, buffer_, version_);
  return writeRecord();
}

Status RecordingWriter::appendVoice(double time, std::span<const std::uint8_t> packet) {
  if (packet.empty() || packet.size() > kRecordingMaxVoicePacket || !std::isfinite(time)) {
    return fail("{}: voice packet of {} bytes at time {}: not recordable", path_, packet.size(),
                time);
  }
  std::lock_guard lock(mutex_);
  encodeVoiceRecord(time, packet, buffer_);
  if (Status s = writeRecord(); !s) return s;
  ++voice_;
  return {};
}

Status RecordingWriter::sync() {
  if (::fdatasync(fd_) != 0) return fail("{}: fdatasync failed: {}", path_, std::strerror(errno));
  return {};
}

RecordingSource::RecordingSource(Recording recording, std::string name)
    : recording_(std::move(recording)), name_(std::move(name)) {}

PollResult RecordingSource::poll(double /*timeout_s*/, SensorFrame& frame) {
  if (next_ >= recording_.frames.size()) {
    return PollResult::end(
        recording_.complete
            ? fmt::format("{}: end of recording ({} frames)", name_, next_)
            : fmt::format("end of the recording's good records: {}", recording_.stop_reason));
  }
  frame = recording_.frames[next_++];
  return PollResult::frame();
}

std::string RecordingSource::describe() const {
  return fmt::format("recording {} ({} frames{})", name_, recording_.frames.size(),
                     recording_.complete
                         ? ""
                         : fmt::format(", {} damaged bytes skipped in {} places",
                                       recording_.skipped_bytes, recording_.damage.size()));
}

}  // namespace vistel
