// vistel-server's command line: a bad value is refused, naming the option, never silently
// turned into something else (issue 20, finding 9: --log-level loud turned logging off).
#include <string>

#include <gtest/gtest.h>

#include "tests/integration/program.hpp"
#include "tests/support/test_support.hpp"

namespace vistel {
namespace {

TEST(ServerCli, AnUnknownLogLevelIsRefusedNotSilenced) {
  const std::string dir = test::scratchDir();
  test::Program server("vistel-server", {"--port", "0", "--log-level", "loud"},
                       dir + "/server.log");
  EXPECT_EQ(server.wait(10.0), 2);
  EXPECT_NE(server.log().find("--log-level 'loud'"), std::string::npos) << server.log();
}

}  // namespace
}  // namespace vistel
