// Replaying gives the same deformed vertices and contacts (forces, areas) with 1 and 2
// threads and any chunk size (STYLE.md "Reproducible"), and the per-frame loop allocates
// nothing after warm-up.

#include <chrono>

#include <gtest/gtest.h>
#include <glm/gtc/matrix_transform.hpp>

#include "common/base/hash.hpp"
#include "tests/deform/fixtures.hpp"
#include "tests/support/alloc_counter.hpp"

namespace vistel {
namespace {

using test::Scene;

// Folds a body's contacts into h, field by field (BodyContact has padding).
std::uint64_t hashContacts(const std::vector<BodyContact>& contacts, std::uint64_t h) {
  for (const BodyContact& c : contacts) {
    h = fnv1a64(&c.partner, sizeof c.partner, h);
    h = fnv1a64(&c.vertices, sizeof c.vertices, h);
    h = fnv1a64(&c.force, sizeof c.force, h);
    h = fnv1a64(&c.area, sizeof c.area, h);
    h = fnv1a64(&c.centre, sizeof c.centre, h);
    h = fnv1a64(&c.max_depth, sizeof c.max_depth, h);
  }
  return h;
}

// A clip: the elbow bends from 0 to 150 degrees while a soft ball slides along the
// forearm and presses into it; returns the hash of every frame's deformed vertices and
// contacts.
std::uint64_t replay(TaskPool* pool, int chunk) {
  auto arm = test::armBody();
  BallSpec spec;
  spec.radius = 0.05f;
  spec.stiffness = 2.0e4f;
  spec.elasticity = Elasticity::kViscoelastic;
  auto ball = test::ballBody(spec, glm::vec3(0.0f));
  Scene scene;
  scene.bodies = {arm.get(), ball.get()};
  scene.pool = pool;
  scene.options.chunk_size = chunk;
  std::uint64_t h = kFnvOffset;
  double contact_area = 0.0;
  for (int f = 0; f < 24; ++f) {
    const float t = static_cast<float>(f) / 23.0f;
    test::bendArm(*arm, glm::radians(150.0f) * t);
    ball->placement =
        glm::translate(glm::mat4(1.0f), glm::vec3(0.35f + 0.2f * t, 0.0f, 0.075f - 0.02f * t));
    scene.step(f / 30.0);
    h = hashSpan<glm::vec3>(arm->state.positions, h);
    h = hashSpan<glm::vec3>(ball->state.positions, h);
    h = hashContacts(arm->state.contacts, h);
    h = hashContacts(ball->state.contacts, h);
    contact_area += arm->state.contacts.empty() ? 0.0 : arm->state.contacts[0].area;
  }
  EXPECT_GT(arm->state.counters.contact_vertices, 0);
  EXPECT_GT(contact_area, 0.0);  // the contacts hashed are not empty
  return h;
}

TEST(Determinism, SameHashWithOneAndTwoThreads) {
  TaskPool one(1), two(2);
  const std::uint64_t serial = replay(nullptr, 512);
  EXPECT_EQ(replay(&one, 512), serial);
  EXPECT_EQ(replay(&two, 512), serial);
  EXPECT_EQ(replay(&two, 64), serial);
  EXPECT_EQ(replay(&two, 100), serial);
}

// DeformOptions::time_phases: the phases' wall times when asked (each one measured, together
// within the call's), zeros otherwise, and the same deformation either way.
TEST(PhaseTimes, MeasuredOnlyWhenAskedAndChangeNothing) {
  const auto run = [](bool timed, DeformPhaseTimes& times, double& wall) {
    auto arm = test::armBody();
    BallSpec spec;
    spec.radius = 0.05f;
    spec.stiffness = 2.0e4f;
    auto ball = test::ballBody(spec, glm::vec3(0.45f, 0.08f, 0.0f));
    Scene scene;
    scene.bodies = {arm.get(), ball.get()};
    scene.options.time_phases = timed;
    test::bendArm(*arm, glm::radians(140.0f));  // a crease to relax and smooth, and contact
    const auto start = std::chrono::steady_clock::now();
    scene.step(0.0);
    wall = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    times = arm->state.counters.phase_seconds;
    EXPECT_GT(arm->state.counters.contact_vertices, 0);
    EXPECT_GT(arm->state.counters.relaxed_vertices, 0);
    return hashSpan<glm::vec3>(arm->state.positions);
  };
  DeformPhaseTimes off, on;
  double wall_off = 0.0, wall_on = 0.0;
  const std::uint64_t plain = run(false, off, wall_off);
  const std::uint64_t timed = run(true, on, wall_on);
  EXPECT_EQ(plain, timed);
  for (const double t :
       {off.penetration, off.solve, off.relax, off.smooth, off.normals, off.contacts}) {
    EXPECT_EQ(t, 0.0);
  }
  for (const double t : {on.penetration, on.solve, on.relax, on.smooth, on.normals, on.contacts}) {
    EXPECT_GE(t, 0.0);
  }
  EXPECT_GT(on.penetration, 0.0);
  EXPECT_GT(on.solve, 0.0);
  EXPECT_GT(on.relax, 0.0);
  EXPECT_LE(on.penetration + on.solve + on.relax + on.smooth + on.normals + on.contacts, wall_on);
}

TEST(Allocation, NoHeapAllocationPerFrameAfterWarmUp) {
  auto arm = test::armBody();
  BallSpec spec;
  spec.radius = 0.05f;
  spec.stiffness = 2.0e4f;
  auto ball = test::ballBody(spec, glm::vec3(0.45f, 0.08f, 0.0f));
  TaskPool pool(2);
  Scene scene;
  scene.bodies = {arm.get(), ball.get()};
  scene.pool = &pool;
  scene.options.chunk_size = 128;
  // Warm-up: the largest scene first (deep contact, bent elbow).
  test::bendArm(*arm, glm::radians(140.0f));
  scene.step(0.0);
  test::bendArm(*arm, 0.0f);
  scene.step(0.03);
  const test::AllocationCounter counter;
  for (int f = 0; f < 10; ++f) {
    test::bendArm(*arm, glm::radians(14.0f * f));
    ball->placement[3] = glm::vec4(0.45f, 0.09f - 0.002f * f, 0.0f, 1.0f);
    scene.step(0.06 + f / 30.0);
  }
  EXPECT_EQ(counter.count(), 0);
  EXPECT_GT(arm->state.counters.contact_vertices, 0);
}

}  // namespace
}  // namespace vistel
