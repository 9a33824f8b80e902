// A fixture for tests that run the real programs: a scratch folder holding the synthetic
// avatar (synthetic.vavatar) and a waving clip (wave.bvh) on its joints, and the fetched
// avatars' cache inside it.
#pragma once

#include <cstdlib>
#include <string>

#include <gtest/gtest.h>

#include "common/avatar/avatar_io.hpp"
#include "common/base/file.hpp"
#include "tests/net/synthetic_avatar.hpp"
#include "tests/support/test_support.hpp"

namespace vistel::test {

class SessionScratch : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = scratchDir();
    avatar_path_ = dir_ + "/synthetic.vavatar";
    ASSERT_TRUE(saveAvatar(makeSyntheticAvatar(), avatar_path_));
    bvh_path_ = dir_ + "/wave.bvh";
    ASSERT_TRUE(writeFileText(bvh_path_, syntheticBvh(60, 30.0)));
    setenv("XDG_CACHE_HOME", (dir_ + "/cache").c_str(), 1);
  }
  std::string dir_;
  std::string avatar_path_;
  std::string bvh_path_;
};

}  // namespace vistel::test
