// DeformScene on synthetic bodies: the frame equals the three steps run by hand, the split
// frame (prepare / deformBody / collectContacts) equals step(), contacts are equal and
// opposite, received interaction lists are used or rejected, rigid-only and bad postures,
// and the same bits with 1 and 2 threads.
#include <algorithm>
#include <cmath>
#include <thread>

#include <gtest/gtest.h>
#include <glm/gtc/matrix_transform.hpp>

#include "common/base/hash.hpp"
#include "common/deform/posed_primitives.hpp"
#include "tests/scene/scene_fixtures.hpp"

namespace vistel {
namespace {

using test::at;

// Ball at (0.45, 0.08, 0): the tube (radius 0.04 along +X) and the ball (0.05) overlap 1 cm.
const glm::vec3 kBallInContact(0.45f, 0.08f, 0.0f);

DeformScene tubeAndBall(const SceneOptions& options = {}, float stiffness = kRigidStiffness,
                        const glm::mat4& tube_placement = glm::mat4(1.0f)) {
  std::vector<SceneBody> bodies = {SceneBody{"tube", test::tubeAvatar(), tube_placement, true},
                                   SceneBody{"ball", test::ballAvatar(0.05f, stiffness),
                                             tube_placement * at(kBallInContact), true}};
  Result<DeformScene> scene = DeformScene::create(std::move(bodies), options);
  EXPECT_TRUE(scene.ok()) << (scene.ok() ? "" : scene.error().message);
  return std::move(*scene);
}

float maxDistance(std::span<const glm::vec3> a, std::span<const glm::vec3> b) {
  float m = 0.0f;
  for (std::size_t i = 0; i < a.size(); ++i) m = std::max(m, glm::length(a[i] - b[i]));
  return m;
}

bool sameBits(std::span<const glm::vec3> a, std::span<const glm::vec3> b) {
  return a.size() == b.size() && hashSpan<glm::vec3>(a) == hashSpan<glm::vec3>(b);
}

TEST(DeformScene, StepEqualsTheThreeStepsByHand) {
  DeformScene scene = tubeAndBall({}, 2.0e4f);
  test::bendTube(scene.posture(0), 0.3f);
  ASSERT_TRUE(scene.step(0.0).ok());

  // The same frame by hand: skin, pose primitives, Step 1, Steps 2-3, contacts.
  struct Manual {
    std::vector<glm::mat4> joints, skin;
    std::vector<DualQuat> dq;
    std::vector<glm::vec3> pos, nrm;
    PosedPrimitives posed;
    DeformState state;
  };
  std::vector<Manual> m(2);
  std::vector<BodyView> views(2);
  for (int i = 0; i < 2; ++i) {
    const AvatarModel& a = *scene.body(i).avatar;
    Manual& b = m[static_cast<std::size_t>(i)];
    const auto nj = static_cast<std::size_t>(a.skeleton.jointCount());
    b.joints.resize(nj);
    b.skin.resize(nj);
    b.dq.resize(nj);
    b.pos.resize(a.skin.positions.size());
    b.nrm.resize(a.skin.positions.size());
    Posture p = i == 0 ? scene.posture(0) : restPosture(a.skeleton);
    poseSkeleton(a.skeleton, p, b.joints);
    skinningMatrices(a.skeleton, b.joints, b.skin);
    for (glm::mat4& x : b.skin) x = scene.body(i).placement * x;
    skinMesh(a.skin, SkinningMethod::kDualQuaternion, b.skin, b.dq, b.pos, b.nrm);
    posePrimitives(a.implicit->primitives, b.skin, b.posed);
    ASSERT_TRUE(initDeformState(*a.implicit, a.skin.indices, b.state).ok());
    views[static_cast<std::size_t>(i)] = BodyView{&a.implicit->graph, &b.posed};
  }
  InteractionScratch scratch;
  InteractionList list;
  buildInteractions(views, scratch, list);
  EXPECT_EQ(list.pairs, scene.interactions().pairs);
  EXPECT_FALSE(list.pairs.empty());
  std::vector<const DeformState*> states;
  for (int i = 0; i < 2; ++i) {
    Manual& b = m[static_cast<std::size_t>(i)];
    const AvatarModel& a = *scene.body(i).avatar;
    DeformInput in{b.pos, b.nrm, a.skin.indices, 0.0, a.skin.positions};
    deformSkin(*a.implicit, views, i, list, in, b.state);
    states.push_back(&b.state);
    EXPECT_TRUE(sameBits(b.pos, scene.rigidPositions(i))) << "body " << i;
    EXPECT_TRUE(sameBits(b.state.positions, scene.positions(i))) << "body " << i;
    EXPECT_TRUE(sameBits(b.state.normals, scene.normals(i))) << "body " << i;
  }
  std::vector<PairContact> pairs;
  combineContacts(states, pairs);
  ASSERT_EQ(pairs.size(), scene.contacts().size());
  ASSERT_EQ(pairs.size(), 1u);
  EXPECT_EQ(pairs[0].force_on_a, scene.contacts()[0].force_on_a);
}

TEST(DeformScene, ATubeAloneAtRestDoesNotMove) {
  std::vector<SceneBody> bodies = {SceneBody{"tube", test::tubeAvatar(), at({1, 2, 3}), true}};
  Result<DeformScene> scene = DeformScene::create(std::move(bodies));
  ASSERT_TRUE(scene.ok()) << scene.error().message;
  ASSERT_TRUE(scene->step(0.0).ok());
  EXPECT_LT(maxDistance(scene->positions(0), scene->rigidPositions(0)), 1e-5f);
  EXPECT_NEAR(scene->rigidPositions(0)[0].x, test::tubeAvatar()->skin.positions[0].x + 1.0f, 1e-6f);
  EXPECT_EQ(scene->contacts().size(), 0u);
  EXPECT_EQ(scene->contactSummary(0).area, 0.0);
  EXPECT_TRUE(scene->contactSummary(0).deformed);
}

TEST(DeformScene, ContactIsEqualAndOppositeAndPushesApart) {
  for (const float stiffness : {kRigidStiffness, 2.0e4f}) {
    DeformScene scene = tubeAndBall({}, stiffness);
    ASSERT_TRUE(scene.step(0.0).ok());
    const BodyContactSummary tube = scene.contactSummary(0);
    const BodyContactSummary ball = scene.contactSummary(1);
    EXPECT_GT(tube.area, 1e-5) << stiffness;
    EXPECT_EQ(tube.partner, 1);
    EXPECT_EQ(ball.partner, 0);
    EXPECT_EQ(tube.partner_count, 1);
    EXPECT_EQ(tube.self_area, 0.0);
    EXPECT_NEAR(tube.max_depth, 0.01, 2e-3);
    // Equal and opposite, the ball (above the tube) pushed up, the tube down.
    EXPECT_EQ(tube.force + ball.force, glm::dvec3(0.0));
    EXPECT_GT(ball.force.y, 0.0);
    EXPECT_GT(glm::length(ball.force), 0.1 * std::abs(ball.force.y) + 1e-6);
    // The tube's vertices under the ball were pushed in: all the way against a rigid ball
    // (which does not move), part of the way against a soft one (which gives too).
    if (stiffness == kRigidStiffness) {
      EXPECT_GT(maxDistance(scene.positions(0), scene.rigidPositions(0)), 8e-3f);
      EXPECT_LT(maxDistance(scene.positions(1), scene.rigidPositions(1)), 1e-5f);
    } else {
      EXPECT_GT(maxDistance(scene.positions(0), scene.rigidPositions(0)), 2e-3f);
      EXPECT_GT(maxDistance(scene.positions(1), scene.rigidPositions(1)), 2e-3f);
    }
  }
}

TEST(DeformScene, SplitFrameEqualsStep) {
  // A placement with a rotation: the split frame works in model space, step() in world.
  const glm::mat4 placement =
      glm::rotate(at({0.5f, 1.0f, -2.0f}), 0.7f, glm::normalize(glm::vec3(0.2f, 1.0f, 0.1f)));
  DeformScene whole = tubeAndBall({}, 2.0e4f, placement);
  DeformScene split = tubeAndBall({}, 2.0e4f, placement);
  for (int frame = 0; frame < 3; ++frame) {
    const float angle = 0.2f * static_cast<float>(frame);
    test::bendTube(whole.posture(0), angle);
    test::bendTube(split.posture(0), angle);
    const double time = frame / 30.0;
    ASSERT_TRUE(whole.step(time).ok());
    ASSERT_TRUE(split.prepare(time).ok());
    EXPECT_EQ(split.interactions().pairs, whole.interactions().pairs);
    for (int i = 0; i < 2; ++i) {
      // What a renderer does: skin in model space with the prepared matrices.
      const AvatarModel& a = *split.body(i).avatar;
      std::vector<glm::vec3> pos(a.skin.positions.size()), nrm(pos.size());
      std::vector<DualQuat> dq(split.skinMatrices(i).size());
      skinMesh(a.skin, SkinningMethod::kDualQuaternion, split.skinMatrices(i), dq, pos, nrm);
      EXPECT_TRUE(split.matchesPrepared(i, split.skinMatrices(i), split.body(i).placement));
      split.deformBody(i, pos, nrm);
      // Back in model space; the scene keeps the world-space result.
      for (std::size_t v = 0; v < pos.size(); ++v) {
        const glm::vec3 world(split.body(i).placement * glm::vec4(pos[v], 1.0f));
        ASSERT_LT(glm::length(world - split.positions(i)[v]), 2e-6f);
      }
      EXPECT_LT(maxDistance(split.positions(i), whole.positions(i)), 1e-5f) << i;
    }
    split.collectContacts();
    ASSERT_EQ(split.contacts().size(), 1u);
    const BodyContactSummary a = split.contactSummary(0);
    const BodyContactSummary b = whole.contactSummary(0);
    EXPECT_NEAR(a.area, b.area, 0.02 * b.area);
    EXPECT_LT(glm::length(a.force - b.force), 0.02 * glm::length(b.force));
  }
  // A renderer that skinned another posture is told.
  std::vector<glm::mat4> other(split.skinMatrices(0).begin(), split.skinMatrices(0).end());
  other[1][3].x += 1e-3f;
  EXPECT_FALSE(split.matchesPrepared(0, other, split.body(0).placement));
  EXPECT_FALSE(split.matchesPrepared(0, split.skinMatrices(0), glm::mat4(1.0f)));
}

TEST(DeformScene, DeformBodyRunsConcurrentlyForDifferentBodies) {
  // Two tubes crossing: each deforms against the other.
  const auto make = [] {
    std::vector<SceneBody> bodies = {
        SceneBody{"a", test::tubeAvatar(), glm::mat4(1.0f), true},
        SceneBody{"b", test::tubeAvatar(),
                  glm::rotate(at({0.45f, 0.07f, -0.45f}), -1.5708f, glm::vec3(0, 1, 0)), true}};
    Result<DeformScene> s = DeformScene::create(std::move(bodies));
    EXPECT_TRUE(s.ok());
    return std::move(*s);
  };
  DeformScene serial = make();
  DeformScene threaded = make();
  const AvatarModel& a = *test::tubeAvatar();
  std::vector<std::vector<glm::vec3>> pos(4, std::vector<glm::vec3>(a.skin.positions.size()));
  std::vector<std::vector<glm::vec3>> nrm = pos;
  std::vector<DualQuat> dq(3);
  ASSERT_TRUE(serial.prepare(0.0).ok());
  ASSERT_TRUE(threaded.prepare(0.0).ok());
  for (int k = 0; k < 4; ++k) {
    skinMesh(a.skin, SkinningMethod::kDualQuaternion, serial.skinMatrices(k % 2), dq,
             pos[static_cast<std::size_t>(k)], nrm[static_cast<std::size_t>(k)]);
  }
  serial.deformBody(0, pos[0], nrm[0]);
  serial.deformBody(1, pos[1], nrm[1]);
  std::thread t0([&] { threaded.deformBody(0, pos[2], nrm[2]); });
  std::thread t1([&] { threaded.deformBody(1, pos[3], nrm[3]); });
  t0.join();
  t1.join();
  serial.collectContacts();
  threaded.collectContacts();
  EXPECT_TRUE(sameBits(pos[0], pos[2]));
  EXPECT_TRUE(sameBits(pos[1], pos[3]));
  EXPECT_TRUE(sameBits(nrm[0], nrm[2]));
  ASSERT_EQ(serial.contacts().size(), 1u);
  EXPECT_EQ(serial.contacts()[0].force_on_a, threaded.contacts()[0].force_on_a);
  EXPECT_GT(serial.contactSummary(0).area, 0.0);
  EXPECT_GT(serial.contactSummary(1).area, 0.0);
  EXPECT_EQ(serial.contactSummary(0).force + serial.contactSummary(1).force, glm::dvec3(0.0));
}

TEST(DeformScene, UsesAValidReceivedListAndRejectsABadOne) {
  DeformScene local = tubeAndBall();
  ASSERT_TRUE(local.step(0.0).ok());
  const InteractionList received = local.interactions();
  ASSERT_FALSE(received.pairs.empty());

  // A server's list: only `pairs` travels.
  InteractionList sent;
  sent.pairs = received.pairs;
  std::reverse(sent.pairs.begin(), sent.pairs.end());
  DeformScene remote = tubeAndBall();
  ASSERT_TRUE(remote.step(0.0, &sent).ok());
  EXPECT_EQ(remote.interactions().pairs, received.pairs);
  EXPECT_TRUE(sameBits(remote.positions(0), local.positions(0)));

  // An empty list: no contact at all this frame (the server says nothing touches).
  InteractionList none;
  ASSERT_TRUE(remote.step(0.0, &none).ok());
  EXPECT_EQ(remote.contactSummary(0).area, 0.0);

  // Out of range, self-paired, not allowed: an error, and the local Step 1 is used.
  for (const Interaction bad : {Interaction{0, 0, 1, 7}, Interaction{0, 1, 0, 1},
                                Interaction{0, 0, 5, 0}, Interaction{0, 0, 0, 2}}) {
    InteractionList list;
    list.pairs = {bad};
    const Status st = remote.step(0.0, &list);
    EXPECT_FALSE(st.ok());
    if (!st.ok()) {
      EXPECT_NE(st.error().message.find("received interaction list"), std::string::npos)
          << st.error().message;
    }
    EXPECT_EQ(remote.interactions().pairs, received.pairs);
    EXPECT_GT(remote.contactSummary(0).area, 0.0);
  }
}

TEST(DeformScene, RigidOnlySkinsAndNothingElse) {
  SceneOptions options;
  options.rigid_only = true;
  options.skinning = SkinningMethod::kLinear;
  DeformScene scene = tubeAndBall(options);
  EXPECT_FALSE(scene.deforms(0));
  test::bendTube(scene.posture(0), 0.5f);
  ASSERT_TRUE(scene.step(0.0).ok());
  EXPECT_TRUE(sameBits(scene.positions(0), scene.rigidPositions(0)));
  EXPECT_TRUE(scene.interactions().pairs.empty());
  EXPECT_TRUE(scene.contacts().empty());
  EXPECT_FALSE(scene.contactSummary(0).deformed);
  EXPECT_EQ(scene.deformState(0), nullptr);
  // Linear blend skinning as asked.
  const AvatarModel& a = *scene.body(0).avatar;
  std::vector<glm::vec3> pos(a.skin.positions.size()), nrm(pos.size());
  std::vector<DualQuat> dq(3);
  skinMesh(a.skin, SkinningMethod::kLinear, scene.skinMatrices(0), dq, pos, nrm);
  EXPECT_TRUE(sameBits(pos, scene.rigidPositions(0)));
  // deformBody leaves the vertices alone.
  std::vector<glm::vec3> copy = pos;
  scene.deformBody(0, pos, nrm);
  EXPECT_TRUE(sameBits(pos, copy));
}

TEST(DeformScene, APostureThatDoesNotFitIsDrawnAtRest) {
  DeformScene scene = tubeAndBall();
  scene.posture(0).rotations.resize(2);
  ASSERT_TRUE(scene.step(0.0).ok());
  EXPECT_EQ(scene.posturesAtRest(), 1);
  DeformScene rest = tubeAndBall();
  ASSERT_TRUE(rest.step(0.0).ok());
  EXPECT_TRUE(sameBits(scene.positions(0), rest.positions(0)));
  Posture nan = restPosture(scene.body(0).avatar->skeleton);
  nan.rotations[1].x = NAN;
  scene.setPosture(0, nan);
  ASSERT_TRUE(scene.step(0.0).ok());
  EXPECT_EQ(scene.posturesAtRest(), 1);
}

TEST(DeformScene, CreateRejectsBadInput) {
  EXPECT_FALSE(DeformScene::create({}).ok());
  std::vector<SceneBody> none = {SceneBody{"x", nullptr, glm::mat4(1.0f), true}};
  Result<DeformScene> r = DeformScene::create(none);
  ASSERT_FALSE(r.ok());
  EXPECT_NE(r.error().message.find("no avatar"), std::string::npos);
  auto broken = std::make_shared<AvatarModel>(*test::tubeAvatar());
  broken->skin.indices.push_back(99999);
  std::vector<SceneBody> bad = {SceneBody{"broken", broken, glm::mat4(1.0f), true}};
  r = DeformScene::create(bad);
  ASSERT_FALSE(r.ok());
  EXPECT_NE(r.error().message.find("broken"), std::string::npos) << r.error().message;
  SceneOptions zero;
  zero.threads = 0;
  std::vector<SceneBody> ok = {SceneBody{"tube", test::tubeAvatar(), glm::mat4(1.0f), true}};
  EXPECT_FALSE(DeformScene::create(ok, zero).ok());
  // A body without an implicit model is skinned and never deformed.
  auto plain = std::make_shared<AvatarModel>(*test::tubeAvatar());
  plain->implicit.reset();
  std::vector<SceneBody> mixed = {
      SceneBody{"plain", plain, glm::mat4(1.0f), true},
      SceneBody{"ball", test::ballAvatar(0.05f), at(kBallInContact), true}};
  r = DeformScene::create(mixed);
  ASSERT_TRUE(r.ok()) << r.error().message;
  EXPECT_FALSE(r->deforms(0));
  ASSERT_TRUE(r->step(0.0).ok());
  EXPECT_TRUE(r->interactions().pairs.empty());
}

// A short replay: the elbow bends while a soft viscoelastic ball slides along the forearm.
std::uint64_t replay(int threads, int skin_chunk, int deform_chunk) {
  SceneOptions options;
  options.threads = threads;
  options.skin_chunk = skin_chunk;
  options.deform.chunk_size = deform_chunk;
  BallSpec spec;
  spec.radius = 0.05f;
  spec.stiffness = 2.0e4f;
  spec.elasticity = Elasticity::kViscoelastic;
  Result<std::shared_ptr<const AvatarModel>> ball = makeBallAvatar(spec);
  EXPECT_TRUE(ball.ok());
  std::vector<SceneBody> bodies = {SceneBody{"tube", test::tubeAvatar(), glm::mat4(1.0f), true},
                                   SceneBody{"ball", *ball, glm::mat4(1.0f), true}};
  Result<DeformScene> scene = DeformScene::create(std::move(bodies), options);
  EXPECT_TRUE(scene.ok());
  std::uint64_t h = kFnvOffset;
  int contact_frames = 0;
  for (int f = 0; f < 16; ++f) {
    const float t = static_cast<float>(f) / 15.0f;
    test::bendTube(scene->posture(0), 1.2f * t);
    scene->setPlacement(1, at({0.35f + 0.2f * t, 0.0f, 0.08f - 0.015f * t}));
    EXPECT_TRUE(scene->step(f / 30.0).ok());
    for (int i = 0; i < 2; ++i) {
      h = hashSpan(scene->positions(i), h);
      h = hashSpan(scene->normals(i), h);
    }
    const glm::dvec3 force = scene->contactSummary(0).force;
    h = fnv1a64(&force, sizeof force, h);
    if (scene->contactSummary(0).area > 0.0) ++contact_frames;
  }
  EXPECT_GE(contact_frames, 4);
  return h;
}

TEST(DeformScene, SameHashWithOneAndTwoThreads) {
  const std::uint64_t one = replay(1, 2048, 512);
  EXPECT_EQ(replay(2, 2048, 512), one);
  EXPECT_EQ(replay(2, 100, 64), one);
  EXPECT_EQ(replay(1, 7, 100), one);
}

}  // namespace
}  // namespace vistel
