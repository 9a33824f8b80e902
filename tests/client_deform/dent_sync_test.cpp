// Dents shared between sites (issue 25 item 9; client/deform/dent_sync.hpp): a plastic ball
// dented by one site's avatar is drawn with the same dent at a site that never saw the
// contact, also when that site builds the ball's body later (a late joiner) or rebuilds its
// scene; a site keeps what it speaks for (its own avatar, a prop it is touching); records
// go out only when they change, at most once per interval.
#include <algorithm>
#include <cmath>
#include <memory>
#include <vector>

#include <gtest/gtest.h>
#include <glm/gtc/matrix_transform.hpp>

#include "client/deform/dent_sync.hpp"
#include "client/deform/room_deformer.hpp"
#include "client/view/room_view.hpp"
#include "common/deform/prop.hpp"
#include "tests/client_deform/ball_views.hpp"

namespace vistel {
namespace {

constexpr float kClayRadius = 0.05f;
constexpr std::uint32_t kSelfA = 4, kSelfB = 6, kPropId = 9, kPropView = 0x9FFFF;
constexpr double kFrame = 1.0 / 60.0;

// One site: a headless view, its deformer and its dent sync.
struct Site {
  std::unique_ptr<RoomView> view;
  RoomDeformer deformer;
  DentSync sync;
  std::vector<MemberView> views;
  double t = 0.0;

  Site() : view(test::headlessView()) {}
  void frame() {
    EXPECT_TRUE(deformer.sync(views, *view).ok());
    EXPECT_TRUE(deformer.prepare(t).ok());
    view->render(views);
    deformer.finish();
    t += kFrame;
  }
  MemberView* find(std::uint32_t id) {
    auto it =
        std::find_if(views.begin(), views.end(), [&](const MemberView& v) { return v.id == id; });
    return it == views.end() ? nullptr : &*it;
  }
  // The drawn skin of a view's body (world), or empty when it was not deformed.
  std::vector<glm::vec3> drawn(std::uint32_t id) const {
    const std::optional<PartForceInput> in = deformer.partForceInput(id);
    if (!in) return {};
    return std::vector<glm::vec3>(in->positions.begin(), in->positions.end());
  }
};

// Its deepest dent: the largest |drawn - rigid| of the prop.
float deepest(const Site& s, const MemberView& prop) {
  const std::vector<glm::vec3> d = s.drawn(prop.id);
  float worst = 0.0f;
  for (std::size_t v = 0; v < d.size(); ++v) {
    const glm::vec3 rigid(prop.placement * glm::vec4(prop.avatar->skin.positions[v], 1.0f));
    worst = std::max(worst, glm::length(d[v] - rigid));
  }
  return worst;
}

// Bytes of a record's two packed varint lists (what Dents adds to its fixed fields).
std::size_t varintBytes(const DentRecord& r) {
  std::size_t n = 0;
  for (const auto* list : {&r.gaps, &r.depths}) {
    for (std::uint32_t x : *list) {
      do {
        ++n;
        x >>= 7;
      } while (x != 0);
    }
  }
  return n;
}

float largestDifference(const std::vector<glm::vec3>& a, const std::vector<glm::vec3>& b) {
  EXPECT_EQ(a.size(), b.size());
  float worst = 0.0f;
  for (std::size_t v = 0; v < std::min(a.size(), b.size()); ++v) {
    worst = std::max(worst, glm::length(a[v] - b[v]));
  }
  return worst;
}

class DentSyncTest : public ::testing::Test {
 protected:
  DentSyncTest()
      : clay_(test::ballAvatar(kClayRadius, 3.0e4f, Elasticity::kPlastic)),
        hand_(test::ballAvatar(kClayRadius, kRigidStiffness)) {}

  // Site A's avatar (a rigid ball, "the hand") presses the clay ball 1 cm deep for a few
  // frames and lets go; every record A gives goes to `sent`.
  void pressAtA(Site& a, std::vector<OutgoingDents>& sent, std::vector<double>& sent_at) {
    a.views = {test::ballView(kSelfA, hand_, glm::vec3(2.0f * kClayRadius - 0.01f, 0, 0), true),
               test::ballView(kPropView, clay_, glm::vec3(0.0f))};
    const DentBody self{false, kSelfA, kSelfA};
    const std::vector<DentBody> props = {{true, kPropId, kPropView}};
    for (int k = 0; k < 90; ++k) {
      if (k == 10) a.find(kSelfA)->placement = glm::translate(glm::mat4(1.0f), glm::vec3(1, 0, 0));
      a.frame();
      for (const OutgoingDents& o : a.sync.collect(a.deformer, a.t, self, props)) {
        sent.push_back(o);
        sent_at.push_back(a.t);
      }
    }
  }

