// Issue 25 item 4: every vertex in the model. The builder gives the free vertices (fingers,
// toes, the upper chest, the crown) fields of their own (adoptFreeVertices); measured here on
// the default avatar and the shared MakeHuman body against the same avatar built with them
// left free (BuildOptions::adopt_free_vertices off): free vertices per region before and
// after, the calibrated rest (nothing moves), a rigid ball meeting the adopted skin (at most
// 2 mm into the mesh, as skin_fit_test for the rest of the body), and a soft ball on a
// fingertip, the back of the hand and the upper chest sharing the overlap with the body.
#include <algorithm>
#include <cstdio>
#include <map>
#include <memory>
#include <string>

#include <gtest/gtest.h>

#include "common/deform/posed_primitives.hpp"
#include "common/deform/prop.hpp"
#include "common/deform/vertex_field.hpp"
#include "offline/build/free_vertex_adoption.hpp"
#include "tests/deform/fixtures.hpp"
#include "tests/support/test_support.hpp"

namespace vistel {
namespace {

using Avatar = test::RealAvatar;

constexpr float kBallRadius = 0.1f;  // the server's default ball
constexpr float kLimit = 0.002f;     // issue 25 item 5: at most 2 mm into the mesh

// The avatar as the builder makes it (free vertices adopted) and as it was made before.
const Avatar* adopted(const std::string& which) { return test::realAvatar(which); }
const Avatar* keptFree(const std::string& which) { return test::realAvatar(which + ":free"); }

// The region a vertex belongs to: the joint carrying most of its skin weight, by canonical
// part (fingers, toes, chest, head...).
std::string region(const AvatarModel& a, std::size_t v) {
  const SkinMesh& m = a.skin;
  const auto k = static_cast<std::size_t>(m.influences);
  int best = -1;
  float w = 0.0f;
  for (std::size_t s = 0; s < k; ++s) {
    if (m.weights[v * k + s] > w) {
      w = m.weights[v * k + s];
      best = m.joints[v * k + s];
    }
  }
  if (best < 0) return "(none)";
  std::string n = a.skeleton.names[static_cast<std::size_t>(best)];
  std::transform(n.begin(), n.end(), n.begin(), [](unsigned char ch) { return std::tolower(ch); });
  const auto has = [&n](const char* s) { return n.find(s) != std::string::npos; };
  if (has("thumb") || has("index") || has("middle") || has("ring") || has("pinky")) {
    return "fingers";
  }
  if (has("toe") || has("ball")) return "toes";
  if (has("hand")) return "hands";
  if (has("foot")) return "feet";
  if (has("head")) return "head";
  if (has("neck")) return "neck";
  if (has("clavicle")) return "clavicles";
  if (has("spine") || has("chest")) return "chest";
  return "other";
}

std::map<std::string, int> freePerRegion(const Avatar& a, int& total) {
  std::map<std::string, int> per;
  total = 0;
  const auto& cls = a.model.calibration.vertex_class;
  for (std::size_t v = 0; v < cls.size(); ++v) {
    if (cls[v] != VertexClass::kFree) continue;
    ++per[region(a.avatar, v)];
    ++total;
  }
  return per;
}

void printFree(const char* when, const Avatar& a, const std::map<std::string, int>& per,
               int total) {
  std::printf("%s %s: %d of %d vertices free:", a.avatar.name.c_str(), when, total,
              a.avatar.skin.vertexCount());
  for (const auto& [name, count] : per) std::printf(" %s %d", name.c_str(), count);
  std::printf("\n");
}

// Free vertices per region before and after, and the rest: every adopted vertex on its
// surface, nothing moves.
void adoptionChecks(const std::string& which, int bound_total, int bound_region) {
  const Avatar* before = keptFree(which);
  ASSERT_NE(before, nullptr);
  const Avatar* after = adopted(which);
  ASSERT_NE(after, nullptr);
  int total_before = 0, total_after = 0;
  const std::map<std::string, int> per_before = freePerRegion(*before, total_before);
  printFree("before", *before, per_before, total_before);
  const std::map<std::string, int> per = freePerRegion(*after, total_after);
  printFree("after", *after, per, total_after);
  std::printf("%s: %d primitives added (%d in all), %d vertices adopted, %d demoted\n",
              which.c_str(), after->report.adopted_primitives,
              static_cast<int>(after->model.primitives.items.size()),
              after->report.adopted_vertices, after->report.calibration.demoted);
  for (std::size_t i = before->model.primitives.items.size();
       i < after->model.primitives.items.size(); ++i) {
    const Primitive& p = after->model.primitives.items[i];
    std::printf("  %s: r_in %.4f m, r_out %.4f m\n", p.name.c_str(), p.r_in, p.r_out);
  }
  EXPECT_EQ(after->model.primitives.items.size(),
            before->model.primitives.items.size() +
                static_cast<std::size_t>(after->report.adopted_primitives));
  EXPECT_LE(total_after, bound_total);
  for (const auto& [name, count] : per) EXPECT_LE(count, bound_region) << name;
  EXPECT_TRUE(validateImplicitModel(after->model, after->avatar.skeleton.jointCount(),
                                    after->avatar.skin.vertexCount())
                  .ok());

  // Adopting again changes nothing: no free vertex is left to adopt.
  ImplicitModel again = after->model;
  Result<AdoptionReport> second =
      adoptFreeVertices(again, after->avatar.skeleton, after->avatar.skin);
  ASSERT_TRUE(second.ok()) << second.error().message;
  EXPECT_EQ(second->primitives, 0);
  EXPECT_EQ(again.primitives.items.size(), after->model.primitives.items.size());

  // Every added primitive names its body part, one of the model's other primitives.
  const auto& items = after->model.primitives.items;
  for (const Primitive& p : items) {
    const std::string_view part = primitivePart(p.name);
    if (part == p.name) continue;
    EXPECT_TRUE(std::any_of(items.begin(), items.end(), [&](const Primitive& q) {
      return q.name == part;
    })) << p.name;
  }
  EXPECT_EQ(primitivePart("l_hand/index_01_l"), "l_hand");
  EXPECT_EQ(primitivePart("torso"), "torso");

  auto b = test::realBody(*after);
  test::expectRestsExactly(*b, which);
}

TEST(FreeVertices, DefaultAvatarAdopted) { adoptionChecks("default", 40, 20); }  // measured 2

TEST(FreeVertices, MakehumanAdopted) {
  VISTEL_REQUIRE_SHARED(path, "avatars/makehuman_game_engine.glb");
  adoptionChecks("makehuman", 40, 20);  // measured 0 (5,437 before)
}

// A rigid ball (r 0.1 m) brought in along the outward normal at every stride-th vertex until
// it touches the posed primitives (stepBall, as the server); the mesh's deepest vertex inside
// it then. Concave places the ball cannot reach along the normal are left out. Returns the
// worst depth over samples whose deepest vertex is modelled, counting those that are free.
struct Approach {
  float worst = -INFINITY;
  int worst_vertex = -1;
  int samples = 0, free_samples = 0, adopted_samples = 0;
};

Approach approachBall(const test::Body& b, const AvatarModel& avatar, int stride) {
  Approach out;
  for (int v = 0; v < b.mesh.vertexCount(); v += stride) {
    const std::optional<test::BallTouch> touch = test::rigidBallTouch(b, v, kBallRadius);
    if (!touch) continue;
    const auto ai = static_cast<std::size_t>(touch->vertex);
    if (b.model.calibration.vertex_class[ai] == VertexClass::kFree) {
      ++out.free_samples;
      continue;
    }
    ++out.samples;
    const std::string part = region(avatar, ai);
    if (part == "fingers" || part == "toes") ++out.adopted_samples;
    if (touch->depth > out.worst) {
      out.worst = touch->depth;
      out.worst_vertex = touch->vertex;
    }
  }
  return out;
}

void ballMeetsAdoptedSkin(const std::string& which, int stride, int min_adopted) {
  const Avatar* after = adopted(which);
  ASSERT_NE(after, nullptr);
  auto b = test::realBody(*after);
  b->pose();
  const Approach ap = approachBall(*b, after->avatar, stride);
  std::printf(
      "%s adopted: rigid ball at every %d-th vertex: %d modelled samples (%d on adopted skin), "
      "%d free; worst mesh penetration %.4f m (vertex %d, %s)\n",
      which.c_str(), stride, ap.samples, ap.adopted_samples, ap.free_samples, ap.worst,
      ap.worst_vertex,
      ap.worst_vertex >= 0
          ? region(after->avatar, static_cast<std::size_t>(ap.worst_vertex)).c_str()
          : "-");
  EXPECT_GE(ap.adopted_samples, min_adopted);
  EXPECT_EQ(ap.free_samples, 0);
  EXPECT_LE(ap.worst, kLimit);
}

TEST(FreeVertices, DefaultAvatarBallMeetsTheAdoptedSkin) {
  ballMeetsAdoptedSkin("default", 23, 50);
}

TEST(FreeVertices, MakehumanBallMeetsTheAdoptedSkin) {
  VISTEL_REQUIRE_SHARED(path, "avatars/makehuman_game_engine.glb");
  ballMeetsAdoptedSkin("makehuman", 37, 50);
}

// Sites: the left fingertip farthest from the body (+X), the back of the left hand (the
// highest vertex of the hand's primitive), the upper chest (the front-most vertex whose
// heaviest joint is the chest's), the crown (the highest vertex).
std::vector<std::pair<std::string, int>> softBallSites(const Avatar& a) {
  const SkinMesh& m = a.avatar.skin;
  const auto pick = [&](const auto& accept, const auto& better) {
    int best = -1;
    for (int v = 0; v < m.vertexCount(); ++v) {
      const auto vi = static_cast<std::size_t>(v);
      if (!accept(vi)) continue;
      if (best < 0 || better(m.positions[vi], m.positions[static_cast<std::size_t>(best)]))
        best = v;
    }
    return best;
  };
  const auto in = [&](const char* r) {
    return [&a, r](std::size_t v) { return region(a.avatar, v) == r; };
  };
  const auto owned_by = [&](const char* name) {
    return [&a, name](std::size_t v) {
      const std::int16_t p = a.model.calibration.prims[v][0];
      return p >= 0 && a.model.primitives.items[static_cast<std::size_t>(p)].name == name;
    };
  };
  const auto any = [](std::size_t) { return true; };
  const auto left = [](const glm::vec3& x, const glm::vec3& y) { return x.x > y.x; };
  const auto higher = [](const glm::vec3& x, const glm::vec3& y) { return x.y > y.y; };
  const auto fronter = [](const glm::vec3& x, const glm::vec3& y) { return x.z > y.z; };
  return {{"fingertip", pick(in("fingers"), left)},
          {"hand", pick(owned_by("l_hand"), higher)},
          {"chest", pick(in("chest"), fronter)},
          {"crown", pick(any, higher)}};
}

// After adoption no site is free; where the body is bony (the ball takes at least 95% by
// the stiffness ratio) the body's share stays under 5% (a free site took 37-56%); on the
// chest the share is within soft_tolerance of the stiffness ratio (relative); both sides'
// contact areas within a factor 2 of each other.
void softBallShares(const std::string& which, float soft_tolerance) {
  const Avatar* before = keptFree(which);
  ASSERT_NE(before, nullptr);
  const Avatar* after = adopted(which);
  ASSERT_NE(after, nullptr);
  for (const auto& [name, v] : softBallSites(*after)) {
    ASSERT_GE(v, 0) << name;
    for (const Avatar* a : {before, after}) {
      const test::SoftBallShare s = test::softBallAt(*a, v);
      std::printf(
          "%s %s: soft ball on the %s (vertex %d, %s): body moves %.4f m, ball %.4f m: body "
          "share %.3f (stiffness ratio %.3f); contact areas body %.1f cm^2, ball %.1f cm^2\n",
          which.c_str(), a == before ? "before" : "adopted", name.c_str(), v,
          s.free_site ? "free" : "modelled", s.body_move, s.ball_move, s.share(), s.expected,
          s.area_body * 1e4, s.area_ball * 1e4);
      if (a == before) continue;
      EXPECT_FALSE(s.free_site) << name;
      if (s.expected < 0.05f) {
        EXPECT_LE(s.share(), 0.05f) << name;
      } else {
        EXPECT_NEAR(s.share() / s.expected, 1.0f, soft_tolerance) << name;
      }
      const double lo = std::min(s.area_body, s.area_ball), hi = std::max(s.area_body, s.area_ball);
      EXPECT_GE(lo, 0.5 * hi) << name;
    }
  }
}

TEST(FreeVertices, DefaultAvatarSoftBallShares) { softBallShares("default", 0.2f); }

TEST(FreeVertices, MakehumanSoftBallShares) {
  VISTEL_REQUIRE_SHARED(path, "avatars/makehuman_game_engine.glb");
  softBallShares("makehuman", 1.0f);  // measured 1.78x on the chest
}

// The adopted vertices keep their skinned position until something touches them
// (kRigidUntouched), as they did free: fingers curled 60 degrees at every joint and the
// wrists bent leave every one where the skinning put it. Within the body an adopted primitive
// collides only with the map's primitives (DeformScratch::adopted).
void untouchedStaySkinned(const std::string& which) {
  const Avatar* a = adopted(which);
  ASSERT_NE(a, nullptr);
  auto b = test::realBody(*a);
  const Skeleton& sk = b->skeleton;
  std::vector<bool> adopted_prim(b->model.primitives.items.size());
  for (std::size_t i = 0; i < adopted_prim.size(); ++i) {
    const std::string& name = b->model.primitives.items[i].name;
    adopted_prim[i] = primitivePart(name) != name;
  }
  for (const auto& pair : b->model.graph.collide_pairs) {
    EXPECT_FALSE(adopted_prim[pair[0]] && adopted_prim[pair[1]])
        << b->model.primitives.items[pair[0]].name << " / "
        << b->model.primitives.items[pair[1]].name;
  }
  const glm::quat curl = glm::angleAxis(glm::radians(60.0f), glm::vec3(0.0f, 0.0f, 1.0f));
  int curled = 0;
  for (int j = 0; j < sk.jointCount(); ++j) {
    std::string n = sk.names[static_cast<std::size_t>(j)];
    std::transform(n.begin(), n.end(), n.begin(),
                   [](unsigned char ch) { return std::tolower(ch); });
    const auto has = [&n](const char* s) { return n.find(s) != std::string::npos; };
    if (has("thumb") || has("index") || has("middle") || has("ring") || has("pinky") ||
        has("hand")) {
      b->posture.rotations[static_cast<std::size_t>(j)] =
          sk.rest_local[static_cast<std::size_t>(j)].rotation * curl;
      ++curled;
    }
  }
  ASSERT_GT(curled, 10);
  test::Scene scene;
  scene.bodies = {b.get()};
  scene.step(0.0);
  int checked = 0, moved = 0;
  const Calibration& cal = b->model.calibration;
  for (std::size_t v = 0; v < cal.prims.size(); ++v) {
    if (cal.vertex_class[v] != VertexClass::kLimb || !adopted_prim[cal.prims[v][0]]) continue;
    ++checked;
    if ((b->state.flags[v] & kVertexContact) != 0) continue;
    if (b->state.positions[v] != b->rigid_pos[v]) ++moved;
  }
  std::printf("%s, fingers curled: %d adopted vertices, %d moved without a contact\n",
              which.c_str(), checked, moved);
  EXPECT_GT(checked, 1000);
  EXPECT_EQ(moved, 0);
}

TEST(FreeVertices, DefaultAvatarUntouchedStaySkinned) { untouchedStaySkinned("default"); }

TEST(FreeVertices, MakehumanUntouchedStaySkinned) {
  VISTEL_REQUIRE_SHARED(path, "avatars/makehuman_game_engine.glb");
  untouchedStaySkinned("makehuman");
}

}  // namespace
}  // namespace vistel
