// chooseDeformTiers / deformsOnFrame: tiers by floor-plane distance, contact, hysteresis and
// budgets; the lower rate spread evenly over frames; settings validated.
#include <cmath>
#include <limits>
#include <vector>

#include <gtest/gtest.h>

#include "common/scene/deform_lod.hpp"

namespace vistel {
namespace {

using T = DeformTier;

// Bodies on the +x axis at these distances from a viewer at the origin (1.6 m up: the
// height does not count).
std::vector<glm::vec3> along(std::initializer_list<float> xs) {
  std::vector<glm::vec3> out;
  for (const float x : xs) out.emplace_back(x, 0.0f, 0.0f);
  return out;
}

std::vector<T> tiers(const DeformLodSettings& s, const std::vector<glm::vec3>& positions,
                     const std::vector<std::uint8_t>& contact = {},
                     const std::vector<T>& previous = {}) {
  DeformLodInput input;
  input.positions = positions;
  input.viewer = glm::vec3(0.0f, 1.6f, 0.0f);
  input.in_contact = contact;
  input.previous = previous;
  DeformLodScratch scratch;
  std::vector<T> out(positions.size(), T::kRigid);
  chooseDeformTiers(s, input, scratch, out);
  return out;
}

DeformLodSettings settings() {
  DeformLodSettings s;
  s.full_radius_m = 2.0f;
  s.reduced_radius_m = 5.0f;
  s.hysteresis_m = 0.5f;
  s.max_full = 100;
  s.max_reduced = 100;
  return s;
}

TEST(DeformLod, DisabledDeformsEveryBodyAtFullRate) {
  DeformLodSettings s = settings();
  s.enabled = false;
  EXPECT_EQ(tiers(s, along({0.0f, 3.0f, 50.0f})), (std::vector<T>{T::kFull, T::kFull, T::kFull}));
}

TEST(DeformLod, TiersByFloorDistance) {
  const std::vector<T> got = tiers(settings(), along({0.5f, 2.0f, 2.1f, 5.0f, 5.1f, 40.0f}));
  EXPECT_EQ(got,
            (std::vector<T>{T::kFull, T::kFull, T::kReduced, T::kReduced, T::kRigid, T::kRigid}));
  // The distance is measured in x and z only.
  std::vector<glm::vec3> diagonal = {glm::vec3(1.2f, 9.0f, 1.2f), glm::vec3(4.0f, 0.0f, 4.0f)};
  EXPECT_EQ(tiers(settings(), diagonal), (std::vector<T>{T::kFull, T::kRigid}));
}

TEST(DeformLod, ContactMeansFullRateWhateverTheDistance) {
  const std::vector<T> got = tiers(settings(), along({30.0f, 30.5f, 40.0f}), {1, 1, 0});
  EXPECT_EQ(got, (std::vector<T>{T::kFull, T::kFull, T::kRigid}));
  DeformLodSettings s = settings();
  s.contact_full = false;
  EXPECT_EQ(tiers(s, along({30.0f, 30.5f, 40.0f}), {1, 1, 0}),
            (std::vector<T>{T::kRigid, T::kRigid, T::kRigid}));
}

TEST(DeformLod, HysteresisKeepsABetterTierNearItsBoundary) {
  const std::vector<glm::vec3> p = along({2.3f, 2.3f, 5.3f, 5.3f, 5.6f});
  const std::vector<T> previous = {T::kFull, T::kReduced, T::kReduced, T::kRigid, T::kFull};
  EXPECT_EQ(tiers(settings(), p, {}, previous),
            (std::vector<T>{T::kFull, T::kReduced, T::kReduced, T::kRigid, T::kRigid}));
  // Without a previous frame (or one of the wrong size), plain radii.
  EXPECT_EQ(tiers(settings(), p, {}, {T::kFull}),
            (std::vector<T>{T::kReduced, T::kReduced, T::kRigid, T::kRigid, T::kRigid}));
}

TEST(DeformLod, BudgetsKeepContactsAndTheNearestFirst) {
  DeformLodSettings s = settings();
  s.max_full = 2;
  s.max_reduced = 2;
  // Five near bodies (one far but in contact), two mid-range ones.
  const std::vector<glm::vec3> p = along({1.5f, 0.5f, 1.0f, 1.8f, 20.0f, 3.0f, 4.0f});
  const std::vector<std::uint8_t> contact = {0, 0, 0, 0, 1, 0, 0};
  const std::vector<T> got = tiers(s, p, contact);
  // Full: the body in contact, then the nearest (0.5 m). Reduced: the next nearest of those
  // dropped (1.0, 1.5 m); the rest over the budgets rigid.
  EXPECT_EQ(got, (std::vector<T>{T::kReduced, T::kFull, T::kReduced, T::kRigid, T::kFull, T::kRigid,
                                 T::kRigid}));
  const DeformTierCounts c = countTiers(got);
  EXPECT_EQ(c.full, 2);
  EXPECT_EQ(c.reduced, 2);
  EXPECT_EQ(c.rigid, 3);
  // Ties go to the lower index.
  s.max_full = 1;
  s.max_reduced = 0;
  EXPECT_EQ(tiers(s, along({1.0f, 1.0f})), (std::vector<T>{T::kFull, T::kRigid}));
}

TEST(DeformLod, BadInputIsHandled) {
  const float inf = std::numeric_limits<float>::infinity();
  const float nan = std::numeric_limits<float>::quiet_NaN();
  EXPECT_EQ(tiers(settings(), {glm::vec3(nan, 0, 0), glm::vec3(inf, 0, 0), glm::vec3(0.0f)}),
            (std::vector<T>{T::kRigid, T::kRigid, T::kFull}));
  // An output of the wrong size is left alone.
  const std::vector<glm::vec3> p = along({0.0f, 1.0f});
  DeformLodInput input;
  input.positions = p;
  DeformLodScratch scratch;
  std::vector<T> out(1, T::kReduced);
  chooseDeformTiers(settings(), input, scratch, out);
  EXPECT_EQ(out[0], T::kReduced);
  // No bodies.
  std::vector<T> none;
  input.positions = {};
  chooseDeformTiers(settings(), input, scratch, none);
}

TEST(DeformLod, LowerRateSpreadsOverFrames) {
  const int k = 3;
  for (int body = 0; body < 7; ++body) {
    int count = 0;
    for (std::int64_t frame = 0; frame < 3 * k; ++frame) {
      count += deformsOnFrame(T::kReduced, body, frame, k) ? 1 : 0;
      EXPECT_TRUE(deformsOnFrame(T::kFull, body, frame, k));
      EXPECT_FALSE(deformsOnFrame(T::kRigid, body, frame, k));
    }
    EXPECT_EQ(count, 3) << "body " << body;
  }
  // In any one frame, about a third of the bodies.
  int on_frame = 0;
  for (int body = 0; body < 9; ++body) on_frame += deformsOnFrame(T::kReduced, body, 4, k);
  EXPECT_EQ(on_frame, 3);
  EXPECT_TRUE(deformsOnFrame(T::kReduced, 5, 11, 0));  // reduced_every < 1 counts as 1
}

TEST(DeformLod, SettingsAreValidated) {
  EXPECT_TRUE(validateDeformLodSettings(DeformLodSettings{}).ok());
  auto bad = [](auto change) {
    DeformLodSettings s;
    change(s);
    return validateDeformLodSettings(s);
  };
  Status st = bad([](DeformLodSettings& s) { s.full_radius_m = -1.0f; });
  ASSERT_FALSE(st.ok());
  EXPECT_NE(st.error().message.find("full_radius_m"), std::string::npos);
  st = bad([](DeformLodSettings& s) { s.reduced_radius_m = 1.0f; });
  ASSERT_FALSE(st.ok());
  EXPECT_NE(st.error().message.find("reduced_radius_m"), std::string::npos);
  EXPECT_FALSE(bad([](DeformLodSettings& s) { s.hysteresis_m = NAN; }).ok());
  EXPECT_FALSE(bad([](DeformLodSettings& s) { s.reduced_every = 0; }).ok());
  EXPECT_FALSE(bad([](DeformLodSettings& s) { s.max_full = -1; }).ok());
  EXPECT_FALSE(bad([](DeformLodSettings& s) { s.max_reduced = -1; }).ok());
}

}  // namespace
}  // namespace vistel