  std::shared_ptr<const AvatarModel> clay_, hand_;
};

TEST_F(DentSyncTest, ADentMadeAtOneSiteIsDrawnAtAnother) {
  Site a;
  std::vector<OutgoingDents> sent;
  std::vector<double> sent_at;
  pressAtA(a, sent, sent_at);
  const float dent_a = deepest(a, *a.find(kPropView));
  std::printf(
      "site A: clay dented %.2f mm; %zu records sent, the last %zu of %u vertices in %zu bytes\n",
      dent_a * 1e3f, sent.size(), dentCount(sent.back().record), sent.back().record.vertex_count,
      varintBytes(sent.back().record));
  ASSERT_GT(dent_a, 0.004f) << "the plastic ball keeps a dent at A";
  ASSERT_FALSE(sent.empty());
  for (const OutgoingDents& o : sent) {
    EXPECT_TRUE(o.body.prop) << "the hand is rigid: only the clay has dents";
    EXPECT_EQ(o.body.id, kPropId);
  }
  // Only changes, at most every min_interval_s (0.25 s), and none once the dent is still:
  // the hand let go at frame 10 of 90.
  for (std::size_t k = 1; k < sent_at.size(); ++k) {
    EXPECT_GE(sent_at[k] - sent_at[k - 1], 0.25 - 1e-9);
  }
  EXPECT_LE(sent.size(), 3u);
  EXPECT_LT(sent_at.back(), 11 * kFrame + 0.25 + 1e-9);

  // Site B saw no contact (its copy of A's hand is far away) and adopts the records.
  Site b;
  b.views = {test::ballView(kSelfB, hand_, glm::vec3(0, 0, 1), true),
             test::ballView(kSelfA, hand_, glm::vec3(1, 0, 0)),
             test::ballView(kPropView, clay_, glm::vec3(0.0f))};
  const DentBody self_b{false, kSelfB, kSelfB};
  b.frame();
  EXPECT_LT(deepest(b, *b.find(kPropView)), 1e-6f) << "no dent at B before the records";
  for (const OutgoingDents& o : sent) {
    ASSERT_TRUE(b.sync.receive(b.deformer, b.t, self_b, o.body, o.record).ok());
  }
  b.frame();
  const float apart = largestDifference(a.drawn(kPropView), b.drawn(kPropView));
  std::printf("site B: clay dented %.2f mm; A and B differ by %.3f mm at most\n",
              deepest(b, *b.find(kPropView)) * 1e3f, apart * 1e3f);
  EXPECT_LT(apart, 2.0f * kDentQuantumM) << "the same dent at both sites, to the quantum";
  EXPECT_EQ(b.sync.counters().adopted, sent.size());

  // B's scene rebuilt (a member joins): the dent stays.
  b.views.push_back(test::ballView(12, hand_, glm::vec3(-1, 0, 0)));
  b.frame();
  EXPECT_LT(largestDifference(a.drawn(kPropView), b.drawn(kPropView)), 2.0f * kDentQuantumM);
}

TEST_F(DentSyncTest, ALateJoinerDrawsTheDentOnceTheBodyArrives) {
  Site a;
  std::vector<OutgoingDents> sent;
  std::vector<double> sent_at;
  pressAtA(a, sent, sent_at);
  ASSERT_FALSE(sent.empty());
  // C joins: the server gives it the newest record before C draws the prop (its model is
  // not built yet): the record waits for the body.
  Site c;
  c.views = {test::ballView(kSelfB, hand_, glm::vec3(0, 0, 1), true)};
  c.frame();
  const DentBody self_c{false, kSelfB, kSelfB};
  ASSERT_TRUE(c.sync.receive(c.deformer, c.t, self_c, sent.back().body, sent.back().record).ok());
  EXPECT_EQ(c.deformer.pendingDents(), 1);
  c.views.push_back(test::ballView(kPropView, clay_, glm::vec3(0.0f)));
  c.frame();
  EXPECT_EQ(c.deformer.pendingDents(), 0);
  EXPECT_LT(largestDifference(a.drawn(kPropView), c.drawn(kPropView)), 2.0f * kDentQuantumM);

  // A record for a view that is no longer drawn is dropped, not kept for ever.
  ASSERT_TRUE(
      c.sync.receive(c.deformer, c.t, self_c, DentBody{true, 77, 0x77FFFF}, sent.back().record)
          .ok());
  EXPECT_EQ(c.deformer.pendingDents(), 1);
  c.frame();
  EXPECT_EQ(c.deformer.pendingDents(), 0);
}

// A viscoelastic dent adopted late has recovered over the record's age as it has at the site
// that made it: a record 0.5 s old (the ball's time constant) arrives at e^-1 of its depth.
TEST_F(DentSyncTest, AViscoelasticDentRecoversOverTheRecordsAge) {
  const auto putty = test::ballAvatar(kClayRadius, 3.0e4f, Elasticity::kViscoelastic);
  ASSERT_NE(putty, nullptr);
  const float tau = putty->implicit->primitives.items[0].time_constant;
  Site a;
  a.views = {test::ballView(kSelfA, hand_, glm::vec3(2.0f * kClayRadius - 0.01f, 0, 0), true),
             test::ballView(kPropView, putty, glm::vec3(0.0f))};
  for (int k = 0; k < 5; ++k) a.frame();
  DentRecord pressed;
  ASSERT_TRUE(a.deformer.recordDents(kPropView, pressed));
  ASSERT_GT(dentCount(pressed), 10u);

  Site c;
  c.views = {test::ballView(kSelfB, hand_, glm::vec3(0, 0, 1), true),
             test::ballView(kPropView, putty, glm::vec3(0.0f))};
  c.frame();
  const DentBody self_c{false, kSelfB, kSelfB};
  ASSERT_TRUE(
      c.sync.receive(c.deformer, c.t, self_c, {true, kPropId, kPropView}, pressed, tau).ok());
  DentRecord adopted;
  ASSERT_TRUE(c.deformer.recordDents(kPropView, adopted));
  std::vector<float> made(pressed.vertex_count), got(adopted.vertex_count);
  ASSERT_TRUE(applyDents(pressed, made).ok());
  ASSERT_TRUE(applyDents(adopted, got).ok());
  float deepest_made = 0.0f, deepest_got = 0.0f;
  for (std::size_t v = 0; v < made.size(); ++v) {
    EXPECT_NEAR(got[v], made[v] * std::exp(-1.0f), 1.5f * kDentQuantumM) << v;
    deepest_made = std::min(deepest_made, made[v]);
    deepest_got = std::min(deepest_got, got[v]);
  }
  std::printf("viscoelastic dent %.2f mm, adopted %.2f s late: %.2f mm (e^-1 of it: %.2f mm)\n",
              -deepest_made * 1e3f, tau, -deepest_got * 1e3f,
              -deepest_made * 1e3f * std::exp(-1.0f));
  // A negative age is refused.
  EXPECT_FALSE(c.deformer.adoptDents(kPropView, pressed, -1.0));
}

TEST_F(DentSyncTest, ASiteKeepsWhatItSpeaksFor) {
  Site a;
  std::vector<OutgoingDents> sent;
  std::vector<double> sent_at;
  a.views = {test::ballView(kSelfA, hand_, glm::vec3(2.0f * kClayRadius - 0.01f, 0, 0), true),
             test::ballView(kPropView, clay_, glm::vec3(0.0f))};
  const DentBody self{false, kSelfA, kSelfA};
  const std::vector<DentBody> props = {{true, kPropId, kPropView}};
  for (int k = 0; k < 5; ++k) {
    a.frame();
    a.sync.collect(a.deformer, a.t, self, props);
  }
  ASSERT_TRUE(a.deformer.touching(kSelfA, kPropView));
  const std::vector<glm::vec3> before = a.drawn(kPropView);
  // Another site's record (no dent) for the prop A is pressing, and for A's own avatar: both
  // skipped; A's dent stays.
  DentRecord none;
  none.vertex_count = static_cast<std::uint32_t>(clay_->skin.vertexCount());
  EXPECT_TRUE(a.sync.receive(a.deformer, a.t, self, props[0], none).ok());
  DentRecord own;
  own.vertex_count = static_cast<std::uint32_t>(hand_->skin.vertexCount());
  EXPECT_TRUE(a.sync.receive(a.deformer, a.t, self, self, own).ok());
  EXPECT_EQ(a.sync.counters().skipped, 2u);
  EXPECT_EQ(a.sync.counters().adopted, 0u);
  a.frame();
  EXPECT_LT(largestDifference(before, a.drawn(kPropView)), 1e-5f);

  // Once A has let go for longer than linger_s, the prop is another site's again.
  a.find(kSelfA)->placement = glm::translate(glm::mat4(1.0f), glm::vec3(1, 0, 0));
  for (int k = 0; k < 70; ++k) {
    a.frame();
    a.sync.collect(a.deformer, a.t, self, props);
  }
  EXPECT_TRUE(a.sync.receive(a.deformer, a.t, self, props[0], none).ok());
  EXPECT_EQ(a.sync.counters().adopted, 1u);
  a.frame();
  EXPECT_LT(deepest(a, *a.find(kPropView)), 1e-6f) << "the other site's record: no dent";

  // A record for another mesh is refused and named.
  DentRecord wrong = none;
  wrong.vertex_count += 1;
  const Status refused = a.sync.receive(a.deformer, a.t, self, props[0], wrong);
  ASSERT_FALSE(refused);
  EXPECT_NE(refused.error().message.find("prop 0x9"), std::string::npos) << refused.error().message;
  EXPECT_EQ(a.sync.counters().failed, 1u);
}

}  // namespace
}  // namespace vistel
