// The fast path of deformSkin (patches, vectorised culling, the candidate cache's bounds,
// packed field lanes, the lone limb vertices' short way, kept problems) against the plain
// scalar reference (DeformOptions::reference: every collider of a vertex's interaction list
// tested directly, every vertex solved the full way): the same equations, so the same skin up
// to float rounding. Tolerance: 1e-5 m per vertex, ten times the root-finder's step tolerance
// (RootOptions, 1e-6 m): the two ways compute a few quantities by different float operations
// (a vertex's rigid-pose depth from the field's gradient against the skeleton distance's, the
// order of a vertex's always-pair candidates), and a root-find may then stop at another
// iterate within its tolerance. Flags may differ on a handful of borderline vertices, where a
// threshold (a move of kReshapeOffset or relax_min_offset, a contact within
// kContactTolerance) falls between the two. (Measured when written: at most 1e-6 m, no flag
// differing.) Both ways orient the relaxation by the gradient of the solve's last evaluation
// (gradientNear): a fresh gradient at the solved point moves some inner-elbow vertices of
// the bent arm by up to 2.5 mm, so it is part of the method, not of the acceleration.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <memory>

#include <gtest/gtest.h>
#include <glm/gtc/matrix_transform.hpp>

#include "common/deform/deform.hpp"
#include "common/motion/bvh.hpp"
#include "common/motion/retarget.hpp"
#include "tests/deform/fixtures.hpp"
#include "tests/support/test_support.hpp"

namespace vistel {
namespace {

constexpr float kTolerance = 1e-5f;  // metres (see the file comment)
constexpr int kBorderlineFlags = 5;  // vertices per frame whose flags may differ

struct Difference {
  float max_distance = 0.0f;
  int worst = -1;
  int flags = 0;  // vertices whose flags differ
};

Difference compare(const DeformState& fast, const DeformState& ref) {
  Difference d;
  for (std::size_t v = 0; v < fast.positions.size(); ++v) {
    const float dist = glm::length(fast.positions[v] - ref.positions[v]);
    if (!(dist <= d.max_distance)) {
      d.max_distance = dist;
      d.worst = static_cast<int>(v);
    }
    if (fast.flags[v] != ref.flags[v]) ++d.flags;
  }
  return d;
}

void expectClose(const Difference& d, const char* what, int frame) {
  EXPECT_LE(d.max_distance, kTolerance)
      << what << " frame " << frame << ": vertex " << d.worst << " differs by " << d.max_distance;
  EXPECT_LE(d.flags, kBorderlineFlags) << what << " frame " << frame;
}

// The arm bending through the hard case while a ball presses on its forearm (rigid, then
// soft and deformed too), with propagation: every term of Step 2.
TEST(Reference, ArmFixturesMatchTheFastPath) {
  for (const bool soft_ball : {false, true}) {
    std::unique_ptr<test::Body> arm[2], ball[2];
    test::Scene scene[2];
    for (int k = 0; k < 2; ++k) {
      arm[k] = test::armBody();
      BallSpec spec;
      spec.radius = 0.05f;
      spec.stiffness = soft_ball ? 3e4f : kRigidStiffness;
      ball[k] = test::ballBody(spec, glm::vec3(0.45f, 0.5f, 0.0f));
      ball[k]->deform = soft_ball;
      scene[k].bodies = {arm[k].get(), ball[k].get()};
      scene[k].options.reference = k == 1;
    }
    float worst = 0.0f;
    int flags = 0;
    for (int f = 0; f < 24; ++f) {
      const float angle = 2.6f * static_cast<float>(f) / 23.0f;
      const float depth = 0.02f * std::sin(static_cast<float>(f) * 0.4f);
      for (int k = 0; k < 2; ++k) {
        test::bendArm(*arm[k], angle);
        ball[k]->placement[3] = glm::vec4(0.45f, 0.09f - depth, 0.0f, 1.0f);
        scene[k].step(f / 30.0);
      }
      const Difference d = compare(arm[0]->state, arm[1]->state);
      expectClose(d, soft_ball ? "arm, soft ball" : "arm, rigid ball", f);
      worst = std::max(worst, d.max_distance);
      flags += d.flags;
      if (soft_ball) expectClose(compare(ball[0]->state, ball[1]->state), "soft ball", f);
    }
    std::printf("arm (%s ball): largest difference %.3g m, %d vertex flags differ\n",
                soft_ball ? "soft" : "rigid", static_cast<double>(worst), flags);
  }
}

// A real avatar on motion capture: the frames of bench_deform, where the right hand swings
// through the hips (self-contact of many parts at once).
TEST(Reference, MakehumanFramesMatchTheFastPath) {
  VISTEL_REQUIRE_SHARED(avatar_path, "avatars/makehuman_game_engine.glb");
  VISTEL_REQUIRE_SHARED(clip_path, "mocap/cmu/01_01.bvh");
  const test::RealAvatar* a = test::realAvatar("makehuman");
  ASSERT_NE(a, nullptr);
  Result<MotionClip> clip = loadBvh(clip_path);
  ASSERT_TRUE(clip.ok()) << clip.error().message;
  std::unique_ptr<test::Body> body[2];
  test::Scene scene[2];
  for (int k = 0; k < 2; ++k) {
    body[k] = test::realBody(*a);
    scene[k].bodies = {body[k].get()};
    scene[k].options.reference = k == 1;
  }
  const Skeleton cs = clipSkeleton(*clip);
  Result<const JointMap*> cmap = selectJointMap(a->maps, cs);
  ASSERT_TRUE(cmap.ok()) << cmap.error().message;
  Result<Retargeter> rt = Retargeter::forClip(*clip, **cmap, body[0]->skeleton, *a->map);
  ASSERT_TRUE(rt.ok()) << rt.error().message;
  constexpr int kFrames = 6;
  const int first = clip->frame_count / 2 - 12;
  Posture src;
  float worst = 0.0f;
  int contact = 0, flags = 0;
  for (int f = 0; f < kFrames; ++f) {
    samplePosture(*clip, first + 4 * f, src);
    for (int k = 0; k < 2; ++k) {
      rt->apply(src, body[k]->posture);
      scene[k].step(f / 30.0);
    }
    const Difference d = compare(body[0]->state, body[1]->state);
    expectClose(d, "makehuman", f);
    worst = std::max(worst, d.max_distance);
    flags += d.flags;
    contact += body[0]->state.counters.contact_vertices;
    EXPECT_NEAR(body[0]->state.counters.contact_vertices, body[1]->state.counters.contact_vertices,
                kBorderlineFlags)
        << "frame " << f;
  }
  EXPECT_GT(contact, 0) << "the frames have contacts";
  std::printf(
      "makehuman %d frames: largest difference %.3g m, %d vertex flags differ, %d contact "
      "vertices\n",
      kFrames, static_cast<double>(worst), flags, contact);
}

// DeformState holds its scratch behind a pointer: a copy carries on exactly as the original.
TEST(Reference, CopiedStateContinuesIdentically) {
  auto arm = test::armBody();
  test::Scene scene;
  scene.bodies = {arm.get()};
  test::bendArm(*arm, 2.0f);
  scene.step(0.0);
  DeformState copy = arm->state;
  DeformState moved = std::move(copy);
  test::bendArm(*arm, 2.2f);
  scene.step(1.0 / 30.0);
  const DeformState first = arm->state;
  arm->state = moved;
  scene.step(1.0 / 30.0);
  EXPECT_EQ(first.positions, arm->state.positions);
  EXPECT_EQ(first.flags, arm->state.flags);
}

}  // namespace
}  // namespace vistel
