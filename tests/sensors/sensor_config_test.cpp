// Sensor configs: the shipped files parse to what they say; mistakes get errors that name
// the file, the key and the reason.
#include <gtest/gtest.h>

#include "common/base/embedded.hpp"
#include "common/sensors/sensor_config.hpp"
#include "tests/sensors/setup_errors.hpp"

namespace vistel {
namespace {

TEST(SensorConfig, ShippedFilesParse) {
  auto fastrak = loadSensorSetup("config/sensors/fastrak.toml");
  ASSERT_TRUE(fastrak.ok()) << fastrak.error().message;
  EXPECT_EQ(fastrak->tracker_kind, TrackerKind::kFastrak);
  EXPECT_EQ(fastrak->tracker.transport, TrackerTransport::kSerial);
  EXPECT_EQ(fastrak->tracker.format.encoding, FastrakEncoding::kBinary);
  EXPECT_EQ(fastrakRecordSize(fastrak->tracker.format), 32u);
  ASSERT_EQ(fastrak->tracker.stations.size(), 4u);
  EXPECT_EQ(fastrak->tracker.stations[2].site, BodySite::kLeftWrist);
  EXPECT_EQ(fastrak->tracker.usb.vendor_id, 0x0F44);
  ASSERT_EQ(fastrak->gloves.size(), 2u);
  EXPECT_EQ(fastrak->gloves[0].hand, Hand::kLeft);
  EXPECT_EQ(fastrak->gloves[1].port, "/dev/ttyUSB2");
  EXPECT_EQ(fastrak->gloves[1].calibration.sensors.size(), 22u);
  EXPECT_EQ(fastrak->calibration.alignment, AlignmentMode::kFacing);
  EXPECT_TRUE(fastrak->calibration.estimate_proportions);
  // +Z (down on the unit) maps to -Y.
  EXPECT_NEAR((fastrak->tracker.transmitter.rotation * glm::vec3(0, 0, 1)).y, -1.0f, 1e-6f);
  EXPECT_FALSE(fastrak->text.empty());

  auto sim = loadSensorSetup("config/sensors/sim.toml");
  ASSERT_TRUE(sim.ok()) << sim.error().message;
  EXPECT_EQ(sim->tracker_kind, TrackerKind::kNone);
  EXPECT_EQ(sim->sim.glove, GlovePattern::kCycle);
  EXPECT_NEAR(sim->sim.position_noise_m, 0.0008f, 1e-9f);
  EXPECT_GT(sim->sim.hold_s, sim->calibration.window_s);

  // Six sensors: a HID tracker with foot stations, and the simulated rig with them.
  auto feet = loadSensorSetup("config/sensors/hid_feet.toml");
  ASSERT_TRUE(feet.ok()) << feet.error().message;
  EXPECT_EQ(feet->tracker_kind, TrackerKind::kHid);
  ASSERT_EQ(feet->hid.stations.size(), 6u);
  EXPECT_EQ(feet->hid.stations[4].site, BodySite::kLeftFoot);
  EXPECT_EQ(feet->hid.stations[5].site, BodySite::kRightFoot);
  ASSERT_EQ(feet->tracker.stations.size(), 6u);
  EXPECT_EQ(feet->mounts[static_cast<std::size_t>(BodySite::kRightFoot)].offset,
            glm::vec3(0.0f, 0.0f, 0.07f));
  EXPECT_FLOAT_EQ(
      feet->solver.station_filters[static_cast<std::size_t>(BodySite::kLeftFoot)].position_beta,
      10.0f);
  EXPECT_TRUE(feet->sim.foot_trackers);
  EXPECT_FALSE(sim->sim.foot_trackers);
  auto sim_feet = loadSensorSetup("config/sensors/sim_feet.toml");
  ASSERT_TRUE(sim_feet.ok()) << sim_feet.error().message;
  EXPECT_TRUE(sim_feet->sim.foot_trackers);
  EXPECT_DOUBLE_EQ(sim_feet->sim.rate_hz, 240.0);
  EXPECT_EQ(sim_feet->sim.mounts[static_cast<std::size_t>(BodySite::kLeftFoot)].site,
            BodySite::kLeftFoot);
  EXPECT_FALSE(fastrak->sim.foot_trackers);

  auto hid = loadSensorSetup("config/sensors/hid.toml");
  ASSERT_TRUE(hid.ok()) << hid.error().message;
  EXPECT_EQ(hid->tracker_kind, TrackerKind::kHid);
  EXPECT_EQ(hid->hid.stations.size(), 4u);
  EXPECT_EQ(hid->hid.stations[3].position_type, HidValueType::kI16);

  auto glove =
      parseGloveConfig(std::string(*embeddedConfig("sensors/cyberglove.toml")), "cyberglove.toml");
  ASSERT_TRUE(glove.ok()) << glove.error().message;
  EXPECT_TRUE(glove->stream);
}

const char* kStations = R"(
[[station]]
number = 1
site = "head"
[[station]]
number = 2
site = "chest"
[[station]]
number = 3
site = "left_wrist"
[[station]]
number = 4
site = "right_wrist"
)";

TEST(SensorConfig, MistakesNameTheKeyAndTheReason) {
  test::expectSetupError("[tracker]\nport = 3\n", "tracker.port: expected a string");
  test::expectSetupError("[tracker]\nbaud = 0\n", "tracker.baud");
  test::expectSetupError("[tracker]\nencoding = \"hex\"\n", "expected one of 'binary', 'ascii'");
  test::expectSetupError(std::string("[tracker]\noutput_list = [2, 7]\n") + kStations,
                         "item code 7");
  test::expectSetupError(std::string("[tracker]\noutput_list = [0, 1]\n") + kStations,
                         "no position or orientation");
  test::expectSetupError("[tracker]\nprot = \"/dev/ttyS0\"\n", "unknown key 'prot'");
  test::expectSetupError(
      "[tracker]\nkind = \"fastrak\"\n[[station]]\nnumber = 1\nsite = \"head\"\n",
      "no station is worn at 'chest'");
  test::expectSetupError(
      "[[station]]\nnumber = 1\nsite = \"head\"\n[[station]]\nnumber = 2\nsite = \"head\"\n",
      "listed twice");
  test::expectSetupError("[[station]]\nnumber = 9\nsite = \"head\"\n", "station.number");
  test::expectSetupError("[solver]\nstance = \"lying\"\n", "solver.stance");
  test::expectSetupError("[solver]\npelvis_tilt_share = 2\n", "outside [0, 1]");
  test::expectSetupError("[[glove]]\nconfig = \"config/sensors/none.toml\"\n", "none.toml");
  test::expectSetupError(
      "[hid]\nreport_size = 8\n[[hid.station]]\nsite = \"head\"\nposition_offset = 4\n",
      "reach past the 8-byte report");
  test::expectSetupError("participant = \n", "bad.toml:1");
  // Foot stations: optional, but a FASTRAK has four receivers, and a HID tracker still needs
  // the four upper-body sites.
  test::expectSetupError(std::string("[tracker]\nkind = \"fastrak\"\n") + kStations +
                             "[[station]]\nnumber = 0\nsite = \"left_foot\"\n",
                         "a FASTRAK has 4 receivers");
  test::expectSetupError(
      "[tracker]\nkind = \"hid\"\n[[hid.station]]\nsite = \"head\"\n[[hid.station]]\n"
      "site = \"left_foot\"\n",
      "0 stations laid out at 'chest'");
  test::expectSetupError("[[station]]\nnumber = 0\nsite = \"left_ankle\"\n", "station.site");
  EXPECT_FALSE(parseGloveConfig("sensors = 20\n", "g.toml").ok());
  EXPECT_FALSE(loadSensorSetup("config/sensors/no-such-file.toml").ok());
}

}  // namespace
}  // namespace vistel
