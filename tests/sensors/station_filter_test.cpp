// The station filter (station_filter.hpp): smooths a still station's noise, follows steady
// motion without lag, keeps a 30 Hz station's 120 Hz output free of steps at its readings,
// and reads the noise figures from the sensors config.
#include <cmath>
#include <cstdio>
#include <vector>

#include <gtest/gtest.h>

#include "common/sensors/random.hpp"
#include "common/sensors/sensor_config.hpp"
#include "common/sensors/station_filter.hpp"

namespace vistel {
namespace {

constexpr double kTick = 1.0 / 120.0;  // output rate
constexpr int kEvery = 4;              // a reading every 4 ticks (30 Hz)

// Runs the filter on a trajectory x(t) (positions along x; rotation about y by x radians),
// readings at 30 Hz with Gaussian noise of the given RMS; returns the 120 Hz output.
std::vector<glm::vec3> run(const StationFilterParams& params, double (*x)(double), float noise_m,
                           int ticks, std::vector<glm::quat>* rotations = nullptr) {
  StationFilter filter;
  SimRandom rng(7);
  std::vector<glm::vec3> out;
  for (int k = 0; k < ticks; ++k) {
    const double t = k * kTick;
    if (k % kEvery == 0) {
      const float s = noise_m / std::sqrt(3.0f);
      const glm::vec3 n(static_cast<float>(rng.gaussian()) * s,
                        static_cast<float>(rng.gaussian()) * s,
                        static_cast<float>(rng.gaussian()) * s);
      const float v = static_cast<float>(x(t));
      filter.update(glm::vec3(v, 0.0f, 0.0f) + n, glm::angleAxis(v, glm::vec3(0, 1, 0)), t, t,
                    params);
    }
    glm::vec3 p;
    glm::quat q;
    filter.evaluate(t, params, p, q);
    out.push_back(p);
    if (rotations != nullptr) rotations->push_back(q);
  }
  return out;
}

double still(double) { return 0.1; }
double ramp(double t) { return 0.5 * t; }  // 0.5 m/s
double sway(double t) { return 0.1 * std::sin(2.0 * glm::pi<double>() * 0.8 * t); }

TEST(StationFilter, SmoothsAStillStationsNoise) {
  // At a 1 Hz corner (the chest's); at the head's and wrists' 4 Hz, close to the 30 Hz
  // reading rate, extrapolating between readings gives back what the filter removes.
  StationFilterParams params;
  params.position_cutoff_hz = params.orientation_cutoff_hz = 1.0f;
  const std::vector<glm::vec3> out = run(params, still, 0.0008f, 1200);
  double sum = 0.0;
  int n = 0;
  for (std::size_t k = 240; k < out.size(); ++k, ++n)
    sum += glm::dot(out[k] - glm::vec3(0.1f, 0, 0), out[k] - glm::vec3(0.1f, 0, 0));
  const double rms = std::sqrt(sum / n);
  EXPECT_LT(rms, 0.0008 * 0.65) << "RMS error of the output, metres";
}

TEST(StationFilter, FollowsSteadyMotionWithoutLag) {
  const StationFilterParams params;
  std::vector<glm::quat> q;
  const std::vector<glm::vec3> out = run(params, ramp, 0.0f, 600, &q);
  // After settling, the output is where the ramp is now (not where it was one reading ago:
  // 0.5 m/s x 33 ms = 17 mm), position and rotation alike.
  for (std::size_t k = 360; k < out.size(); ++k) {
    const double t = static_cast<double>(k) * kTick;
    EXPECT_NEAR(out[k].x, ramp(t), 5e-4) << k;
    EXPECT_NEAR(glm::angle(q[k] * glm::inverse(glm::angleAxis(static_cast<float>(ramp(t)),
                                                              glm::vec3(0, 1, 0)))),
                0.0, 2e-3)
        << k;
  }
}

// Mean |jerk| (third difference / tick^3) of a 120 Hz output after it has settled.
double meanJerk(const std::vector<glm::vec3>& p) {
  double sum = 0.0;
  int n = 0;
  for (std::size_t k = 240; k + 3 < p.size(); ++k, ++n) {
    const glm::vec3 d3 = p[k + 3] - 3.0f * p[k + 2] + 3.0f * p[k + 1] - p[k];
    sum += static_cast<double>(glm::length(d3)) / (kTick * kTick * kTick);
  }
  return n > 0 ? sum / n : 0.0;
}

TEST(StationFilter, NoStepsAtReadings) {
  // A swaying station (its own mean |jerk| 8.1 m/s^3) read at 30 Hz and drawn at 120 Hz,
  // without noise: corrections applied at once shake the output at every reading; folded in
  // along the minimum-jerk path over two reading intervals (the default) the output's mean
  // jerk is 64 m/s^3, over half an interval (the earlier default) 981, at once 1473.
  StationFilterParams eased;
  StationFilterParams short_ease;
  short_ease.ease_intervals = 0.5;
  StationFilterParams abrupt;
  abrupt.ease_intervals = 0.0;
  const double own = 0.1 * std::pow(2.0 * glm::pi<double>() * 0.8, 3.0) * 2.0 / glm::pi<double>();
  const double j_eased = meanJerk(run(eased, sway, 0.0f, 1200));
  const double j_short = meanJerk(run(short_ease, sway, 0.0f, 1200));
  const double j_abrupt = meanJerk(run(abrupt, sway, 0.0f, 1200));
  std::printf("mean jerk, m/s^3: own %.1f, eased %.1f, half an interval %.1f, abrupt %.1f\n", own,
              j_eased, j_short, j_abrupt);
  EXPECT_LT(j_eased, 10.0 * own);
  EXPECT_LT(j_eased, 0.1 * j_short);
  EXPECT_LT(j_short, j_abrupt);
}

TEST(StationFilter, DelaySpendsLagOnLessExtrapolation) {
  // With delay_s the output follows the motion that much later (a steady ramp: exactly).
  StationFilterParams params;
  params.delay_s = 0.008;
  const std::vector<glm::vec3> out = run(params, ramp, 0.0f, 600);
  for (std::size_t k = 360; k < out.size(); ++k) {
    const double t = static_cast<double>(k) * kTick;
    EXPECT_NEAR(out[k].x, ramp(t - params.delay_s), 5e-4) << k;
  }
}

TEST(StationFilter, DelayInReadingIntervalsFollowsTheReadingRate) {
  // delay_intervals = 1 at 30 Hz readings: one reading interval (4 ticks) late, as delay_s of
  // 1/30 s would be; the interval is the station's own, measured from its readings.
  StationFilterParams params;
  params.delay_intervals = 1.0;
  const std::vector<glm::vec3> out = run(params, ramp, 0.0f, 600);
  const double interval = kEvery * kTick;
  for (std::size_t k = 360; k < out.size(); ++k) {
    const double t = static_cast<double>(k) * kTick;
    EXPECT_NEAR(out[k].x, ramp(t - interval), 5e-4) << k;
  }
}

TEST(StationFilter, NoiseFiguresAndCornersFromTheSensorsConfig) {
  auto setup = parseSensorSetup(R"(
[tracker]
kind = "none"
position_noise_m = 0.002
orientation_noise_deg = 0.5
[solver]
station_filter = "kalman"
kalman_cutoff_hz = 5.0
head_position_cutoff_hz = 2.5
wrist_position_cutoff_hz = 1.0
wrist_beta = 7.0
chest_cutoff_hz = 2.0
chest_beta = 3.0
hips_cutoff_hz = 0.0
)",
                                "inline");
  ASSERT_TRUE(setup.ok()) << setup.error().message;
  for (std::size_t s = 0; s < kUpperBodySiteCount; ++s) {  // (the feet have their own keys)
    const StationFilterParams& f = setup->solver.station_filters[s];
    EXPECT_FLOAT_EQ(f.position_noise_m, 0.002f);
    EXPECT_FLOAT_EQ(f.orientation_noise_deg, 0.5f);
    const bool chest = s == static_cast<std::size_t>(BodySite::kChest);
    const bool head = s == static_cast<std::size_t>(BodySite::kHead);
    EXPECT_FLOAT_EQ(f.position_cutoff_hz, chest ? 2.0f : head ? 2.5f : 1.0f);
    EXPECT_FLOAT_EQ(f.orientation_cutoff_hz, chest ? 2.0f : 5.0f);
    EXPECT_FLOAT_EQ(f.position_beta, chest ? 3.0f : head ? 0.0f : 7.0f);
  }
  EXPECT_EQ(setup->solver.filter_kind, StationFilterKind::kKalman);
  EXPECT_FLOAT_EQ(setup->solver.hips_cutoff_hz, 0.0f);
  auto bad = parseSensorSetup("[solver]\nstation_filter = \"median\"\n", "inline");
  EXPECT_FALSE(bad.ok());
}

}  // namespace
}  // namespace vistel
