// config/client.toml's [lod] section (the deformable component's level of detail) and
// [view] gpu_skinning: the embedded defaults equal DeformLodSettings{}, every key is read,
// bad values and unknown keys are refused with the key's name.
#include <gtest/gtest.h>

#include "client/net/client_config.hpp"

namespace vistel::net {
namespace {

TEST(LodConfig, EmbeddedDefaultsAreTheCodeDefaults) {
  Result<ClientConfig> c = loadClientConfig("config/client.toml");
  ASSERT_TRUE(c.ok()) << c.error().message;
  const DeformLodSettings d;
  EXPECT_EQ(c->lod.enabled, d.enabled);
  EXPECT_EQ(c->lod.full_radius_m, d.full_radius_m);
  EXPECT_EQ(c->lod.reduced_radius_m, d.reduced_radius_m);
  EXPECT_EQ(c->lod.hysteresis_m, d.hysteresis_m);
  EXPECT_EQ(c->lod.reduced_every, d.reduced_every);
  EXPECT_EQ(c->lod.max_full, d.max_full);
  EXPECT_EQ(c->lod.max_reduced, d.max_reduced);
  EXPECT_EQ(c->lod.contact_full, d.contact_full);
  EXPECT_TRUE(c->gpu_skinning);
}

TEST(LodConfig, ReadsEveryKey) {
  Result<ClientConfig> c = parseClientConfig(
      "[view]\ngpu_skinning = false\n"
      "[lod]\nenabled = false\nfull_radius_m = 1.5\nreduced_radius_m = 4.0\n"
      "hysteresis_m = 0.1\nreduced_every = 4\nmax_full = 3\nmax_reduced = 7\n"
      "contact_full = false\n",
      "c.toml");
  ASSERT_TRUE(c.ok()) << c.error().message;
  EXPECT_FALSE(c->gpu_skinning);
  EXPECT_FALSE(c->lod.enabled);
  EXPECT_FLOAT_EQ(c->lod.full_radius_m, 1.5f);
  EXPECT_FLOAT_EQ(c->lod.reduced_radius_m, 4.0f);
  EXPECT_FLOAT_EQ(c->lod.hysteresis_m, 0.1f);
  EXPECT_EQ(c->lod.reduced_every, 4);
  EXPECT_EQ(c->lod.max_full, 3);
  EXPECT_EQ(c->lod.max_reduced, 7);
  EXPECT_FALSE(c->lod.contact_full);
}

TEST(LodConfig, RefusesBadValues) {
  auto message = [](const char* text) {
    Result<ClientConfig> c = parseClientConfig(text, "c.toml");
    return c.ok() ? std::string() : c.error().message;
  };
  EXPECT_NE(message("[lod]\nreduced_every = 0\n").find("reduced_every"), std::string::npos);
  EXPECT_NE(message("[lod]\nfull_radius_m = -1\n").find("full_radius_m"), std::string::npos);
  EXPECT_NE(
      message("[lod]\nfull_radius_m = 5.0\nreduced_radius_m = 2.0\n").find("reduced_radius_m"),
      std::string::npos);
  EXPECT_NE(message("[lod]\nradius = 2.0\n").find("radius"), std::string::npos);
  EXPECT_NE(message("[lod]\nenabled = 3\n").find("enabled"), std::string::npos);
}

}  // namespace
}  // namespace vistel::net
