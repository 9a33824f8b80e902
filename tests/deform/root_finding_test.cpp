// The hybrid Newton / Illinois root-finder of Step 2 on scalar functions.
#include <cmath>

#include <gtest/gtest.h>

#include "common/deform/root_finding.hpp"

namespace vistel {
namespace {

TEST(RootFinding, AtARootCostsOneEvaluation) {
  int evals = 0;
  auto g = [&](float s, float* dg) {
    ++evals;
    *dg = -1.0f;
    return -s;
  };
  const RootResult r = findRoot(g, 0.0f, 0.1f, RootOptions{});
  EXPECT_TRUE(r.found);
  EXPECT_EQ(r.iterations, 0);
  EXPECT_EQ(evals, 1);
}

TEST(RootFinding, ConvergesOnSmoothAndKinkedFunctions) {
  // Smooth, decreasing outward (inside > 0), root at 0.0123.
  auto smooth = [](float s, float* dg) {
    *dg = -3.0f * std::cos(3.0f * (s - 0.0123f));
    return -std::sin(3.0f * (s - 0.0123f));
  };
  RootResult r = findRoot(smooth, 0.0f, 0.2f, RootOptions{});
  ASSERT_TRUE(r.found);
  EXPECT_NEAR(r.s, 0.0123f, 2e-6f);
  EXPECT_LE(r.iterations, 4);
  // A wrong derivative (pointing away) still finds the root by bracketing.
  auto lying = [](float s, float* dg) {
    *dg = 5.0f;
    return -(s + 0.02f);
  };
  r = findRoot(lying, 0.0f, 0.2f, RootOptions{});
  ASSERT_TRUE(r.found);
  EXPECT_NEAR(r.s, -0.02f, 2e-6f);
  // A kink (derivative jumps): regula falsi keeps it bracketed.
  auto kink = [](float s, float* dg) {
    const float x = s - 0.004f;
    *dg = x > 0.0f ? -10.0f : -0.1f;
    return x > 0.0f ? -10.0f * x : -0.1f * x;
  };
  r = findRoot(kink, 0.03f, 0.2f, RootOptions{});
  ASSERT_TRUE(r.found);
  EXPECT_NEAR(r.s, 0.004f, 2e-6f);
}

TEST(RootFinding, WarmStartNearTheRootTakesFewIterations) {
  auto g = [](float s, float* dg) {
    const float x = s + 0.01f;
    *dg = -(1.0f + 30.0f * x * x);
    return -(x + 10.0f * x * x * x);
  };
  const RootResult cold = findRoot(g, 0.0f, 0.1f, RootOptions{});
  const RootResult warm = findRoot(g, -0.0101f, 0.1f, RootOptions{});
  ASSERT_TRUE(cold.found && warm.found);
  EXPECT_LE(warm.iterations, 2);
  EXPECT_LE(warm.iterations, cold.iterations);
}

TEST(RootFinding, AShortLastNewtonStepIsTakenWithoutAnotherEvaluation) {
  // Smooth, root at 0.0123; g'' / g' is about 3 / m here, so a 50 um Newton step lands
  // within about 3 / 2 * (50 um)^2 ~ 4 nm of the root.
  int evals = 0;
  auto smooth = [&](float s, float* dg) {
    ++evals;
    *dg = -3.0f * std::cos(3.0f * (s - 0.0123f) + 0.5f);
    return -(std::sin(3.0f * (s - 0.0123f) + 0.5f) - std::sin(0.5f));
  };
  RootOptions opt;
  RootResult r = findRoot(smooth, 0.0123f + 5e-5f, 0.2f, opt);
  ASSERT_TRUE(r.found);
  EXPECT_EQ(evals, 1);
  EXPECT_EQ(r.iterations, 0);
  EXPECT_TRUE(r.final_newton);
  EXPECT_NEAR(r.s, 0.0123f, 1e-7f);
  // Without the final step the same start evaluates again.
  evals = 0;
  opt.final_step = 0.0f;
  r = findRoot(smooth, 0.0123f + 5e-5f, 0.2f, opt);
  ASSERT_TRUE(r.found);
  EXPECT_FALSE(r.final_newton);
  EXPECT_GE(evals, 2);
  EXPECT_NEAR(r.s, 0.0123f, 2e-6f);
}

TEST(RootFinding, NoRootWithinReachIsReported) {
  auto g = [](float s, float* dg) {
    *dg = 0.0f;
    return 1.0f + s * s;
  };
  const RootResult r = findRoot(g, 0.0f, 0.05f, RootOptions{});
  EXPECT_FALSE(r.found);
}

}  // namespace
}  // namespace vistel
