// Checks that a sensors config is refused with a message naming the file and the mistake.
#pragma once

#include <string>

#include <gtest/gtest.h>

#include "common/sensors/sensor_config.hpp"

namespace vistel::test {

// `toml`, read as "bad.toml", is refused; the message names the file and contains `fragment`.
inline void expectSetupError(const std::string& toml, const std::string& fragment) {
  Result<SensorSetup> r = parseSensorSetup(toml, "bad.toml");
  ASSERT_FALSE(r.ok()) << toml;
  EXPECT_NE(r.error().message.find("bad.toml"), std::string::npos) << r.error().message;
  EXPECT_NE(r.error().message.find(fragment), std::string::npos) << r.error().message;
}

}  // namespace vistel::test
