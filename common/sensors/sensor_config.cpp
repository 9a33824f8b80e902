#include "common/sensors/sensor_config.hpp"

#include <algorithm>
#include <initializer_list>

#include <toml++/toml.h>

#include "common/base/embedded.hpp"

namespace vistel {
namespace {

// Reads typed values out of TOML tables, remembering the first error (file, key, why).
class Reader {
 public:
  explicit Reader(std::string_view source) : source_(source) {}

  bool failed() const { return !error_.empty(); }
  Error error() const { return Error{error_}; }
  void fail(std::string_view key, std::string_view why) {
    if (error_.empty()) error_ = fmt::format("{}: {}: {}", source_, key, why);
  }

  // Rejects keys a table should not have (typos would otherwise be silently ignored).
  void allowOnly(const toml::table& t, std::string_view where,
                 std::initializer_list<std::string_view> keys) {
    for (const auto& [k, v] : t) {
      (void)v;
      if (std::find(keys.begin(), keys.end(), k.str()) == keys.end()) {
        fail(where, fmt::format("unknown key '{}'", k.str()));
      }
    }
  }

  std::string str(const toml::table& t, std::string_view key, std::string_view where,
                  std::string def) {
    const toml::node* n = t.get(key);
    if (n == nullptr) return def;
    if (auto v = n->value<std::string>()) return *v;
    fail(path(where, key), "expected a string");
    return def;
  }
  bool boolean(const toml::table& t, std::string_view key, std::string_view where, bool def) {
    const toml::node* n = t.get(key);
    if (n == nullptr) return def;
    if (auto v = n->value<bool>()) return *v;
    fail(path(where, key), "expected true or false");
    return def;
  }
  double number(const toml::table& t, std::string_view key, std::string_view where, double def,
                double lo, double hi) {
    const toml::node* n = t.get(key);
    if (n == nullptr) return def;
    std::optional<double> v;
    if (n->is_integer()) v = static_cast<double>(*n->value<std::int64_t>());
    if (n->is_floating_point()) v = *n->value<double>();
    if (!v) {
      fail(path(where, key), "expected a number");
      return def;
    }
    if (!(*v >= lo && *v <= hi)) {
      fail(path(where, key), fmt::format("{} is outside [{}, {}]", *v, lo, hi));
      return def;
    }
    return *v;
  }
  std::int64_t integer(const toml::table& t, std::string_view key, std::string_view where,
                       std::int64_t def, std::int64_t lo, std::int64_t hi) {
    const toml::node* n = t.get(key);
    if (n == nullptr) return def;
    auto v = n->value<std::int64_t>();
    if (!v || !n->is_integer()) {
      fail(path(where, key), "expected an integer");
      return def;
    }
    if (*v < lo || *v > hi) {
      fail(path(where, key), fmt::format("{} is outside [{}, {}]", *v, lo, hi));
      return def;
    }
    return *v;
  }
  std::vector<double> numbers(const toml::table& t, std::string_view key, std::string_view where,
                              std::size_t min_count, std::size_t max_count) {
    std::vector<double> out;
    const toml::node* n = t.get(key);
    if (n == nullptr) return out;
    const toml::array* a = n->as_array();
    if (a == nullptr) {
      fail(path(where, key), "expected an array of numbers");
      return out;
    }
    for (const toml::node& e : *a) {
      if (e.is_integer()) {
        out.push_back(static_cast<double>(*e.value<std::int64_t>()));
      } else if (e.is_floating_point()) {
        out.push_back(*e.value<double>());
      } else {
        fail(path(where, key), "expected an array of numbers");
        return {};
      }
    }
    if (out.size() < min_count || out.size() > max_count) {
      fail(path(where, key),
           fmt::format("has {} numbers (expected {}{})", out.size(), min_count,
                       min_count == max_count ? "" : fmt::format("..{}", max_count)));
      return {};
    }
    return out;
  }
  glm::vec3 vec3(const toml::table& t, std::string_view key, std::string_view where,
                 glm::vec3 def) {
    const std::vector<double> v = numbers(t, key, where, 3, 3);
    if (v.size() != 3) return def;
    return glm::vec3(static_cast<float>(v[0]), static_cast<float>(v[1]), static_cast<float>(v[2]));
  }
  template <typename E>
  E choice(const toml::table& t, std::string_view key, std::string_view where, E def,
           std::initializer_list<std::pair<std::string_view, E>> options) {
    const toml::node* n = t.get(key);
    if (n == nullptr) return def;
    const auto v = n->value<std::string>();
    std::string names;
    for (const auto& [name, value] : options) {
      if (v && *v == name) return value;
      names += fmt::format("{}'{}'", names.empty() ? "" : ", ", name);
    }
    fail(path(where, key), fmt::format("expected one of {}", names));
    return def;
  }
  const toml::table* table(const toml::table& t, std::string_view key, std::string_view where) {
    const toml::node* n = t.get(key);
    if (n == nullptr) return nullptr;
    if (const toml::table* tt = n->as_table()) return tt;
    fail(path(where, key), "expected a table");
    return nullptr;
  }
  std::vector<const toml::table*> tables(const toml::table& t, std::string_view key,
                                         std::string_view where) {
    std::vector<const toml::table*> out;
    const toml::node* n = t.get(key);
    if (n == nullptr) return out;
    const toml::array* a = n->as_array();
    if (a == nullptr) {
      fail(path(where, key), "expected an array of tables ([[...]])");
      return out;
    }
    for (const toml::node& e : *a) {
      if (const toml::table* tt = e.as_table()) {
        out.push_back(tt);
      } else {
        fail(path(where, key), "expected an array of tables ([[...]])");
      }
    }
    return out;
  }

