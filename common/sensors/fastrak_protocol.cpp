#include "common/sensors/fastrak_protocol.hpp"

#include <algorithm>
#include <charconv>
#include <cmath>
#include <cstring>

#include <fmt/format.h>

namespace vistel {
namespace {

constexpr float kMetresPerInch = 0.0254f;
constexpr float kMetresPerCentimetre = 0.01f;
// 16-bit items (PROTOCOLS.md, VESS): 8192 counts = 300 cm, 180 degrees, 1.0.
constexpr float kPosition16Metres = 3.0f / 8192.0f;
constexpr float kAngle16Degrees = 180.0f / 8192.0f;
constexpr float kQuat16Unit = 1.0f / 8192.0f;
constexpr int kAsciiField = 7;
constexpr float kMaxPositionUnits = 10000.0f;  // far beyond any tracker's range

float unitToMetres(LengthUnit units) {
  return units == LengthUnit::kInches ? kMetresPerInch : kMetresPerCentimetre;
}

bool validStatus(std::uint8_t c) {
  return c == ' ' || (c >= 'A' && c <= 'Z') || (c >= 'a' && c <= 'z');
}

// Reads n numbers of one item: binary float32 LE or 7-character ASCII fields.
bool readNumbers(std::span<const std::uint8_t> bytes, FastrakEncoding encoding, int n, float* out) {
  for (int i = 0; i < n; ++i) {
    if (encoding == FastrakEncoding::kBinary) {
      std::memcpy(&out[i], bytes.data() + 4 * i, 4);
    } else {
      const char* first = reinterpret_cast<const char*>(bytes.data()) + kAsciiField * i;
      const char* last = first + kAsciiField;
      while (first < last && *first == ' ') ++first;
      if (first < last && *first == '+') ++first;
      if (first == last) return false;
      const auto [end, ec] = std::from_chars(first, last, out[i]);
      if (ec != std::errc() || end != last) return false;
    }
    if (!std::isfinite(out[i])) return false;
  }
  return true;
}

// 16-bit binary value: low 7 bits of the first byte, then the second byte shifted left 7,
// 14 significant bits, sign-extended.
float read16(const std::uint8_t* p, float scale) {
  int v = ((static_cast<int>(p[1]) << 7) | (p[0] & 0x7F)) & 0x3FFF;
  if (v >= 0x2000) v -= 0x4000;
  return static_cast<float>(v) * scale;
}

void write16(std::string& out, float value, float scale) {
  const int v = std::clamp(static_cast<int>(std::lround(value / scale)), -0x2000, 0x1FFF);
  const int u = v & 0x3FFF;
  out.push_back(static_cast<char>(u & 0x7F));
  out.push_back(static_cast<char>(u >> 7));
}

void writeNumbers(std::string& out, FastrakEncoding encoding, std::span<const float> values,
                  int decimals) {
  for (float v : values) {
    if (encoding == FastrakEncoding::kBinary) {
      char raw[4];
      std::memcpy(raw, &v, 4);
      out.append(raw, 4);
    } else {
      out += fmt::format("{:{}.{}f}", v, kAsciiField, decimals);
    }
  }
}

bool plausibleEuler(const glm::vec3& e) {
  return std::abs(e.x) <= 180.5f && std::abs(e.y) <= 90.5f && std::abs(e.z) <= 180.5f;
}

}  // namespace

std::optional<FastrakItem> fastrakItemFromCode(int code) {
  switch (code) {
    case 0:
      return FastrakItem::kSpace;
    case 1:
      return FastrakItem::kCrLf;
    case 2:
      return FastrakItem::kPosition;
    case 3:
      return FastrakItem::kRelativePosition;
    case 4:
      return FastrakItem::kEuler;
    case 5:
      return FastrakItem::kDirectionCosines;
    case 11:
      return FastrakItem::kQuaternion;
    case 16:
      return FastrakItem::kStylus;
    case 18:
      return FastrakItem::kPosition16;
    case 19:
      return FastrakItem::kEuler16;
    case 20:
      return FastrakItem::kQuaternion16;
    default:
      return std::nullopt;
  }
}

Status validateFastrakFormat(const FastrakFormat& format) {
  if (format.items.empty()) return fail("fastrak output list is empty");
  if (format.items.size() > 32)
    return fail("fastrak output list has {} items (at most 32)", format.items.size());
  bool pose = false;
  for (FastrakItem item : format.items) {
    const bool is16 = item == FastrakItem::kPosition16 || item == FastrakItem::kEuler16 ||
                      item == FastrakItem::kQuaternion16;
    if (is16 && format.encoding == FastrakEncoding::kAscii) {
      return fail("fastrak output item {} exists only in binary mode", static_cast<int>(item));
    }
    if (item == FastrakItem::kPosition || item == FastrakItem::kPosition16 ||
        item == FastrakItem::kEuler || item == FastrakItem::kEuler16 ||
        item == FastrakItem::kQuaternion || item == FastrakItem::kQuaternion16 ||
        item == FastrakItem::kDirectionCosines) {
      pose = true;
    }
  }
  if (!pose) return fail("fastrak output list has no position or orientation item");
  return {};
}

std::size_t fastrakItemSize(FastrakItem item, FastrakEncoding encoding) {
  const bool bin = encoding == FastrakEncoding::kBinary;
  switch (item) {
    case FastrakItem::kSpace:
      return 1;
    case FastrakItem::kCrLf:
      return 2;
    case FastrakItem::kPosition:
    case FastrakItem::kRelativePosition:
    case FastrakItem::kEuler:
      return bin ? 12 : 3 * kAsciiField;
    case FastrakItem::kDirectionCosines:
      return bin ? 36 : 9 * kAsciiField;
    case FastrakItem::kQuaternion:
      return bin ? 16 : 4 * kAsciiField;
    case FastrakItem::kStylus:
      return 2;
    case FastrakItem::kPosition16:
    case FastrakItem::kEuler16:
      return 6;
    case FastrakItem::kQuaternion16:
      return 8;
  }
  return 0;
}

std::size_t fastrakRecordSize(const FastrakFormat& format) {
  std::size_t size = 3;
  for (FastrakItem item : format.items) size += fastrakItemSize(item, format.encoding);
  return size;
}

glm::quat fastrakEulerToQuat(const glm::vec3& e) {
  const glm::vec3 r = glm::radians(e);
  return glm::angleAxis(r.x, glm::vec3(0, 0, 1)) * glm::angleAxis(r.y, glm::vec3(0, 1, 0)) *
         glm::angleAxis(r.z, glm::vec3(1, 0, 0));
}

glm::vec3 fastrakQuatToEuler(const glm::quat& q) {
  // R = Rz(a) Ry(e) Rx(r): R[0][0] = ca ce, R[0][1] = sa ce (column 0), R[0][2] = -se,
  // R[1][2] = ce sr, R[2][2] = ce cr (glm is column-major: m[col][row]).
  const glm::mat3 m = glm::mat3_cast(q);
  const float se = std::clamp(-m[0][2], -1.0f, 1.0f);
  const float el = std::asin(se);
  float az = 0.0f;
  float roll = 0.0f;
  if (std::abs(se) < 0.99999f) {
    az = std::atan2(m[0][1], m[0][0]);
    roll = std::atan2(m[1][2], m[2][2]);
  } else {
    az = std::atan2(-m[1][0], m[1][1]);  // gimbal lock: put everything in azimuth
  }
  return glm::degrees(glm::vec3(az, el, roll));
}

bool decodeFastrakRecord(std::span<const std::uint8_t> bytes, const FastrakFormat& format,
                         FastrakRecord& out) {
  if (bytes.size() != fastrakRecordSize(format)) return false;
  if (bytes[0] != '0' || bytes[1] < '1' || bytes[1] > '0' + kFastrakMaxStations ||
      !validStatus(bytes[2])) {
    return false;
  }
  out = FastrakRecord{};
  out.station = bytes[1] - '0';
  out.status = static_cast<char>(bytes[2]);
  const float to_metres = unitToMetres(format.units);
  std::size_t pos = 3;
  for (FastrakItem item : format.items) {
    const std::size_t size = fastrakItemSize(item, format.encoding);
    const std::span<const std::uint8_t> field = bytes.subspan(pos, size);
    pos += size;
    float v[9];
    switch (item) {
      case FastrakItem::kSpace:
        if (field[0] != ' ') return false;
        break;
      case FastrakItem::kCrLf:
        if (field[0] != '\r' || field[1] != '\n') return false;
        break;
      case FastrakItem::kPosition:
      case FastrakItem::kRelativePosition: {
        if (!readNumbers(field, format.encoding, 3, v)) return false;
        for (int i = 0; i < 3; ++i) {
          if (std::abs(v[i]) > kMaxPositionUnits) return false;
        }
        const glm::vec3 p = glm::vec3(v[0], v[1], v[2]) * to_metres;
        if (item == FastrakItem::kPosition) {
          out.has_position = true;
          out.position = p;
        } else {
          out.has_relative = true;
          out.relative = p;
        }
        break;
      }
      case FastrakItem::kEuler: {
        if (!readNumbers(field, format.encoding, 3, v)) return false;
        out.euler_deg = glm::vec3(v[0], v[1], v[2]);
        if (!plausibleEuler(out.euler_deg)) return false;
        out.has_euler = true;
        if (!out.has_orientation) out.orientation = fastrakEulerToQuat(out.euler_deg);
        out.has_orientation = true;
        break;
      }
      case FastrakItem::kDirectionCosines: {
        if (!readNumbers(field, format.encoding, 9, v)) return false;
        glm::mat3 m;
        for (int c = 0; c < 3; ++c) {
          for (int r = 0; r < 3; ++r) {
            if (std::abs(v[3 * c + r]) > 1.01f) return false;
            m[c][r] = v[3 * c + r];
          }
        }
        if (std::abs(glm::determinant(m) - 1.0f) > 0.05f) return false;
        out.orientation = glm::normalize(glm::quat_cast(m));
        out.has_orientation = true;
        break;
      }
      case FastrakItem::kQuaternion: {
        if (!readNumbers(field, format.encoding, 4, v)) return false;
        const glm::quat q(v[0], v[1], v[2], v[3]);
        if (std::abs(glm::length(q) - 1.0f) > 0.05f) return false;
        out.orientation = glm::normalize(q);
        out.has_orientation = true;
        break;
      }
      case FastrakItem::kStylus:
        if (field[0] != ' ' || (field[1] != '0' && field[1] != '1')) return false;
        out.stylus = field[1] - '0';
        break;
      case FastrakItem::kPosition16:
        out.position =
            glm::vec3(read16(&field[0], kPosition16Metres), read16(&field[2], kPosition16Metres),
                      read16(&field[4], kPosition16Metres));
        out.has_position = true;
        break;
      case FastrakItem::kEuler16:
        out.euler_deg =
            glm::vec3(read16(&field[0], kAngle16Degrees), read16(&field[2], kAngle16Degrees),
                      read16(&field[4], kAngle16Degrees));
        if (!plausibleEuler(out.euler_deg)) return false;
        out.has_euler = true;
        if (!out.has_orientation) out.orientation = fastrakEulerToQuat(out.euler_deg);
        out.has_orientation = true;
        break;
      case FastrakItem::kQuaternion16: {
        const glm::quat q(read16(&field[0], kQuat16Unit), read16(&field[2], kQuat16Unit),
                          read16(&field[4], kQuat16Unit), read16(&field[6], kQuat16Unit));
        if (std::abs(glm::length(q) - 1.0f) > 0.05f) return false;
        out.orientation = glm::normalize(q);
        out.has_orientation = true;
        break;
      }
    }
  }
  return true;
}

void encodeFastrakRecord(const FastrakRecord& r, const FastrakFormat& format, std::string& out) {
  out.push_back('0');
  out.push_back(static_cast<char>('0' + r.station));
  out.push_back(r.status);
  const float per_unit = 1.0f / unitToMetres(format.units);
  const glm::vec3 euler = r.has_euler ? r.euler_deg : fastrakQuatToEuler(r.orientation);
  const glm::mat3 m = glm::mat3_cast(r.orientation);
  const glm::quat q = r.orientation;
  for (FastrakItem item : format.items) {
    switch (item) {
      case FastrakItem::kSpace:
        out.push_back(' ');
        break;
      case FastrakItem::kCrLf:
        out += "\r\n";
        break;
      case FastrakItem::kPosition:
      case FastrakItem::kRelativePosition: {
        const glm::vec3 p = (item == FastrakItem::kPosition ? r.position : r.relative) * per_unit;
        const float v[3] = {p.x, p.y, p.z};
        writeNumbers(out, format.encoding, v, 2);
        break;
      }
      case FastrakItem::kEuler: {
        const float v[3] = {euler.x, euler.y, euler.z};
        writeNumbers(out, format.encoding, v, 2);
        break;
      }
      case FastrakItem::kDirectionCosines: {
        float v[9];
        for (int c = 0; c < 3; ++c) {
          for (int k = 0; k < 3; ++k) v[3 * c + k] = m[c][k];
        }
        writeNumbers(out, format.encoding, v, 4);
        break;
      }
      case FastrakItem::kQuaternion: {
        const float v[4] = {q.w, q.x, q.y, q.z};
        writeNumbers(out, format.encoding, v, 4);
        break;
      }
      case FastrakItem::kStylus:
        out.push_back(' ');
        out.push_back(r.stylus > 0 ? '1' : '0');
        break;
      case FastrakItem::kPosition16:
        for (int i = 0; i < 3; ++i) write16(out, r.position[i], kPosition16Metres);
        break;
      case FastrakItem::kEuler16:
        for (int i = 0; i < 3; ++i) write16(out, euler[i], kAngle16Degrees);
        break;
      case FastrakItem::kQuaternion16:
        write16(out, q.w, kQuat16Unit);
        write16(out, q.x, kQuat16Unit);
        write16(out, q.y, kQuat16Unit);
        write16(out, q.z, kQuat16Unit);
        break;
    }
  }
}

std::string fastrakOutputListCommand(int station, std::span<const FastrakItem> items) {
  std::string cmd = fmt::format("O{}", station);
  for (FastrakItem item : items) cmd += fmt::format(",{}", static_cast<int>(item));
  cmd += '\r';
  return cmd;
}

std::string fastrakStationEnableCommand(int station, bool enable) {
  return fmt::format("l{},{}\r", station, enable ? 1 : 0);
}

std::vector<std::string> fastrakInitCommands(const FastrakFormat& format,
                                             std::span<const int> stations, bool continuous) {
  std::vector<std::string> cmds;
  cmds.emplace_back(kFastrakContinuousOff);
  for (int st = 1; st <= kFastrakMaxStations; ++st) {
    const bool on = std::find(stations.begin(), stations.end(), st) != stations.end();
    cmds.push_back(fastrakStationEnableCommand(st, on));
    if (on) cmds.push_back(fastrakOutputListCommand(st, format.items));
  }
  cmds.emplace_back(format.units == LengthUnit::kInches ? "U" : "u");
  cmds.emplace_back(format.encoding == FastrakEncoding::kBinary ? "f" : "F");
  if (continuous) cmds.emplace_back(kFastrakContinuousOn);
  return cmds;
}

}  // namespace vistel
