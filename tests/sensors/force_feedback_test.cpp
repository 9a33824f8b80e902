// The force-feedback output (issue 25 item 10): the [force_feedback] section of a sensors
// config (what it says, and errors naming the file and key), the report encoding per channel
// type and axis, and ForceFeedbackWriter on a fake HID device: reports only on change, at
// most at the configured rate, the newest forces delivered late rather than lost, a zero
// report at close, one error when the device goes away.
#include <cstring>
#include <deque>
#include <memory>
#include <sstream>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "common/sensors/io/force_feedback.hpp"
#include "common/sensors/sensor_config.hpp"
#include "tests/sensors/setup_errors.hpp"

namespace vistel {
namespace {

constexpr const char* kConfig = R"(
[force_feedback]
vendor_id = 0x1234
product_id = 0x4321
serial = "FF01"
report_id = 5
report_size = 12
max_rate_hz = 50

[[force_feedback.channel]]
part = "l_hand"
offset = 1
scale = 0.1              # u8 magnitude by default

[[force_feedback.channel]]
part = "l_hand"
offset = 2
type = "i16"
scale = 0.01
axis = "y"

[[force_feedback.channel]]
part = "head"
offset = 4
type = "f32"
scale = 0.5
axis = "x"

[[force_feedback.channel]]
part = "chest_plate"
offset = 8
)";

class FakeForceDevice final : public HidOutputDevice {
 public:
  int write(std::span<const std::uint8_t> report) override {
    if (unplugged) return -1;
    reports.emplace_back(report.begin(), report.end());
    return static_cast<int>(report.size());
  }
  std::string lastError() const override { return "device disconnected"; }
  std::string describe() const override { return "fake force feedback"; }
  std::deque<std::vector<std::uint8_t>> reports;
  bool unplugged = false;
};

ForceFeedbackConfig config() {
  Result<SensorSetup> setup = parseSensorSetup(kConfig, "ff.toml");
  EXPECT_TRUE(setup.ok()) << (setup.ok() ? "" : setup.error().message);
  return setup.ok() ? setup->force_feedback : ForceFeedbackConfig{};
}

TEST(ForceFeedbackConfig, SectionParses) {
  const ForceFeedbackConfig c = config();
  EXPECT_TRUE(c.enabled);
  EXPECT_EQ(c.vendor_id, 0x1234);
  EXPECT_EQ(c.product_id, 0x4321);
  EXPECT_EQ(c.serial, "FF01");
  EXPECT_EQ(c.report_id, 5);
  EXPECT_EQ(c.report_size, 12);
  EXPECT_DOUBLE_EQ(c.max_rate_hz, 50.0);
  ASSERT_EQ(c.channels.size(), 4u);
  EXPECT_EQ(c.channels[0].part, "l_hand");
  EXPECT_EQ(c.channels[0].type, HidValueType::kU8);
  EXPECT_EQ(c.channels[0].component, ForceComponent::kMagnitude);
  EXPECT_FLOAT_EQ(c.channels[0].scale, 0.1f);
  EXPECT_EQ(c.channels[1].type, HidValueType::kI16);
  EXPECT_EQ(c.channels[1].component, ForceComponent::kY);
  EXPECT_EQ(c.channels[2].type, HidValueType::kF32);
  EXPECT_EQ(c.channels[2].component, ForceComponent::kX);
  EXPECT_EQ(c.channels[3].offset, 8);
  // Without the section: disabled.
  Result<SensorSetup> none = parseSensorSetup("participant = \"p\"\n", "plain.toml");
  ASSERT_TRUE(none.ok());
  EXPECT_FALSE(none->force_feedback.enabled);
  // The shipped HID example still parses (its force-feedback section is commented out),
  // and so does that section uncommented.
  Result<SensorSetup> hid = loadSensorSetup("config/sensors/hid.toml");
  ASSERT_TRUE(hid.ok()) << hid.error().message;
  EXPECT_FALSE(hid->force_feedback.enabled);
  const std::size_t at = hid->text.find("# [force_feedback]");
  ASSERT_NE(at, std::string::npos);
  std::string uncommented = hid->text.substr(0, at);
  std::istringstream rest(hid->text.substr(at));
  for (std::string line; std::getline(rest, line);) {
    uncommented += (line.rfind("# ", 0) == 0 ? line.substr(2) : line == "#" ? "" : line) + "\n";
  }
  Result<SensorSetup> example = parseSensorSetup(uncommented, "hid.toml (uncommented)");
  ASSERT_TRUE(example.ok()) << example.error().message;
  EXPECT_TRUE(example->force_feedback.enabled);
  ASSERT_EQ(example->force_feedback.channels.size(), 3u);
  EXPECT_EQ(example->force_feedback.channels[2].part, "torso");
  EXPECT_EQ(example->force_feedback.channels[2].component, ForceComponent::kZ);
}

TEST(ForceFeedbackConfig, MistakesNameFileAndKey) {
  const std::string head = "[force_feedback]\nreport_size = 8\n";
  const std::string channel = "[[force_feedback.channel]]\npart = \"head\"\n";
  test::expectSetupError(head, "force_feedback.channel: no channels");
  test::expectSetupError(
      head + channel + "offset = 7\ntype = \"i16\"\n",
      "force_feedback.channel[0].offset: 7 + 2 bytes reaches past the 8-byte report");
  test::expectSetupError(head + channel + "offset = 5\ntype = \"f32\"\n",
                         "force_feedback.channel[0].offset: 5 + 4 bytes reaches past");
  test::expectSetupError(head + channel + "offset = 0\n",
                         "force_feedback.channel[0].offset: 0 is outside");
  test::expectSetupError(head + channel + "offset = 1\ntype = \"i16\"\n" + channel + "offset = 2\n",
                         "force_feedback.channel[1].offset: byte 2 is already taken by channel[0]");
  test::expectSetupError(head + "[[force_feedback.channel]]\noffset = 1\n",
                         "force_feedback.channel[0].part: missing");
  test::expectSetupError(head + channel, "force_feedback.channel[0].offset: missing");
  test::expectSetupError(
      head + channel + "offset = 1\naxis = \"w\"\n",
      "force_feedback.channel[0].axis: expected one of 'x', 'y', 'z', 'magnitude'");
  test::expectSetupError(head + channel + "offset = 1\ntype = \"u32\"\n",
                         "force_feedback.channel[0].type");
  test::expectSetupError(head + channel + "offset = 1\nscale = 0\n",
                         "force_feedback.channel[0].scale");
  test::expectSetupError(head + channel + "offset = 1\ngain = 2\n",
                         "force_feedback.channel[0]: unknown key 'gain'");
  test::expectSetupError("[force_feedback]\nreport_size = 1\n" + channel + "offset = 1\n",
                         "force_feedback.report_size: 1 is outside");
  test::expectSetupError("[force_feedback]\nrate = 3\n" + channel + "offset = 1\n",
                         "force_feedback: unknown key 'rate'");
  test::expectSetupError("[force_feedback]\nreport_id = 300\n" + channel + "offset = 1\n",
                         "force_feedback.report_id");
}

TEST(ForceFeedbackReport, EncodesEachTypeAndAxis) {
  const ForceFeedbackConfig c = config();
  const std::vector<std::string> parts = {"head", "torso", "l_hand"};
  std::vector<std::string> unknown;
  const std::vector<int> bound = bindForceChannels(c, parts, &unknown);
  EXPECT_EQ(bound, (std::vector<int>{2, 2, 0, -1}));
  EXPECT_EQ(unknown, std::vector<std::string>{"chest_plate"});
  std::vector<std::uint8_t> report(12, 0xAB);
  // l_hand: (3, -4, 0) N: |F| = 5 N -> 50 counts of 0.1 N; y = -4 N -> -400 counts of
  // 0.01 N. head: x = 1.25 N -> 2.5 (f32, 0.5 N per unit).
  const std::vector<glm::vec3> forces = {
      {1.25f, 7.0f, 0.0f}, {9.0f, 9.0f, 9.0f}, {3.0f, -4.0f, 0.0f}};
  encodeForceReport(c, bound, forces, report);
  EXPECT_EQ(report[0], 5);
  EXPECT_EQ(report[1], 50);
  const auto y = static_cast<std::int16_t>(report[2] | (report[3] << 8));
  EXPECT_EQ(y, -400);
  float x = 0.0f;
  std::memcpy(&x, &report[4], 4);
  EXPECT_FLOAT_EQ(x, 2.5f);
  for (std::size_t b = 8; b < 12; ++b) EXPECT_EQ(report[b], 0) << b;  // unknown part, padding
  // Out of range: clamped; not finite: 0.
  const std::vector<glm::vec3> big = {{NAN, 0.0f, 0.0f}, {0.0f, 0.0f, 0.0f}, {0.0f, 1000.0f, 0.0f}};
  encodeForceReport(c, bound, big, report);
  EXPECT_EQ(report[1], 255);
  EXPECT_EQ(static_cast<std::int16_t>(report[2] | (report[3] << 8)), 32767);
  std::memcpy(&x, &report[4], 4);
  EXPECT_EQ(x, 0.0f);
  // No forces at all: only the report id.
  encodeForceReport(c, bound, {}, report);
  EXPECT_EQ(report, (std::vector<std::uint8_t>{5, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0}));
}

TEST(ForceFeedbackWriter, SendsChangesAtMostAtTheRateAndZeroAtClose) {
  const std::vector<std::string> parts = {"head", "l_hand"};
  auto device = std::make_unique<FakeForceDevice>();
  FakeForceDevice* fake = device.get();
  ForceFeedbackWriter writer(std::move(device), config(), parts);  // 50 Hz: 20 ms
  EXPECT_EQ(writer.unknownParts(), std::vector<std::string>{"chest_plate"});
  std::vector<glm::vec3> f = {glm::vec3(0.0f), glm::vec3(0.0f)};
  ASSERT_TRUE(writer.update(0.000, f).ok());  // first: sent (all zero)
  ASSERT_TRUE(writer.update(0.030, f).ok());  // unchanged: not sent
  EXPECT_EQ(fake->reports.size(), 1u);
  f[1] = glm::vec3(0.0f, 1.0f, 0.0f);
  ASSERT_TRUE(writer.update(0.040, f).ok());  // changed: sent
  ASSERT_EQ(fake->reports.size(), 2u);
  EXPECT_EQ(fake->reports.back()[1], 10);
  f[1] = glm::vec3(0.0f, 2.0f, 0.0f);
  ASSERT_TRUE(writer.update(0.045, f).ok());  // 5 ms later: too soon
  f[1] = glm::vec3(0.0f, 3.0f, 0.0f);
  ASSERT_TRUE(writer.update(0.050, f).ok());  // still too soon
  EXPECT_EQ(fake->reports.size(), 2u);
  ASSERT_TRUE(writer.update(0.061, f).ok());  // due: the newest forces
  ASSERT_EQ(fake->reports.size(), 3u);
  EXPECT_EQ(fake->reports.back()[1], 30);
  EXPECT_EQ(writer.reportsSent(), 3u);
  writer.close();
  ASSERT_EQ(fake->reports.size(), 4u);
  EXPECT_EQ(fake->reports.back(), (std::vector<std::uint8_t>{5, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0}));
  writer.close();                           // once only
  ASSERT_TRUE(writer.update(1.0, f).ok());  // closed: nothing more
  EXPECT_EQ(fake->reports.size(), 4u);
}

TEST(ForceFeedbackWriter, AFailingDeviceIsReportedOnceThenLeftAlone) {
  const std::vector<std::string> parts = {"l_hand"};
  auto device = std::make_unique<FakeForceDevice>();
  FakeForceDevice* fake = device.get();
  ForceFeedbackWriter writer(std::move(device), config(), parts, /*max_rate_hz=*/1000.0);
  std::vector<glm::vec3> f = {glm::vec3(1.0f, 0.0f, 0.0f)};
  ASSERT_TRUE(writer.update(0.0, f).ok());
  fake->unplugged = true;
  f[0] = glm::vec3(2.0f, 0.0f, 0.0f);
  const Status st = writer.update(0.1, f);
  ASSERT_FALSE(st.ok());
  EXPECT_NE(st.error().message.find("fake force feedback"), std::string::npos);
  EXPECT_NE(st.error().message.find("device disconnected"), std::string::npos);
  EXPECT_TRUE(writer.failed());
  f[0] = glm::vec3(3.0f, 0.0f, 0.0f);
  EXPECT_TRUE(writer.update(0.2, f).ok());  // silent from now on
  fake->unplugged = false;
  writer.close();  // a failed device gets nothing, not even the zero report
  EXPECT_EQ(fake->reports.size(), 1u);
}

TEST(ForceFeedbackWriter, NoDeviceOnThisMachine) {
  // hidapi finds no such device here (no /dev/hidraw): a clear error naming it.
  ForceFeedbackConfig c = config();
  c.vendor_id = 0xFFFE;
  c.product_id = 0xFFFD;
  Result<std::unique_ptr<HidOutputDevice>> opened = openHidapiOutput(c);
  if (opened.ok()) GTEST_SKIP() << "a HID device answers to fffe:fffd here";
  EXPECT_NE(opened.error().message.find("force feedback hid fffe:fffd"), std::string::npos)
      << opened.error().message;
}

}  // namespace
}  // namespace vistel
