// Issue 25 items 5 and 4 on real avatars: the primitives' contact surfaces meet the skin
// (a rigid ball stepped against the posed primitives, as the server does, touches before it
// sinks into the mesh) and how much of the skin is free (no field of its own).
//
// The ball comes in along the outward normal of sampled skin vertices at rest; where it
// first touches (stepBall's contact model, probed with still steps), the mesh's deepest
// vertex inside the ball is its penetration. Concave places a ball of this size cannot
// reach along the normal are left out. A sample whose deepest vertex is free is counted
// apart: free vertices (fingers, toes, the upper chest) move with bones no primitive follows,
// so no primitive's surface can stand for them (item 4, open).
#include <algorithm>
#include <cstdio>
#include <map>
#include <string>

#include <gtest/gtest.h>

#include "common/deform/posed_primitives.hpp"
#include "common/deform/prop.hpp"
#include "tests/deform/fixtures.hpp"
#include "tests/support/test_support.hpp"

namespace vistel {
namespace {

using Avatar = test::RealAvatar;

constexpr float kServerBallRadius = 0.1f;  // the server's default ball
constexpr float kLimit = 0.002f;           // issue 25 item 5: at most 2 mm into the mesh

struct Worst {
  float depth = -INFINITY;  // metres into the mesh at first touch (negative: a gap)
  int vertex = -1;          // the sampled vertex the ball came in on
  int samples = 0;
  int over = 0;  // samples deeper than kLimit
  double sum = 0.0;
};

struct Approach {
  Worst modelled;    // the deepest mesh vertex has a field of its own
  Worst free;        // the deepest mesh vertex is free
  int skipped = 0;   // concave places the ball cannot reach along the normal
  float gap = 0.0f;  // the largest distance the ball stops short of the mesh (metres)
};

void note(Worst& w, float depth, int v) {
  ++w.samples;
  w.sum += std::max(depth, 0.0f);
  if (depth > kLimit) ++w.over;
  if (depth > w.depth) {
    w.depth = depth;
    w.vertex = v;
  }
}

Approach approachBall(const test::Body& b, int stride) {
  Approach out;
  for (int v = 0; v < b.mesh.vertexCount(); v += stride) {
    const std::optional<test::BallTouch> touch = test::rigidBallTouch(b, v, kServerBallRadius);
    if (!touch) {
      ++out.skipped;
      continue;
    }
    out.gap = std::max(out.gap, -touch->depth);
    const bool free = b.model.calibration.vertex_class[static_cast<std::size_t>(touch->vertex)] ==
                      VertexClass::kFree;
    note(free ? out.free : out.modelled, touch->depth, v);
  }
  return out;
}

std::string ownerName(const test::Body& b, int v) {
  const std::int16_t p = b.model.calibration.prims[static_cast<std::size_t>(v)][0];
  return p >= 0 ? b.model.primitives.items[static_cast<std::size_t>(p)].name : "(none)";
}

// Free vertices per region (the primitive that owns them for collisions).
void printFree(const Avatar& a, const test::Body& b) {
  std::map<std::string, int> per;
  int total = 0;
  for (int v = 0; v < b.mesh.vertexCount(); ++v) {
    if (b.model.calibration.vertex_class[static_cast<std::size_t>(v)] != VertexClass::kFree)
      continue;
    ++per[ownerName(b, v)];
    ++total;
  }
  std::printf("%s: %d of %d vertices free (%d demoted at calibration):", a.avatar.name.c_str(),
              total, b.mesh.vertexCount(), a.report.calibration.demoted);
  for (const auto& [name, count] : per) std::printf(" %s %d", name.c_str(), count);
  std::printf("\n");
}

void printWorst(const char* what, const test::Body& b, const Worst& w) {
  std::printf("  %s: %d samples, worst %.4f m (vertex %d, %s), mean %.5f m, %d over 2 mm\n", what,
              w.samples, w.depth, w.vertex, w.vertex >= 0 ? ownerName(b, w.vertex).c_str() : "-",
              w.samples > 0 ? w.sum / w.samples : 0.0, w.over);
}

Approach measure(const Avatar& a, int stride) {
  auto b = test::realBody(a);
  b->pose();
  printFree(a, *b);
  const Approach ap = approachBall(*b, stride);
  std::printf(
      "%s: a rigid ball (r %.2f m) along the normal at every %d-th vertex, %d concave places "
      "skipped; mesh penetration at first touch, largest gap %.4f m:\n",
      a.avatar.name.c_str(), kServerBallRadius, stride, ap.skipped, ap.gap);
  printWorst("modelled skin", *b, ap.modelled);
  printWorst("free skin", *b, ap.free);
  return ap;
}

// A soft ball's share of the overlap (test::softBallAt), printed at sites any humanoid has:
// the crown (highest vertex), the chest (the torso's front-most), the back of the left hand
// (its highest), the left thigh's front-most vertex.
void softBallSites(const Avatar& a) {
  const SkinMesh& m = a.avatar.skin;
  const auto& cal = a.model.calibration;
  const auto owned = [&](const char* name, const auto& better) {
    int best = -1;
    for (int v = 0; v < m.vertexCount(); ++v) {
      const std::int16_t p = cal.prims[static_cast<std::size_t>(v)][0];
      if (p < 0 || a.model.primitives.items[static_cast<std::size_t>(p)].name != name) continue;
      if (best < 0 || better(m.positions[static_cast<std::size_t>(v)],
                             m.positions[static_cast<std::size_t>(best)]))
        best = v;
    }
    return best;
  };
  const auto higher = [](const glm::vec3& x, const glm::vec3& y) { return x.y > y.y; };
  const auto fronter = [](const glm::vec3& x, const glm::vec3& y) { return x.z > y.z; };
  const std::pair<const char*, int> sites[] = {{"crown", owned("head", higher)},
                                               {"chest", owned("torso", fronter)},
                                               {"hand", owned("l_hand", higher)},
                                               {"thigh", owned("l_thigh", fronter)}};
  for (const auto& [name, v] : sites) {
    if (v < 0) continue;
    const test::SoftBallShare s = test::softBallAt(a, v);
    std::printf(
        "%s soft ball on the %s (vertex %d, %s): body moves %.4f m, ball %.4f m: body share "
        "%.2f (stiffness ratio %.2f); contact areas body %.1f cm^2, ball %.1f cm^2\n",
        a.avatar.name.c_str(), name, v, s.free_site ? "free" : "modelled", s.body_move, s.ball_move,
        s.share(), s.expected, s.area_body * 1e4, s.area_ball * 1e4);
  }
}

TEST(SkinFit, DefaultAvatarSoftBallShares) {
  const Avatar* a = test::realAvatar("default");
  ASSERT_NE(a, nullptr);
  softBallSites(*a);
}

TEST(SkinFit, MakehumanSoftBallShares) {
  VISTEL_REQUIRE_SHARED(path, "avatars/makehuman_game_engine.glb");
  const Avatar* a = test::realAvatar("makehuman");
  ASSERT_NE(a, nullptr);
  softBallSites(*a);
}

TEST(SkinFit, DefaultAvatarBallMeetsTheSkin) {
  const Avatar* a = test::realAvatar("default");
  ASSERT_NE(a, nullptr);
  const Approach ap = measure(*a, 23);
  EXPECT_GT(ap.modelled.samples, 200);
  EXPECT_LE(ap.modelled.depth, kLimit);
}

TEST(SkinFit, MakehumanBallMeetsTheSkin) {
  VISTEL_REQUIRE_SHARED(path, "avatars/makehuman_game_engine.glb");
  const Avatar* a = test::realAvatar("makehuman");
  ASSERT_NE(a, nullptr);
  const Approach ap = measure(*a, 37);
  EXPECT_GT(ap.modelled.samples, 150);
  EXPECT_LE(ap.modelled.depth, kLimit);
}

}  // namespace
}  // namespace vistel
