// The room's CPU work without GL (a headless RoomView) with RoomDeformer: each body posed
// once per frame (the view takes the scene's matrices and skins exactly as it would have),
// the level of detail's tiers (near: every frame; farther: every k-th frame with held
// offsets in between; far: rigid; in contact: full rate wherever), no allocation per frame.
#include <algorithm>
#include <cmath>
#include <memory>
#include <vector>

#include <gtest/gtest.h>
#include <glm/gtc/matrix_transform.hpp>

#include "client/deform/room_deformer.hpp"
#include "client/view/room_view.hpp"
#include "tests/scene/scene_fixtures.hpp"
#include "tests/support/alloc_counter.hpp"

namespace vistel {
namespace {

std::unique_ptr<RoomView> headlessView() {
  ViewOptions options;
  options.headless = true;
  options.worker_threads = 2;
  options.width = 320;
  options.height = 240;
  Result<std::unique_ptr<RoomView>> view = RoomView::create(options);
  EXPECT_TRUE(view.ok()) << (view.ok() ? "" : view.error().message);
  return view.ok() ? std::move(*view) : nullptr;
}

// A tube (tests/scene fixture, 0.6 m along its +x) standing at `where`, turned by `yaw`
// about +y, its elbow bent by `bend` radians.
MemberView tube(std::uint32_t id, const glm::vec3& where, float yaw = 0.0f, float bend = 1.2f) {
  MemberView v;
  v.id = id;
  v.name = "tube";
  v.avatar = test::tubeAvatar();
  v.posture = restPosture(v.avatar->skeleton);
  test::bendTube(v.posture, bend);
  v.placement = glm::rotate(test::at(where), yaw, glm::vec3(0.0f, 1.0f, 0.0f));
  return v;
}

float maxDistance(std::span<const glm::vec3> a, std::span<const glm::vec3> b) {
  float d = 0.0f;
  for (std::size_t i = 0; i < std::min(a.size(), b.size()); ++i) {
    d = std::max(d, glm::distance(a[i], b[i]));
  }
  return d;
}

DeformLodSettings lodSettings() {
  DeformLodSettings s;
  s.full_radius_m = 2.0f;
  s.reduced_radius_m = 6.0f;
  s.reduced_every = 3;
  return s;
}

TEST(HeadlessRoomView, SkinsWithoutGl) {
  std::unique_ptr<RoomView> view = headlessView();
  ASSERT_NE(view, nullptr);
  EXPECT_NE(view->backendDescription().find("headless"), std::string::npos);
  EXPECT_FALSE(view->shouldClose());
  view->pollEvents();
  std::vector<MemberView> members = {tube(1, {0.0f, 1.0f, 0.0f}, 0.0f, 0.0f),
                                     tube(2, {1.0f, 1.0f, 0.0f})};
  view->render(members);
  EXPECT_EQ(view->framesRendered(), 1);
  EXPECT_EQ(view->lastStats().members_drawn, 2);
  EXPECT_EQ(view->workerThreads(), 2);
  EXPECT_EQ(view->lastCameras().size(), 1u);
  // At rest the skinned vertices are the bind-pose ones (model space).
  const std::span<const glm::vec3> rest = view->skinnedPositions(1);
  ASSERT_EQ(rest.size(), test::tubeAvatar()->skin.positions.size());
  EXPECT_LT(maxDistance(rest, test::tubeAvatar()->skin.positions), 1e-5f);
  EXPECT_GT(maxDistance(view->skinnedPositions(2), test::tubeAvatar()->skin.positions), 0.1f);
  EXPECT_FALSE(view->saveScreenshot("/nonexistent/never.png").ok());
  EXPECT_FALSE(view->readFrame().ok());
}

TEST(RoomDeformerLod, PosesOnceAndTiersByDistance) {
  std::unique_ptr<RoomView> view = headlessView();
  std::unique_ptr<RoomView> plain = headlessView();  // no deformer: poses and skins itself
  ASSERT_TRUE(view && plain);
  // Near (full rate), 4 m (lower rate), 10 m (rigid); the viewer at the origin.
  const std::vector<MemberView> members = {tube(1, {0.0f, 1.0f, 0.0f}), tube(2, {4.0f, 1.0f, 0.0f}),
                                           tube(3, {10.0f, 1.0f, 0.0f})};
  RoomDeformer deformer;
  ASSERT_TRUE(deformer.setLod(lodSettings()).ok());
  deformer.setViewer(glm::vec3(0.0f, 1.6f, 0.0f));
  std::vector<glm::vec3> reduced_before;
  int held = 0;
  int deformed = 0;
  for (int frame = 0; frame < 9; ++frame) {
    ASSERT_TRUE(deformer.sync(members, *view).ok());
    ASSERT_TRUE(deformer.prepare(frame / 60.0).ok());
    view->render(members);
    deformer.finish();
    plain->render(members);
    EXPECT_EQ(view->lastStats().poses_copied, 3) << "frame " << frame;
    EXPECT_EQ(plain->lastStats().poses_copied, 0);
    EXPECT_EQ(deformer.skippedLastFrame(), 0);
    const DeformFrameStats& s = deformer.lastStats();
    EXPECT_EQ(s.full, 1);
    EXPECT_EQ(s.reduced, 1);
    EXPECT_EQ(s.rigid, 1);
    EXPECT_EQ(s.deformed + s.held, 2);
    EXPECT_GE(s.deform_cpu_ms, 0.0);
    held += s.held;
    deformed += s.deformed;
    // The same posture every frame: the lower-rate body looks the same whether deformed or
    // held (its held offsets on the same rigid skinning).
    const std::span<const glm::vec3> reduced = view->skinnedPositions(2);
    if (!reduced_before.empty()) {
      EXPECT_LT(maxDistance(reduced, reduced_before), 1e-5f) << "frame " << frame;
    }
    reduced_before.assign(reduced.begin(), reduced.end());
  }
  // The lower-rate body (index 1) deformed on frames 2, 5 and 8 ((frame + 1) % 3 == 0) and
  // on frame 0 (no offsets yet); the near one on every frame.
  EXPECT_EQ(held, 5);
  EXPECT_EQ(deformed, 9 + 4);
  EXPECT_EQ(deformer.tier(1), DeformTier::kFull);
  EXPECT_EQ(deformer.tier(2), DeformTier::kReduced);
  EXPECT_EQ(deformer.tier(3), DeformTier::kRigid);
  EXPECT_FALSE(deformer.tier(99).has_value());
  // The rigid body is exactly what the view skins from its own posing; the deformed ones
  // differ (the bent elbow's correction).
  const auto same = [](std::span<const glm::vec3> a, std::span<const glm::vec3> b) {
    return a.size() == b.size() && std::equal(a.begin(), a.end(), b.begin());
  };
  EXPECT_TRUE(same(view->skinnedPositions(3), plain->skinnedPositions(3)));
  EXPECT_GT(maxDistance(view->skinnedPositions(1), plain->skinnedPositions(1)), 1e-4f);
  EXPECT_GT(maxDistance(view->skinnedPositions(2), plain->skinnedPositions(2)), 1e-4f);

  // Without level of detail every body deforms every frame.
  DeformLodSettings off = lodSettings();
  off.enabled = false;
  ASSERT_TRUE(deformer.setLod(off).ok());
  ASSERT_TRUE(deformer.sync(members, *view).ok());
  ASSERT_TRUE(deformer.prepare(0.5).ok());
  view->render(members);
  deformer.finish();
  EXPECT_EQ(deformer.lastStats().full, 3);
  EXPECT_EQ(deformer.lastStats().deformed, 3);
  // Invalid settings are refused and the previous ones kept.
  DeformLodSettings bad = lodSettings();
  bad.reduced_every = 0;
  EXPECT_FALSE(deformer.setLod(bad).ok());
  EXPECT_FALSE(deformer.lod().enabled);
}

TEST(RoomDeformerLod, ABodyBackFromRigidDeformsBeforeItIsHeld) {
  std::unique_ptr<RoomView> view = headlessView();
  ASSERT_NE(view, nullptr);
  std::vector<MemberView> members = {tube(1, {4.0f, 1.0f, 0.0f})};
  RoomDeformer deformer;
  DeformLodSettings lod = lodSettings();
  lod.hysteresis_m = 0.0f;
  ASSERT_TRUE(deformer.setLod(lod).ok());
  deformer.setViewer(glm::vec3(0.0f));
  auto frame = [&](int f) {
    ASSERT_TRUE(deformer.sync(members, *view).ok());
    ASSERT_TRUE(deformer.prepare(f / 60.0).ok());
    view->render(members);
    deformer.finish();
  };
  // Lower rate (body 0: deforms on the deformer's frames 0, 3, 6, ..., and on its first).
  frame(0);
  frame(1);
  EXPECT_EQ(deformer.lastStats().held, 1);
  // Walks away (rigid) for frames 2 and 3, comes back on frame 4 where it is not due: its
  // old offsets are gone, so it deforms at once instead of holding stale ones.
  members[0].placement = test::at({10.0f, 1.0f, 0.0f});
  frame(2);
  frame(3);
  EXPECT_EQ(deformer.lastStats().rigid, 1);
  EXPECT_EQ(deformer.lastStats().deformed, 0);
  members[0].placement = test::at({4.0f, 1.0f, 0.0f});
  frame(4);
  EXPECT_EQ(deformer.lastStats().reduced, 1);
  EXPECT_EQ(deformer.lastStats().deformed, 1);
  EXPECT_EQ(deformer.lastStats().held, 0);
  frame(5);
  EXPECT_EQ(deformer.lastStats().held, 1);
}

TEST(RoomDeformerLod, ContactRaisesFarBodiesToFullRate) {
  std::unique_ptr<RoomView> view = headlessView();
  ASSERT_NE(view, nullptr);
  // Two tubes crossing 10 m away (the second turned to run along z across the first's
  // upper arm, 6 cm above its axis: 2 cm into it), a third alone beside them.
  const float pi = 3.14159265f;
  const std::vector<MemberView> members = {tube(1, {10.0f, 1.0f, 0.0f}, 0.0f, 0.0f),
                                           tube(2, {10.15f, 1.06f, 0.3f}, pi / 2, 0.0f),
                                           tube(3, {10.0f, 1.0f, 3.0f}, 0.0f, 0.0f)};
  RoomDeformer deformer;
  ASSERT_TRUE(deformer.setLod(lodSettings()).ok());
  deformer.setViewer(glm::vec3(0.0f));
  ASSERT_TRUE(deformer.sync(members, *view).ok());
  ASSERT_TRUE(deformer.prepare(0.0).ok());
  view->render(members);
  deformer.finish();
  EXPECT_EQ(deformer.tier(1), DeformTier::kFull);
  EXPECT_EQ(deformer.tier(2), DeformTier::kFull);
  EXPECT_EQ(deformer.tier(3), DeformTier::kRigid);
  ASSERT_TRUE(deformer.contact(1).has_value());
  EXPECT_GT(deformer.contact(1)->area, 0.0);
  EXPECT_EQ(deformer.lastStats().deformed, 2);
}

TEST(RoomDeformerLod, RigidBodiesGoToTheGpuWhenTheViewSkinsThere) {
  ViewOptions options;
  options.headless = true;
  options.gpu_skinning = true;
  Result<std::unique_ptr<RoomView>> view = RoomView::create(options);
  ASSERT_TRUE(view.ok());
  const std::vector<MemberView> members = {tube(1, {0.0f, 1.0f, 0.0f}), tube(2, {4.0f, 1.0f, 0.0f}),
                                           tube(3, {10.0f, 1.0f, 0.0f})};
  RoomDeformer deformer;
  ASSERT_TRUE(deformer.setLod(lodSettings()).ok());
  deformer.setViewer(glm::vec3(0.0f));
  for (int frame = 0; frame < 6; ++frame) {
    ASSERT_TRUE(deformer.sync(members, **view).ok());
    ASSERT_TRUE(deformer.prepare(frame / 60.0).ok());
    (*view)->render(members);
    deformer.finish();
    // The rigid body is posed on the CPU but skinned by the GPU (headless: not at all); so
    // is the lower-rate body (index 1) between its deformations (frames 1, 3, 4: its held
    // offsets go to the shader); the others are skinned on the CPU.
    const bool held = frame == 1 || frame == 3 || frame == 4;
    const FrameStats& s = (*view)->lastStats();
    EXPECT_EQ(s.members_gpu_skinned, held ? 2 : 1) << "frame " << frame;
    EXPECT_EQ(s.gpu_offsets, held ? 1 : 0) << "frame " << frame;
    EXPECT_EQ(s.gpu_offset_uploads, 0);  // headless: nothing is uploaded
    EXPECT_EQ(s.poses_copied, 3);
    EXPECT_EQ(deformer.lastStats().held, held ? 1 : 0);
    EXPECT_EQ(deformer.lastStats().deformed, held ? 1 : 2);
    EXPECT_TRUE((*view)->skinnedPositions(3).empty());
    EXPECT_EQ((*view)->skinnedPositions(2).empty(), held);
    EXPECT_FALSE((*view)->skinnedPositions(1).empty());
  }
  // Without a deformer every member is skinned on the GPU.
  Result<std::unique_ptr<RoomView>> plain = RoomView::create(options);
  ASSERT_TRUE(plain.ok());
  (*plain)->render(members);
  EXPECT_EQ((*plain)->lastStats().members_gpu_skinned, 3);
  EXPECT_EQ((*plain)->lastStats().vertices_skinned, 0);
  EXPECT_EQ((*plain)->lastStats().members_drawn, 3);
}

TEST(RoomDeformerLod, NoAllocationPerFrameAfterWarmUp) {
  for (const bool gpu : {false, true}) {
    ViewOptions options;
    options.headless = true;
    options.worker_threads = 2;
    options.gpu_skinning = gpu;
    Result<std::unique_ptr<RoomView>> view = RoomView::create(options);
    ASSERT_TRUE(view.ok());
    std::vector<MemberView> members = {tube(1, {0.0f, 1.0f, 0.0f}), tube(2, {4.0f, 1.0f, 0.0f}),
                                       tube(3, {10.0f, 1.0f, 0.0f})};
    RoomDeformer deformer;
    ASSERT_TRUE(deformer.setLod(lodSettings()).ok());
    auto frame = [&](int f) {
      for (MemberView& m : members) {
        test::bendTube(m.posture, 1.0f + 0.1f * static_cast<float>(f % 2));
      }
      ASSERT_TRUE(deformer.sync(members, **view).ok());
      ASSERT_TRUE(deformer.prepare(f / 60.0).ok());
      (*view)->render(members);
      deformer.finish();
    };
    for (int f = 0; f < 6; ++f) frame(f);
    const test::AllocationCounter counter;
    for (int f = 6; f < 12; ++f) frame(f);
    EXPECT_EQ(counter.count(), 0) << (gpu ? "gpu skinning" : "cpu skinning");
    EXPECT_EQ(deformer.rebuilds(), 1);
    EXPECT_EQ((*view)->lastStats().members_gpu_skinned, gpu ? 1 : 0);
  }
}

}  // namespace
}  // namespace vistel
