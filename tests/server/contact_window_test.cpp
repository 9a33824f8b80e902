// Step 1 in step with what clients draw (issue 25): a client draws remote members a
// playback delay behind the server's newest postures and its own avatar ahead of them, so
// the server's interaction list covers each primitive's motion over contact_window_s back
// and contact_lead_s ahead. A fast body that meets another between ticks, or has just left
// it, keeps its pairs in the list; with no window it loses them.
#include <gtest/gtest.h>

#include "common/anim/posture.hpp"
#include "common/avatar/avatar_io.hpp"
#include "common/wire/posture_codec.hpp"
#include "server/core/collision_model.hpp"
#include "server/core/room_world.hpp"
#include "tests/net/synthetic_avatar.hpp"

namespace vistel::server {
namespace {

constexpr double kTick = 1.0 / 60.0;
const MemberId kMover{0x00010001u};
const MemberId kStill{0x00010002u};

// Two colliding members 1.2 m apart along x; the mover's hips are shifted by `shift`
// metres towards the other (its root translation).
struct Pair {
  RoomWorld world;
  Skeleton skeleton;
  std::uint16_t sequence = 0;

  explicit Pair(float window, float lead) : world(settings(window, lead)) {
    auto decoded = decodeAvatar(encodeAvatar(test::makeCollidingAvatar()), "test");
    EXPECT_TRUE(decoded);
    skeleton = decoded->skeleton;
    auto model = makeCollisionModel(std::move(*decoded), {}, "test");
    EXPECT_TRUE(model);
    world.addMember(kMover, SeatPlacement{0.0f, 0.0f, 0.0f}, *model);
    world.addMember(kStill, SeatPlacement{1.2f, 0.0f, 0.0f}, *model);
  }
  static WorldSettings settings(float window, float lead) {
    WorldSettings s;
    s.contact_window_s = window;
    s.contact_lead_s = lead;
    return s;
  }
  // One tick with the mover's hips `shift` metres towards the other member.
  void tick(float shift) {
    Posture p = restPosture(skeleton);
    p.root_translation = skeleton.rest_local[0].translation + glm::vec3(shift, 0.0f, 0.0f);
    wire::PostureRecord record;
    ++sequence;
    ASSERT_TRUE(wire::encodePostureRecord(p, sequence, sequence * kTick, record));
    world.setPosture(kMover, record);
    world.step(kTick);
  }
  bool touching() const {
    for (const Interaction& i : world.interactions().pairs) {
      if (i.body_a != i.body_b) return true;
    }
    return false;
  }
};

// The shift at which the two bodies' primitives first overlap (newest poses, no window).
float touchingShift() {
  Pair probe(0.0f, 0.0f);
  for (float shift = 0.0f; shift < 1.2f; shift += 0.005f) {
    probe.tick(shift);
    if (probe.touching()) return shift;
  }
  ADD_FAILURE() << "the bodies never meet";
  return 1.2f;
}

// The mover approaches at 3 m/s (5 cm a tick); at the tick where it is still 2 cm short,
// the client drawing it ahead (0.05 s: 15 cm) sees it touch. Without a window and a lead
// (the newest poses alone), the pair would reach that client a tick late.
TEST(ContactWindow, AFastBodyMeetsAnotherBetweenTicks) {
  const float meet = touchingShift();
  for (const float margins : {0.0f, 1.0f}) {
    Pair pair(0.15f * margins, 0.05f * margins);
    const float short_of = meet - 0.02f;
    for (int k = 6; k >= 0; --k) pair.tick(short_of - 0.05f * static_cast<float>(k));
    EXPECT_EQ(pair.touching(), margins > 0.0f) << "window and lead x " << margins;
  }
  // Only the lead, after a rest: the last tick's motion alone reaches ahead.
  Pair lead_only(0.0f, 0.05f);
  for (int k = 0; k < 10; ++k) lead_only.tick(meet - 0.3f);
  lead_only.tick(meet - 0.07f);  // 23 cm in one tick (14 m/s): 0.7 m ahead in 0.05 s
  EXPECT_FALSE(lead_only.touching()) << "no window: no past motion to lead with";
}

// The mover leaves at 2 m/s after touching: for the window after it left, clients still
// draw it touching (a playback delay behind), so the pairs stay; after the window, not.
TEST(ContactWindow, PairsStayWhileClientsStillDrawTheContact) {
  const float meet = touchingShift();
  for (const float window : {0.0f, 0.15f}) {
    Pair pair(window, 0.0f);
    for (int k = 0; k < 10; ++k) pair.tick(meet + 0.05f);  // deep in contact, at rest
    ASSERT_TRUE(pair.touching());
    int ticks_touching = 0;
    for (int k = 1; k <= 30; ++k) {
      pair.tick(meet - 0.02f - (2.0f * kTick) * static_cast<float>(k));  // clear, leaving
      if (pair.touching()) ++ticks_touching;
    }
    if (window > 0.0f) {
      // 0.15 s = 9 ticks after it left, the newest pose is still within the window of one
      // that touched.
      EXPECT_GE(ticks_touching, 8) << "window " << window;
      EXPECT_LE(ticks_touching, 10) << "window " << window;
    } else {
      EXPECT_EQ(ticks_touching, 0);
    }
  }
}

// A body at rest gets no margin: the list is exactly the newest poses' (no extra pairs to
// send when nobody moves).
TEST(ContactWindow, BodiesAtRestGetNoMargin) {
  const float meet = touchingShift();
  Pair still(0.15f, 0.05f), bare(0.0f, 0.0f);
  for (int k = 0; k < 20; ++k) {
    still.tick(meet - 0.03f);
    bare.tick(meet - 0.03f);
  }
  EXPECT_EQ(still.world.interactions().pairs, bare.world.interactions().pairs);
  EXPECT_FALSE(still.touching());
}

}  // namespace
}  // namespace vistel::server