 private:
  static std::string path(std::string_view where, std::string_view key) {
    return where.empty() ? std::string(key) : fmt::format("{}.{}", where, key);
  }
  std::string source_;
  std::string error_;
};

Result<toml::table> parseToml(std::string_view text, std::string_view source) {
  try {
    return toml::parse(text, std::string(source));
  } catch (const toml::parse_error& e) {
    return fail("{}:{}:{}: {}", source, e.source().begin.line, e.source().begin.column,
                e.description());
  }
}

// Degrees about the body axes (x = left, y = up, z = forward), x first: R = Rz Ry Rx.
glm::quat eulerDegrees(const glm::vec3& d) {
  return glm::angleAxis(glm::radians(d.z), glm::vec3(0, 0, 1)) *
         glm::angleAxis(glm::radians(d.y), glm::vec3(0, 1, 0)) *
         glm::angleAxis(glm::radians(d.x), glm::vec3(1, 0, 0));
}

TransmitterPlacement readPlacement(Reader& r, const toml::table& t, std::string_view where) {
  TransmitterPlacement p;
  glm::vec3 axis = r.vec3(t, "transmitter_axis", where, glm::vec3(1, 0, 0));
  const double angle = r.number(t, "transmitter_angle_deg", where, 0.0, -360.0, 360.0);
  if (glm::length(axis) < 1e-6f) {
    r.fail(std::string(where) + ".transmitter_axis", "must not be zero");
    axis = glm::vec3(1, 0, 0);
  }
  p.rotation = glm::angleAxis(glm::radians(static_cast<float>(angle)), glm::normalize(axis));
  p.position = r.vec3(t, "transmitter_position", where, glm::vec3(0.0f));
  return p;
}

GloveCalibration readGloveCalibration(Reader& r, const toml::table& t, std::string_view where,
                                      int sensors) {
  GloveCalibration cal = defaultGloveCalibration(sensors);
  const std::size_t n = static_cast<std::size_t>(sensors);
  const auto gain = r.numbers(t, "gain_deg", where, n, n);
  const auto offset = r.numbers(t, "offset", where, n, n);
  const auto lo = r.numbers(t, "min_deg", where, n, n);
  const auto hi = r.numbers(t, "max_deg", where, n, n);
  for (std::size_t i = 0; i < n; ++i) {
    GloveSensorCalibration& c = cal.sensors[i];
    if (!gain.empty()) c.gain = glm::radians(static_cast<float>(gain[i]));
    if (!offset.empty()) c.offset = static_cast<float>(offset[i]);
    if (!lo.empty()) c.min = glm::radians(static_cast<float>(lo[i]));
    if (!hi.empty()) c.max = glm::radians(static_cast<float>(hi[i]));
    if (c.min > c.max) r.fail(where, fmt::format("sensor {}: min_deg above max_deg", i));
  }
  return cal;
}

Result<GloveDeviceConfig> readGlove(Reader& r, const toml::table& t, std::string_view where) {
  r.allowOnly(t, where,
              {"hand", "port", "baud", "sensors", "timestamp", "status_byte", "mode",
               "reply_timeout_s", "gain_deg", "offset", "min_deg", "max_deg", "config"});
  GloveDeviceConfig g;
  g.hand =
      r.choice(t, "hand", where, Hand::kRight, {{"left", Hand::kLeft}, {"right", Hand::kRight}});
  g.port = r.str(t, "port", where, g.port);
  g.baud = static_cast<int>(r.integer(t, "baud", where, g.baud, 300, 4000000));
  g.format.sensor_count = static_cast<int>(r.integer(t, "sensors", where, 22, 18, 22));
  if (g.format.sensor_count != 18 && g.format.sensor_count != 22) {
    r.fail(std::string(where) + ".sensors", "must be 18 or 22");
    g.format.sensor_count = 22;
  }
  g.format.timestamp = r.boolean(t, "timestamp", where, false);
  g.format.status_byte = r.boolean(t, "status_byte", where, false);
  g.stream = r.choice(t, "mode", where, true, {{"stream", true}, {"poll", false}});
  g.reply_timeout_s = r.number(t, "reply_timeout_s", where, 1.0, 0.01, 60.0);
  g.calibration = readGloveCalibration(r, t, where, g.format.sensor_count);
  return g;
}

HidValueType hidType(Reader& r, const toml::table& t, std::string_view key,
                     std::string_view where) {
  return r.choice(
      t, key, where, HidValueType::kF32,
      {{"f32", HidValueType::kF32}, {"i16", HidValueType::kI16}, {"u8", HidValueType::kU8}});
}

void readHid(Reader& r, const toml::table& t, HidConfig& hid) {
  const std::string where = "hid";
  r.allowOnly(t, where,
              {"vendor_id", "product_id", "serial", "report_id", "report_size", "station", "glove",
               "transmitter_axis", "transmitter_angle_deg", "transmitter_position"});
  hid.vendor_id = static_cast<std::uint16_t>(r.integer(t, "vendor_id", where, 0, 0, 0xFFFF));
  hid.product_id = static_cast<std::uint16_t>(r.integer(t, "product_id", where, 0, 0, 0xFFFF));
  hid.serial = r.str(t, "serial", where, "");
  hid.report_id = static_cast<int>(r.integer(t, "report_id", where, -1, -1, 255));
  hid.report_size = static_cast<int>(r.integer(t, "report_size", where, 64, 1, 4096));
  hid.transmitter = readPlacement(r, t, where);
  for (const toml::table* s : r.tables(t, "station", where)) {
    const std::string w = "hid.station";
    r.allowOnly(*s, w,
                {"site", "position_offset", "position_type", "position_scale", "orientation_offset",
                 "orientation_type", "orientation_scale", "valid_offset"});
    HidStationLayout l;
    l.site = r.choice(*s, "site", w, BodySite::kHead,
                      {{"head", BodySite::kHead},
                       {"chest", BodySite::kChest},
                       {"left_wrist", BodySite::kLeftWrist},
                       {"right_wrist", BodySite::kRightWrist},
                       {"left_foot", BodySite::kLeftFoot},
                       {"right_foot", BodySite::kRightFoot}});
    l.position_offset = static_cast<int>(r.integer(*s, "position_offset", w, 0, 0, 4095));
    l.position_type = hidType(r, *s, "position_type", w);
    l.position_scale = static_cast<float>(r.number(*s, "position_scale", w, 1.0, -1e6, 1e6));
    l.orientation_offset = static_cast<int>(r.integer(*s, "orientation_offset", w, 12, 0, 4095));
    l.orientation_type = hidType(r, *s, "orientation_type", w);
    l.orientation_scale = static_cast<float>(r.number(*s, "orientation_scale", w, 1.0, -1e6, 1e6));
    l.valid_offset = static_cast<int>(r.integer(*s, "valid_offset", w, -1, -1, 4095));
    hid.stations.push_back(l);
  }
  for (const toml::table* g : r.tables(t, "glove", where)) {
    const std::string w = "hid.glove";
    r.allowOnly(*g, w,
                {"hand", "offset", "sensors", "gain_deg", "offset_counts", "min_deg", "max_deg"});
    HidGloveLayout l;
    l.hand =
        r.choice(*g, "hand", w, Hand::kRight, {{"left", Hand::kLeft}, {"right", Hand::kRight}});
    l.offset = static_cast<int>(r.integer(*g, "offset", w, 0, 0, 4095));
    l.sensor_count = static_cast<int>(r.integer(*g, "sensors", w, 22, 18, 22));
    if (l.sensor_count != 18 && l.sensor_count != 22) r.fail(w + ".sensors", "must be 18 or 22");
    l.calibration = defaultGloveCalibration(l.sensor_count == 18 ? 18 : 22);
    hid.gloves.push_back(l);
  }
  // Every field must fit in the report.
  auto size = [](HidValueType type) {
    return type == HidValueType::kF32 ? 4 : type == HidValueType::kI16 ? 2 : 1;
  };
  for (const HidStationLayout& l : hid.stations) {
    if (l.position_offset + 3 * size(l.position_type) > hid.report_size ||
        l.orientation_offset + 4 * size(l.orientation_type) > hid.report_size ||
        l.valid_offset >= hid.report_size) {
      r.fail("hid.station", fmt::format("{} fields reach past the {}-byte report",
                                        bodySiteName(l.site), hid.report_size));
    }
  }
  for (const HidGloveLayout& l : hid.gloves) {
    if (l.offset + l.sensor_count > hid.report_size) {
      r.fail("hid.glove", fmt::format("{} glove reaches past the {}-byte report", handName(l.hand),
                                      hid.report_size));
    }
  }
}

// [force_feedback] and its [[force_feedback.channel]]s: every channel inside the report,
// after the report id byte, none overlapping another.
void readForceFeedback(Reader& r, const toml::table& t, ForceFeedbackConfig& ff) {
  const std::string where = "force_feedback";
  r.allowOnly(
      t, where,
      {"vendor_id", "product_id", "serial", "report_id", "report_size", "max_rate_hz", "channel"});
  ff.enabled = true;
  ff.vendor_id = static_cast<std::uint16_t>(r.integer(t, "vendor_id", where, 0, 0, 0xFFFF));
  ff.product_id = static_cast<std::uint16_t>(r.integer(t, "product_id", where, 0, 0, 0xFFFF));
  ff.serial = r.str(t, "serial", where, "");
  ff.report_id = static_cast<int>(r.integer(t, "report_id", where, 0, 0, 255));
  ff.report_size = static_cast<int>(r.integer(t, "report_size", where, 64, 2, 4096));
  ff.max_rate_hz = r.number(t, "max_rate_hz", where, 60.0, 0.1, 1000.0);
  const std::vector<const toml::table*> channels = r.tables(t, "channel", where);
  if (channels.empty() && !r.failed()) {
    r.fail(where + ".channel", "no channels ([[force_feedback.channel]] with part and offset)");
  }
  std::vector<std::uint8_t> used(static_cast<std::size_t>(ff.report_size), 0);
  for (std::size_t i = 0; i < channels.size() && !r.failed(); ++i) {
    const toml::table& c = *channels[i];
    const std::string w = fmt::format("force_feedback.channel[{}]", i);
    r.allowOnly(c, w, {"part", "offset", "type", "scale", "axis"});
    ForceFeedbackChannel ch;
    if (c.get("part") == nullptr) r.fail(w + ".part", "missing (the avatar's primitive name)");
    ch.part = r.str(c, "part", w, "");
    if (ch.part.empty() && !r.failed()) r.fail(w + ".part", "must not be empty");
    if (c.get("offset") == nullptr) r.fail(w + ".offset", "missing (byte offset in the report)");
    ch.offset = static_cast<int>(r.integer(c, "offset", w, 1, 1, 4095));
    ch.type = hidType(r, c, "type", w);
    if (c.get("type") == nullptr) ch.type = HidValueType::kU8;
    ch.scale = static_cast<float>(r.number(c, "scale", w, 1.0, 1e-9, 1e9));
    ch.component = r.choice(c, "axis", w, ForceComponent::kMagnitude,
                            {{"x", ForceComponent::kX},
                             {"y", ForceComponent::kY},
                             {"z", ForceComponent::kZ},
                             {"magnitude", ForceComponent::kMagnitude}});
    if (r.failed()) break;
    const int size = ch.type == HidValueType::kF32 ? 4 : ch.type == HidValueType::kI16 ? 2 : 1;
    if (ch.offset + size > ff.report_size) {
      r.fail(w + ".offset", fmt::format("{} + {} bytes reaches past the {}-byte report", ch.offset,
                                        size, ff.report_size));
      break;
    }
    for (int b = ch.offset; b < ch.offset + size; ++b) {
      if (used[static_cast<std::size_t>(b)] != 0) {
        r.fail(w + ".offset", fmt::format("byte {} is already taken by channel[{}]", b,
                                          static_cast<int>(used[static_cast<std::size_t>(b)]) - 1));
        break;
      }
      used[static_cast<std::size_t>(b)] =
          static_cast<std::uint8_t>(std::min<std::size_t>(i + 1, 255));
    }
    ff.channels.push_back(std::move(ch));
  }
}

}  // namespace

Result<GloveDeviceConfig> parseGloveConfig(std::string_view toml_text,
                                           std::string_view source_name) {
  Result<toml::table> t = parseToml(toml_text, source_name);
  if (!t) return t.error();
  Reader r(source_name);
  Result<GloveDeviceConfig> g = readGlove(r, *t, "");
  if (r.failed()) return r.error();
  return g;
}

Result<SensorSetup> parseSensorSetup(std::string_view toml_text, std::string_view source_name) {
  Result<toml::table> parsed = parseToml(toml_text, source_name);
  if (!parsed) return parsed.error();
  const toml::table& root = *parsed;
  Reader r(source_name);
  SensorSetup setup;
  setup.source = std::string(source_name);
  setup.text = std::string(toml_text);
  r.allowOnly(root, "",
              {"participant", "tracker", "station", "glove", "hid", "solver", "calibration", "sim",
               "force_feedback"});
  setup.participant = r.str(root, "participant", "", "participant");

  // The tracker.
  if (const toml::table* t = r.table(root, "tracker", "")) {
    const std::string w = "tracker";
    r.allowOnly(*t, w,
                {"kind", "transport", "port", "baud", "encoding", "mode", "units", "output_list",
                 "reply_timeout_s", "check_status", "transmitter_axis", "transmitter_angle_deg",
                 "transmitter_position", "usb", "position_noise_m", "orientation_noise_deg"});
    setup.tracker_kind = r.choice(*t, "kind", w, TrackerKind::kFastrak,
                                  {{"fastrak", TrackerKind::kFastrak},
                                   {"hid", TrackerKind::kHid},
                                   {"none", TrackerKind::kNone}});
    TrackerConfig& tc = setup.tracker;
    tc.transport =
        r.choice(*t, "transport", w, TrackerTransport::kSerial,
                 {{"serial", TrackerTransport::kSerial}, {"usb", TrackerTransport::kUsb}});
    tc.port = r.str(*t, "port", w, tc.port);
    tc.baud = static_cast<int>(r.integer(*t, "baud", w, tc.baud, 300, 4000000));
    tc.format.encoding =
        r.choice(*t, "encoding", w, FastrakEncoding::kBinary,
                 {{"binary", FastrakEncoding::kBinary}, {"ascii", FastrakEncoding::kAscii}});
    tc.continuous = r.choice(*t, "mode", w, true, {{"continuous", true}, {"poll", false}});
    tc.format.units =
        r.choice(*t, "units", w, LengthUnit::kInches,
                 {{"inches", LengthUnit::kInches}, {"centimetres", LengthUnit::kCentimetres}});
    const std::vector<double> list = r.numbers(*t, "output_list", w, 1, 32);
    if (!list.empty()) {
      tc.format.items.clear();
      for (double code : list) {
        const auto item = fastrakItemFromCode(static_cast<int>(code));
        if (!item || code != static_cast<int>(code)) {
          r.fail(w + ".output_list", fmt::format("item code {} is not one vistel decodes", code));
          break;
        }
        tc.format.items.push_back(*item);
      }
    }
    if (!r.failed()) {
      if (Status s = validateFastrakFormat(tc.format); !s)
        r.fail(w + ".output_list", s.error().message);
    }
    tc.reply_timeout_s = r.number(*t, "reply_timeout_s", w, 1.0, 0.01, 60.0);
    tc.check_status = r.boolean(*t, "check_status", w, true);
    tc.transmitter = readPlacement(r, *t, w);
    // The tracker's noise model: the station filter's reading variance.
    for (StationFilterParams& f : setup.solver.station_filters) {
      f.position_noise_m =
          static_cast<float>(r.number(*t, "position_noise_m", w, f.position_noise_m, 0, 1));
      f.orientation_noise_deg = static_cast<float>(
          r.number(*t, "orientation_noise_deg", w, f.orientation_noise_deg, 0, 90));
    }
    if (const toml::table* u = r.table(*t, "usb", w)) {
      const std::string wu = "tracker.usb";
      r.allowOnly(*u, wu, {"vendor_id", "product_id", "interface", "endpoint_out", "endpoint_in"});
      tc.usb.vendor_id = static_cast<std::uint16_t>(r.integer(*u, "vendor_id", wu, 0, 0, 0xFFFF));
      tc.usb.product_id = static_cast<std::uint16_t>(r.integer(*u, "product_id", wu, 0, 0, 0xFFFF));
      tc.usb.interface_number = static_cast<int>(r.integer(*u, "interface", wu, 0, 0, 255));
      tc.usb.endpoint_out =
          static_cast<std::uint8_t>(r.integer(*u, "endpoint_out", wu, 0x02, 0, 0x7F));
      tc.usb.endpoint_in =
          static_cast<std::uint8_t>(r.integer(*u, "endpoint_in", wu, 0x82, 0x80, 0xFF));
    }
  }

  // Stations: which device station is worn where, and the nominal mounting.
  std::array<bool, kBodySiteCount> seen{};
  for (const toml::table* s : r.tables(root, "station", "")) {
    const std::string w = "station";
    r.allowOnly(*s, w, {"number", "site", "mount_offset", "mount_rotation_deg"});
    StationMapping m;
    m.station = static_cast<int>(r.integer(*s, "number", w, 0, 0, kFastrakMaxStations));
    m.site = r.choice(*s, "site", w, BodySite::kHead,
                      {{"head", BodySite::kHead},
                       {"chest", BodySite::kChest},
                       {"left_wrist", BodySite::kLeftWrist},
                       {"right_wrist", BodySite::kRightWrist},
                       {"left_foot", BodySite::kLeftFoot},
                       {"right_foot", BodySite::kRightFoot}});
    const int si = static_cast<int>(m.site);
    if (seen[si]) r.fail(w, fmt::format("site '{}' listed twice", bodySiteName(m.site)));
    seen[si] = true;
    for (const StationMapping& other : setup.tracker.stations) {
      if (m.station != 0 && other.station == m.station)
        r.fail(w, fmt::format("station {} listed twice", m.station));
    }
    setup.tracker.stations.push_back(m);
    SensorMount& mount = setup.mounts[si];
    mount.site = m.site;
    mount.offset = r.vec3(*s, "mount_offset", w, mount.offset);
    if (s->get("mount_rotation_deg") != nullptr) {
      mount.rotation = eulerDegrees(r.vec3(*s, "mount_rotation_deg", w, glm::vec3(0.0f)));
    }
  }
  if (setup.tracker_kind == TrackerKind::kFastrak && !r.failed()) {
    for (int s = 0; s < kUpperBodySiteCount; ++s) {
      if (!seen[s]) {
        r.fail("station", fmt::format("no station is worn at '{}' (the solver needs all four)",
                                      bodySiteName(static_cast<BodySite>(s))));
        break;
      }
    }
    if (setup.tracker.stations.size() > static_cast<std::size_t>(kFastrakMaxStations) &&
        !r.failed()) {
      r.fail("station",
             fmt::format("{} stations, but a FASTRAK has {} receivers (foot trackers need a "
                         "tracker with six, e.g. kind = \"hid\")",
                         setup.tracker.stations.size(), kFastrakMaxStations));
    }
  }

  // Gloves: a file each, with the port overridable here.
  for (const toml::table* g : r.tables(root, "glove", "")) {
    const std::string w = "glove";
    r.allowOnly(*g, w, {"hand", "config", "port"});
    const std::string file = r.str(*g, "config", w, "config/sensors/cyberglove.toml");
    if (r.failed()) break;
    Result<std::string> text = readConfigText(file);
    if (!text) {
      r.fail(w + ".config", text.error().message);
      break;
    }
    Result<GloveDeviceConfig> glove = parseGloveConfig(*text, file);
    if (!glove) {
      r.fail(w + ".config", glove.error().message);
      break;
    }
    glove->hand =
        r.choice(*g, "hand", w, glove->hand, {{"left", Hand::kLeft}, {"right", Hand::kRight}});
    glove->port = r.str(*g, "port", w, glove->port);
    for (const GloveDeviceConfig& other : setup.gloves) {
      if (other.hand == glove->hand) r.fail(w, fmt::format("two {} gloves", handName(glove->hand)));
    }
    setup.gloves.push_back(std::move(*glove));
  }

  if (const toml::table* h = r.table(root, "hid", "")) readHid(r, *h, setup.hid);
  if (setup.tracker_kind == TrackerKind::kHid && !r.failed()) {
    // The four upper-body sites, each once; the feet optional.
    std::array<int, kBodySiteCount> laid{};
    for (const HidStationLayout& l : setup.hid.stations) ++laid[static_cast<std::size_t>(l.site)];
    for (int site = 0; site < kBodySiteCount; ++site) {
      const int n = laid[static_cast<std::size_t>(site)];
      if (n > 1 || (n == 0 && site < kUpperBodySiteCount)) {
        r.fail("hid.station",
               fmt::format("{} stations laid out at '{}' (the solver needs the four upper-body "
                           "sites once each; the feet are optional)",
                           n, bodySiteName(static_cast<BodySite>(site))));
        break;
      }
    }
  }

  // Solver.
  if (const toml::table* t = r.table(root, "solver", "")) {
    const std::string w = "solver";
    r.allowOnly(*t, w,
                {"stance",
                 "filter",
                 "predict",
                 "position_min_cutoff_hz",
                 "position_beta",
                 "orientation_min_cutoff_hz",
                 "orientation_beta",
                 "predict_cutoff_hz",
                 "stale_after_s",
                 "blend_back_s",
                 "pelvis_tilt_share",
                 "pelvis_twist_limit_deg",
                 "clavicle_lift_start_deg",
                 "clavicle_lift_gain",
                 "clavicle_lift_max_deg",
                 "joint_limits",
                 "fingers",
                 "station_filter",
                 "kalman_cutoff_hz",
                 "head_position_cutoff_hz",
                 "wrist_position_cutoff_hz",
                 "wrist_beta",
                 "chest_cutoff_hz",
                 "chest_beta",
                 "ease_intervals",
                 "hips_cutoff_hz",
                 "hips_beta",
                 "foot_position_cutoff_hz",
                 "foot_beta"});
    SolverOptions& o = setup.solver;
    o.filter_kind = r.choice(
        *t, "station_filter", w, o.filter_kind,
        {{"kalman", StationFilterKind::kKalman}, {"one_euro", StationFilterKind::kOneEuro}});
    for (int site = 0; site < kBodySiteCount; ++site) {
      StationFilterParams& f = o.station_filters[static_cast<std::size_t>(site)];
      if (site == static_cast<int>(BodySite::kChest)) {
        f.position_cutoff_hz = f.orientation_cutoff_hz =
            static_cast<float>(r.number(*t, "chest_cutoff_hz", w, f.position_cutoff_hz, 0.01, 100));
        f.position_beta =
            static_cast<float>(r.number(*t, "chest_beta", w, f.position_beta, 0, 100));
      } else {
        f.orientation_cutoff_hz = static_cast<float>(
            r.number(*t, "kalman_cutoff_hz", w, f.orientation_cutoff_hz, 0.01, 100));
        if (site == static_cast<int>(BodySite::kHead)) {
          f.position_cutoff_hz = static_cast<float>(
              r.number(*t, "head_position_cutoff_hz", w, f.position_cutoff_hz, 0.01, 100));
        } else if (isFootSite(static_cast<BodySite>(site))) {
          f.position_cutoff_hz = static_cast<float>(
              r.number(*t, "foot_position_cutoff_hz", w, f.position_cutoff_hz, 0.01, 100));
          f.position_beta =
              static_cast<float>(r.number(*t, "foot_beta", w, f.position_beta, 0, 100));
        } else {
          f.position_cutoff_hz = static_cast<float>(
              r.number(*t, "wrist_position_cutoff_hz", w, f.position_cutoff_hz, 0.01, 100));
          f.position_beta =
              static_cast<float>(r.number(*t, "wrist_beta", w, f.position_beta, 0, 100));
        }
      }
      f.ease_intervals = r.number(*t, "ease_intervals", w, f.ease_intervals, 0, 4);
    }
    o.hips_cutoff_hz =
        static_cast<float>(r.number(*t, "hips_cutoff_hz", w, o.hips_cutoff_hz, 0, 100));
    o.hips_beta = static_cast<float>(r.number(*t, "hips_beta", w, o.hips_beta, 0, 100));
    o.stance = r.choice(*t, "stance", w, o.stance,
                        {{"standing", Stance::kStanding}, {"seated", Stance::kSeated}});
    o.filter = r.boolean(*t, "filter", w, o.filter);
    o.predict = r.boolean(*t, "predict", w, o.predict);
    o.position_filter.min_cutoff_hz = static_cast<float>(
        r.number(*t, "position_min_cutoff_hz", w, o.position_filter.min_cutoff_hz, 0.01, 100));
    o.position_filter.beta =
        static_cast<float>(r.number(*t, "position_beta", w, o.position_filter.beta, 0, 1000));
    o.orientation_filter.min_cutoff_hz = static_cast<float>(r.number(
        *t, "orientation_min_cutoff_hz", w, o.orientation_filter.min_cutoff_hz, 0.01, 100));
    o.orientation_filter.beta =
        static_cast<float>(r.number(*t, "orientation_beta", w, o.orientation_filter.beta, 0, 1000));
    const float predict_cutoff = static_cast<float>(
        r.number(*t, "predict_cutoff_hz", w, o.position_filter.predict_cutoff_hz, 0.01, 100));
    o.position_filter.predict_cutoff_hz = o.orientation_filter.predict_cutoff_hz = predict_cutoff;
    o.stale_after_s = r.number(*t, "stale_after_s", w, o.stale_after_s, 0.001, 10);
    o.blend_back_s = r.number(*t, "blend_back_s", w, o.blend_back_s, 0.001, 10);
    o.pelvis_tilt_share =
        static_cast<float>(r.number(*t, "pelvis_tilt_share", w, o.pelvis_tilt_share, 0, 1));
    o.pelvis_twist_limit_deg = static_cast<float>(
        r.number(*t, "pelvis_twist_limit_deg", w, o.pelvis_twist_limit_deg, 0, 180));
    o.clavicle_lift_start_deg = static_cast<float>(
        r.number(*t, "clavicle_lift_start_deg", w, o.clavicle_lift_start_deg, 0, 180));
    o.clavicle_lift_gain =
        static_cast<float>(r.number(*t, "clavicle_lift_gain", w, o.clavicle_lift_gain, 0, 2));
    o.clavicle_lift_max_deg = static_cast<float>(
        r.number(*t, "clavicle_lift_max_deg", w, o.clavicle_lift_max_deg, 0, 90));
    o.joint_limits = r.boolean(*t, "joint_limits", w, o.joint_limits);
    o.fingers = r.boolean(*t, "fingers", w, o.fingers);
  }

  // Calibration.
  if (const toml::table* t = r.table(root, "calibration", "")) {
    const std::string w = "calibration";
    r.allowOnly(*t, w, {"alignment", "estimate_proportions", "floor_height", "window_s"});
    CalibrationOptions& c = setup.calibration;
    c.alignment = r.choice(*t, "alignment", w, c.alignment,
                           {{"fixed", AlignmentMode::kFixed}, {"facing", AlignmentMode::kFacing}});
    c.estimate_proportions = r.boolean(*t, "estimate_proportions", w, c.estimate_proportions);
    c.floor_height = static_cast<float>(r.number(*t, "floor_height", w, c.floor_height, -100, 100));
    c.window_s = r.number(*t, "window_s", w, c.window_s, 0.01, 60);
  }
  setup.calibration.nominal_mounts = setup.mounts;

  // Simulator.
  if (const toml::table* t = r.table(root, "sim", "")) {
    const std::string w = "sim";
    r.allowOnly(
        *t, w,
        {"rate_hz", "shared_rate", "latency_s", "position_noise_m", "orientation_noise_deg", "seed",
         "glove", "glove_period_s", "hold_s", "random_dropout_rate_hz", "random_dropout_s"});
    SimOptions& s = setup.sim;
    s.rate_hz = r.number(*t, "rate_hz", w, s.rate_hz, 1, 10000);
    s.shared_rate = r.boolean(*t, "shared_rate", w, s.shared_rate);
    s.latency_s = r.number(*t, "latency_s", w, s.latency_s, 0, 10);
    s.position_noise_m =
        static_cast<float>(r.number(*t, "position_noise_m", w, s.position_noise_m, 0, 1));
    s.orientation_noise_deg = static_cast<float>(
        r.number(*t, "orientation_noise_deg", w, s.orientation_noise_deg, 0, 90));
    s.seed = static_cast<std::uint64_t>(
        r.integer(*t, "seed", w, static_cast<std::int64_t>(s.seed), 0, INT64_MAX));
    s.glove = r.choice(*t, "glove", w, s.glove,
                       {{"neutral", GlovePattern::kNeutral},
                        {"grasp", GlovePattern::kGrasp},
                        {"point", GlovePattern::kPoint},
                        {"spread", GlovePattern::kSpread},
                        {"cycle", GlovePattern::kCycle}});
    s.glove_period_s = r.number(*t, "glove_period_s", w, s.glove_period_s, 0.01, 1000);
    s.hold_s = r.number(*t, "hold_s", w, s.hold_s, 0, 1000);
    s.random_dropout_rate_hz =
        r.number(*t, "random_dropout_rate_hz", w, s.random_dropout_rate_hz, 0, 100);
    s.random_dropout_s = r.number(*t, "random_dropout_s", w, s.random_dropout_s, 0, 100);
  }
  setup.sim.mounts = setup.mounts;
  // A setup that lists a foot station simulates both feet (six stations).
  setup.sim.foot_trackers = seen[static_cast<std::size_t>(BodySite::kLeftFoot)] ||
                            seen[static_cast<std::size_t>(BodySite::kRightFoot)];

  // Force feedback.
  if (const toml::table* t = r.table(root, "force_feedback", "")) {
    readForceFeedback(r, *t, setup.force_feedback);
  }
  if (r.failed()) return r.error();
  return setup;
}

Result<SensorSetup> loadSensorSetup(const std::string& path) {
  Result<std::string> text = readConfigText(path);
  if (!text) return text.error();
  return parseSensorSetup(*text, path);
}

}  // namespace vistel
