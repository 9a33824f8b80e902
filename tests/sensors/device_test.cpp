// Drivers against emulated devices: a FASTRAK-class tracker and a CyberGlove box on
// pseudo-terminals (every encoding, mode and unit; garbage between records; records split
// across reads; the device unplugged), the tracker over a fake USB bulk device, a HID tracker
// through a fake HID device, and the tracker + gloves merged.
#include <chrono>
#include <deque>
#include <thread>

#include <gtest/gtest.h>

#include "common/sensors/io/cyberglove_source.hpp"
#include "common/sensors/io/fastrak_source.hpp"
#include "common/sensors/io/hid_source.hpp"
#include "common/sensors/io/posture_source.hpp"
#include "common/sensors/io/serial_transport.hpp"
#include "common/sensors/io/usb_transport.hpp"
#include "tests/sensors/device_models.hpp"
#include "tests/sensors/humanoid.hpp"
#include "tests/sensors/pty_emulator.hpp"

namespace vistel {
namespace {

double now() {
  static const auto start = std::chrono::steady_clock::now();
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

// Each station holds a distinct pose (device axes, metres).
FastrakRecord stationPose(int st, double /*t*/) {
  FastrakRecord r;
  r.station = st;
  r.position = glm::vec3(0.1f * st, 0.2f + 0.01f * st, -0.3f);
  r.orientation = glm::angleAxis(0.3f * st, glm::normalize(glm::vec3(1, 2, 3)));
  r.stylus = 0;
  return r;
}

TrackerConfig trackerConfig(FastrakEncoding encoding, bool continuous, LengthUnit units) {
  TrackerConfig c;
  c.format.encoding = encoding;
  c.format.units = units;
  c.continuous = continuous;
  c.stations = {{1, BodySite::kHead},
                {2, BodySite::kChest},
                {3, BodySite::kLeftWrist},
                {4, BodySite::kRightWrist}};
  c.transmitter.rotation = glm::angleAxis(glm::radians(90.0f), glm::vec3(1, 0, 0));
  c.transmitter.position = glm::vec3(0.0f, 1.0f, 0.0f);
  c.reply_timeout_s = 1.0;
  return c;
}

void expectStations(const SensorFrame& f, const TrackerConfig& c, float tol_m, float tol_deg) {
  for (const StationMapping& m : c.stations) {
    const StationReading& s = f.station(m.site);
    ASSERT_TRUE(s.valid) << bodySiteName(m.site);
    const FastrakRecord want = stationPose(m.station, 0.0);
    const glm::vec3 p = c.transmitter.rotation * want.position + c.transmitter.position;
    EXPECT_LT(glm::distance(s.position, p), tol_m) << bodySiteName(m.site);
    EXPECT_LT(test::angleDegrees(s.orientation, c.transmitter.rotation * want.orientation),
              tol_deg);
  }
}

std::unique_ptr<test::PtyEmulator> startTracker(test::FastrakModel& model, double garbage,
                                                int chunk) {
  test::PtyOptions o;
  o.garbage_probability = garbage;
  o.max_chunk = chunk;
  o.seed = 17;
  return test::PtyEmulator::start(
      [&model](std::string_view in, double t, test::Pieces& out) { model.receive(in, t, out); },
      [&model](double t, test::Pieces& out) { model.tick(t, out); }, o);
}

// Polls until `want` frames arrived (or 3 s passed), checking each.
int pollFrames(SensorSource& source, const TrackerConfig& c, int want, float tol_m, float tol_deg) {
  SensorFrame f;
  int frames = 0;
  const double deadline = now() + 3.0;
  while (frames < want && now() < deadline) {
    const PollResult r = source.poll(0.2, f);
    if (r.status == PollStatus::kTimeout) continue;
    EXPECT_TRUE(r.isFrame()) << pollStatusName(r.status) << ": " << r.message;
    if (!r.isFrame()) break;
    // Streaming fills the stations one record at a time: count frames once all have come.
    bool all = true;
    for (const StationMapping& m : c.stations) all = all && f.station(m.site).valid;
    if (!all) continue;
    expectStations(f, c, tol_m, tol_deg);
    ++frames;
  }
  return frames;
}

struct TrackerCase {
  FastrakEncoding encoding;
  bool continuous;
  LengthUnit units;
};

class TrackerOnPty : public ::testing::TestWithParam<TrackerCase> {};

TEST_P(TrackerOnPty, ParsesThroughGarbageAndSplitReadsThenReportsUnplugging) {
  const TrackerCase c = GetParam();
  test::FastrakModel model(stationPose);
  auto pty = startTracker(model, 0.3, 7);
  ASSERT_NE(pty, nullptr);
  auto serial = SerialTransport::open(pty->path(), 115200);
  ASSERT_TRUE(serial.ok()) << serial.error().message;
  const TrackerConfig config = trackerConfig(c.encoding, c.continuous, c.units);
  auto source = FastrakSource::open(std::move(*serial), config);
  ASSERT_TRUE(source.ok()) << source.error().message;
  const bool ascii = c.encoding == FastrakEncoding::kAscii;
  EXPECT_EQ(pollFrames(**source, config, 12, ascii ? 3e-4f : 1e-5f, ascii ? 0.02f : 1e-3f), 12);
  // The unit was told what the config says.
  pty->withLock([&] {
    EXPECT_EQ(model.format().encoding, c.encoding);
    EXPECT_EQ(model.format().units, c.units);
    EXPECT_EQ(model.continuous(), c.continuous);
    EXPECT_EQ(model.format().items, config.format.items);
  });
  EXPECT_GT((*source)->recordCount(), 12u);
  if (!c.continuous) {
    pty->withLock([&] { EXPECT_GE(model.polls(), 12); });
  }
  EXPECT_GT(pty->garbageBytes(), 0u);

  // Unplug: the driver says so, and keeps saying so.
  pty->unplug();
  SensorFrame f;
  PollResult r;
  const double deadline = now() + 3.0;
  do {
    r = (*source)->poll(0.1, f);
  } while ((r.isFrame() || r.status == PollStatus::kTimeout) && now() < deadline);
  EXPECT_EQ(r.status, PollStatus::kUnplugged) << r.message;
  EXPECT_NE(r.message.find("unplugged"), std::string::npos) << r.message;
  EXPECT_EQ((*source)->poll(0.05, f).status, PollStatus::kUnplugged);
}

INSTANTIATE_TEST_SUITE_P(
    Modes, TrackerOnPty,
    ::testing::Values(TrackerCase{FastrakEncoding::kBinary, true, LengthUnit::kInches},
                      TrackerCase{FastrakEncoding::kBinary, false, LengthUnit::kInches},
                      TrackerCase{FastrakEncoding::kBinary, true, LengthUnit::kCentimetres},
                      TrackerCase{FastrakEncoding::kBinary, false, LengthUnit::kCentimetres},
                      TrackerCase{FastrakEncoding::kAscii, true, LengthUnit::kInches},
                      TrackerCase{FastrakEncoding::kAscii, false, LengthUnit::kInches},
                      TrackerCase{FastrakEncoding::kAscii, true, LengthUnit::kCentimetres},
                      TrackerCase{FastrakEncoding::kAscii, false, LengthUnit::kCentimetres}),
    [](const auto& param_info) {
      const TrackerCase& c = param_info.param;
      return std::string(c.encoding == FastrakEncoding::kBinary ? "Binary" : "Ascii") +
             (c.continuous ? "Continuous" : "Polled") +
             (c.units == LengthUnit::kInches ? "Inches" : "Centimetres");
    });

TEST(TrackerOnPty, SilentPortIsAClearError) {
  // A port with nothing behind it: no status reply.
  test::PtyOptions o;
  auto pty = test::PtyEmulator::start([](std::string_view, double, test::Pieces&) {},
                                      [](double, test::Pieces&) {}, o);
  ASSERT_NE(pty, nullptr);
  auto serial = SerialTransport::open(pty->path(), 115200);
  ASSERT_TRUE(serial.ok());
  TrackerConfig config = trackerConfig(FastrakEncoding::kBinary, true, LengthUnit::kInches);
  config.reply_timeout_s = 0.2;
  auto source = FastrakSource::open(std::move(*serial), config);
  ASSERT_FALSE(source.ok());
  EXPECT_NE(source.error().message.find("no status reply"), std::string::npos)
      << source.error().message;
  EXPECT_FALSE(SerialTransport::open("/dev/no-such-port", 115200).ok());
  EXPECT_FALSE(SerialTransport::open(pty->path(), 12345).ok());
}

// ---- Gloves ------------------------------------------------------------------------------

std::array<std::uint8_t, 22> gloveRaw(double) {
  std::array<std::uint8_t, 22> raw{};
  for (int i = 0; i < 22; ++i)
    raw[static_cast<std::size_t>(i)] = static_cast<std::uint8_t>(10 + 11 * i);
  return raw;
}

GloveDeviceConfig gloveConfig(int sensors, bool stream) {
  GloveDeviceConfig g;
  g.hand = Hand::kLeft;
  g.format.sensor_count = sensors;
  g.stream = stream;
  g.calibration = defaultGloveCalibration(sensors);
  g.reply_timeout_s = 1.0;
  return g;
}

void expectGlove(const GloveReading& got, const GloveDeviceConfig& config) {
  ASSERT_TRUE(got.valid);
  GloveRecord r;
  r.sensor_count = config.format.sensor_count;
  const auto raw = gloveRaw(0.0);
  std::copy(raw.begin(), raw.end(), r.raw.begin());
  GloveReading want;
  applyGloveCalibration(r, config.calibration, want);
  for (int i = 0; i < kGloveSensorCount; ++i)
    EXPECT_NEAR(got.angles[static_cast<std::size_t>(i)], want.angles[static_cast<std::size_t>(i)],
                1e-6f)
        << i;
}

struct GloveCase {
  int hardware;  // sensors the box has enabled at power-up
  int config;    // sensors the config asks for
  bool stream;
};

class GloveOnPty : public ::testing::TestWithParam<GloveCase> {};

TEST_P(GloveOnPty, ParsesThroughGarbageThenReportsUnplugging) {
  const GloveCase c = GetParam();
  test::GloveModel model(c.hardware, gloveRaw);
  test::PtyOptions o;
  o.garbage_probability = 0.3;
  o.garbage_excludes = "e";  // "eg" in line noise would read as a real error record
  o.max_chunk = 5;
  auto pty = test::PtyEmulator::start(
      [&model](std::string_view in, double t, test::Pieces& out) { model.receive(in, t, out); },
      [&model](double t, test::Pieces& out) { model.tick(t, out); }, o);
  ASSERT_NE(pty, nullptr);
  auto serial = SerialTransport::open(pty->path(), 115200);
  ASSERT_TRUE(serial.ok());
  const GloveDeviceConfig config = gloveConfig(c.config, c.stream);
  auto glove = CyberGloveSource::open(std::move(*serial), config);
  ASSERT_TRUE(glove.ok()) << glove.error().message;
  SensorFrame f;
  int frames = 0;
  const double deadline = now() + 3.0;
  while (frames < 10 && now() < deadline) {
    const PollResult r = (*glove)->poll(0.2, f);
    if (r.status == PollStatus::kTimeout) continue;
    ASSERT_TRUE(r.isFrame()) << r.message;
    expectGlove(f.glove(Hand::kLeft), config);
    ++frames;
  }
  EXPECT_EQ(frames, 10);
  pty->withLock([&] {
    EXPECT_EQ(model.format().sensor_count, c.config);
    EXPECT_EQ(model.streaming(), c.stream);
  });

  // Sampling errors are skipped; the glove pulled out of the box is "unplugged".
  pty->withLock([&] { model.setSamplingError(true); });
  for (int i = 0; i < 3; ++i) (void)(*glove)->poll(0.05, f);
  EXPECT_GT((*glove)->samplingErrors(), 0u);
  pty->withLock([&] {
    model.setSamplingError(false);
    model.setGlovePlugged(false);
  });
  PollResult r;
  double until = now() + 3.0;
  do {
    r = (*glove)->poll(0.1, f);
  } while ((r.isFrame() || r.status == PollStatus::kTimeout) && now() < until);
  EXPECT_EQ(r.status, PollStatus::kUnplugged);
  EXPECT_NE(r.message.find("glove not plugged in"), std::string::npos) << r.message;
  EXPECT_FALSE(f.glove(Hand::kLeft).valid);

  // The box itself goes away.
  pty->unplug();
  until = now() + 3.0;
  do {
    r = (*glove)->poll(0.1, f);
  } while (r.status != PollStatus::kUnplugged && now() < until);
  EXPECT_EQ(r.status, PollStatus::kUnplugged);
}

INSTANTIATE_TEST_SUITE_P(Modes, GloveOnPty,
                         ::testing::Values(GloveCase{22, 22, true}, GloveCase{18, 18, true},
                                           GloveCase{22, 22, false}, GloveCase{18, 18, false},
                                           GloveCase{18, 22, true}),
                         [](const auto& param_info) {
                           const GloveCase& c = param_info.param;
                           return "Box" + std::to_string(c.hardware) + "Config" +
                                  std::to_string(c.config) + (c.stream ? "Streaming" : "Polled");
                         });

// ---- Tracker + gloves ----------------------------------------------------------------------

TEST(SensorRig, MergesGlovesAndSurvivesAGloveUnplugging) {
  test::FastrakModel tracker_model(stationPose);
  auto tracker_pty = startTracker(tracker_model, 0.0, 0);
  test::GloveModel glove_model(22, gloveRaw);
  auto glove_pty = test::PtyEmulator::start(
      [&glove_model](std::string_view in, double t, test::Pieces& out) {
        glove_model.receive(in, t, out);
      },
      [&glove_model](double t, test::Pieces& out) { glove_model.tick(t, out); });
  ASSERT_TRUE(tracker_pty && glove_pty);
  const TrackerConfig tc = trackerConfig(FastrakEncoding::kBinary, true, LengthUnit::kInches);
  auto tracker =
      FastrakSource::open(std::move(*SerialTransport::open(tracker_pty->path(), 115200)), tc);
  ASSERT_TRUE(tracker.ok()) << tracker.error().message;
  const GloveDeviceConfig gc = gloveConfig(22, true);
  auto glove =
      CyberGloveSource::open(std::move(*SerialTransport::open(glove_pty->path(), 115200)), gc);
  ASSERT_TRUE(glove.ok()) << glove.error().message;
  std::vector<std::unique_ptr<SensorSource>> gloves;
  gloves.push_back(std::move(*glove));
  SensorRig rig(std::move(*tracker), std::move(gloves));
  SensorFrame f;
  int with_glove = 0;
  for (int i = 0; i < 40 && with_glove < 5; ++i) {
    if (!rig.poll(0.2, f).isFrame() || !f.station(BodySite::kRightWrist).valid) continue;
    expectStations(f, tc, 1e-5f, 1e-3f);
    if (f.glove(Hand::kLeft).valid) {
      expectGlove(f.glove(Hand::kLeft), gc);
      ++with_glove;
    }
  }
  EXPECT_EQ(with_glove, 5);
  glove_pty->unplug();
  int frames = 0;
  for (int i = 0; i < 40 && frames < 10; ++i) frames += rig.poll(0.2, f).isFrame() ? 1 : 0;
  EXPECT_EQ(frames, 10);  // the tracker carries on
  EXPECT_NE(rig.gloveStatus().find("unplugged"), std::string::npos) << rig.gloveStatus();
  EXPECT_NE(rig.describe().find("glove"), std::string::npos);
}

// ---- USB ---------------------------------------------------------------------------------

// A FASTRAK-class unit behind bulk endpoints: 64-byte IN packets (records split across
// packets), and "no device" once unplugged.
class FakeUsbTracker final : public UsbBulkDevice {
 public:
  explicit FakeUsbTracker(test::FastrakModel& model) : model_(model) {}
  UsbStatus bulkTransfer(std::uint8_t endpoint, std::uint8_t* data, int length, int& transferred,
                         unsigned timeout_ms, std::string& error) override {
    transferred = 0;
    if (unplugged) {
      error = "No such device (it may have been disconnected)";
      return UsbStatus::kNoDevice;
    }
    test::Pieces pieces;
    if ((endpoint & 0x80) == 0) {
      model_.receive(
          std::string_view(reinterpret_cast<const char*>(data), static_cast<std::size_t>(length)),
          now(), pieces);
      transferred = length;
    } else {
      model_.tick(now(), pieces);
    }
    for (const std::string& p : pieces) queue_ += p;
    if ((endpoint & 0x80) == 0) return UsbStatus::kOk;
    if (queue_.empty()) {
      std::this_thread::sleep_for(std::chrono::milliseconds(std::min(timeout_ms, 2u)));
      return UsbStatus::kTimeout;
    }
    const std::size_t n =
        std::min<std::size_t>({queue_.size(), 64, static_cast<std::size_t>(length)});
    std::memcpy(data, queue_.data(), n);
    queue_.erase(0, n);
    transferred = static_cast<int>(n);
    return UsbStatus::kOk;
  }
  std::string describe() const override { return "fake usb 0f44:0002"; }
  bool unplugged = false;

 private:
  test::FastrakModel& model_;
  std::string queue_;
};

TEST(TrackerOverUsb, ParsesPacketsAndReportsUnplugging) {
  for (bool continuous : {true, false}) {
    test::FastrakModel model(stationPose);
    auto device = std::make_unique<FakeUsbTracker>(model);
    FakeUsbTracker* fake = device.get();
    TrackerConfig config =
        trackerConfig(FastrakEncoding::kBinary, continuous, LengthUnit::kCentimetres);
    config.transport = TrackerTransport::kUsb;
    auto source =
        FastrakSource::open(std::make_unique<UsbTransport>(std::move(device), config.usb), config);
    ASSERT_TRUE(source.ok()) << source.error().message;
    EXPECT_EQ(pollFrames(**source, config, 10, 1e-5f, 1e-3f), 10);
    fake->unplugged = true;
    SensorFrame f;
    const PollResult r = (*source)->poll(0.1, f);
    EXPECT_EQ(r.status, PollStatus::kUnplugged) << r.message;
    EXPECT_NE(r.message.find("unplugged"), std::string::npos);
  }
}

// ---- HID ---------------------------------------------------------------------------------

class FakeHid final : public HidDevice {
 public:
  int read(std::uint8_t* data, std::size_t length, int /*timeout_ms*/) override {
    if (reports.empty()) return unplugged ? -1 : 0;
    const std::vector<std::uint8_t> r = reports.front();
    reports.pop_front();
    const std::size_t n = std::min(length, r.size());
    std::memcpy(data, r.data(), n);
    return static_cast<int>(n);
  }
  std::string lastError() const override { return "device disconnected"; }
  std::string describe() const override { return "fake hid"; }
  std::deque<std::vector<std::uint8_t>> reports;
  bool unplugged = false;
};

void put(std::vector<std::uint8_t>& r, int offset, HidValueType type, float value) {
  if (type == HidValueType::kF32) {
    std::memcpy(&r[static_cast<std::size_t>(offset)], &value, 4);
  } else if (type == HidValueType::kI16) {
    const auto v = static_cast<std::int16_t>(std::lround(value));
    std::memcpy(&r[static_cast<std::size_t>(offset)], &v, 2);
  } else {
    r[static_cast<std::size_t>(offset)] = static_cast<std::uint8_t>(value);
  }
}

std::vector<std::uint8_t> hidReport(const HidConfig& c, float shift) {
  std::vector<std::uint8_t> r(static_cast<std::size_t>(c.report_size), 0);
  if (c.report_id >= 0) r[0] = static_cast<std::uint8_t>(c.report_id);
  for (const HidStationLayout& l : c.stations) {
    const int s = static_cast<int>(l.site);
    const glm::vec3 p(0.1f * s + shift, 0.5f, -0.2f);
    const glm::quat q = glm::angleAxis(0.2f * s, glm::vec3(0, 1, 0));
    const int ps = l.position_type == HidValueType::kF32 ? 4 : 2;
    for (int k = 0; k < 3; ++k)
      put(r, l.position_offset + k * ps, l.position_type, p[k] / l.position_scale);
    const int qs = l.orientation_type == HidValueType::kF32 ? 4 : 2;
    const float qv[4] = {q.w, q.x, q.y, q.z};
    for (int k = 0; k < 4; ++k)
      put(r, l.orientation_offset + k * qs, l.orientation_type, qv[k] / l.orientation_scale);
    if (l.valid_offset >= 0) r[static_cast<std::size_t>(l.valid_offset)] = 1;
  }
  for (const HidGloveLayout& g : c.gloves) {
    for (int i = 0; i < g.sensor_count; ++i)
      r[static_cast<std::size_t>(g.offset + i)] = static_cast<std::uint8_t>(20 + 5 * i);
  }
  return r;
}

TEST(HidTracker, DecodesTheConfiguredLayoutSkipsBadReportsAndReportsUnplugging) {
  auto setup = loadSensorSetup("config/sensors/hid.toml");
  ASSERT_TRUE(setup.ok()) << setup.error().message;
  const HidConfig& c = setup->hid;
  auto device = std::make_unique<FakeHid>();
  FakeHid* fake = device.get();
  fake->reports.push_back(hidReport(c, 0.0f));
  std::vector<std::uint8_t> wrong_id = hidReport(c, 0.0f);
  wrong_id[0] = 9;
  fake->reports.push_back(wrong_id);
  std::vector<std::uint8_t> bad_quat = hidReport(c, 0.0f);
  const float two = 2.0f;
  std::memcpy(&bad_quat[static_cast<std::size_t>(c.stations[0].orientation_offset)], &two, 4);
  fake->reports.push_back(bad_quat);
  fake->reports.push_back(std::vector<std::uint8_t>(5, 1));  // short
  fake->reports.push_back(hidReport(c, 0.05f));
  HidSource source(std::move(device), c);
  SensorFrame f;
  ASSERT_TRUE(source.poll(0.1, f).isFrame());
  for (const HidStationLayout& l : c.stations) {
    const StationReading& s = f.station(l.site);
    ASSERT_TRUE(s.valid);
    const int k = static_cast<int>(l.site);
    EXPECT_NEAR(s.position.x, 0.1f * k, 2e-4f);
    EXPECT_NEAR(s.position.y, 0.5f, 2e-4f);
    EXPECT_LT(test::angleDegrees(s.orientation, glm::angleAxis(0.2f * k, glm::vec3(0, 1, 0))),
              0.01f);
  }
  ASSERT_TRUE(f.glove(Hand::kRight).valid);
  ASSERT_TRUE(source.poll(0.1, f).isFrame());  // skips the three bad reports
  EXPECT_EQ(source.rejectedReports(), 3u);
  EXPECT_NEAR(f.station(BodySite::kHead).position.x, 0.05f, 2e-4f);
  EXPECT_EQ(source.poll(0.01, f).status, PollStatus::kTimeout);
  fake->unplugged = true;
  const PollResult r = source.poll(0.01, f);
  EXPECT_EQ(r.status, PollStatus::kUnplugged);
  EXPECT_NE(r.message.find("device disconnected"), std::string::npos);
}

}  // namespace
}  // namespace vistel
