// Step 1: sweep-and-prune across bodies agrees with testing every pair.
#include <random>
#include <set>
#include <tuple>

#include <gtest/gtest.h>
#include <glm/gtc/matrix_transform.hpp>

#include "common/deform/interactions.hpp"

namespace vistel {
namespace {

struct RandomBody {
  PrimitiveSet set;
  CombinationGraph graph;
  PosedPrimitives posed;
};

RandomBody randomBody(std::mt19937& rng, int n) {
  std::uniform_real_distribution<float> u(-0.6f, 0.6f), r(0.02f, 0.12f);
  RandomBody b;
  for (int i = 0; i < n; ++i) {
    Primitive p;
    p.shape.kind = static_cast<ShapeKind>(i % 4);
    p.shape.a = glm::vec3(u(rng), u(rng), u(rng));
    p.shape.b = p.shape.a + 0.3f * glm::vec3(u(rng), u(rng), u(rng));
    p.shape.radius_a = r(rng);
    p.shape.radius_b = r(rng);
    p.shape.polygon_count = 4;
    p.shape.polygon = {glm::vec2(-0.05f, -0.05f), glm::vec2(0.05f, -0.05f), glm::vec2(0.05f, 0.08f),
                       glm::vec2(-0.05f, 0.08f)};
    prepareShape(p.shape);
    p.r_in = p.shape.kind == ShapeKind::kConeSphere ? 1.0f : r(rng);
    p.r_out = p.r_in * 1.4f;
    p.collides = i % 7 != 3;
    b.set.items.push_back(p);
  }
  for (int i = 0; i < n; ++i) {
    for (int j = i + 1; j < n; ++j) {
      if ((i + j) % 3 != 0)
        b.graph.collide_pairs.push_back(
            {static_cast<std::uint16_t>(i), static_cast<std::uint16_t>(j)});
    }
  }
  finalizeGraph(b.graph, n);
  return b;
}

std::set<std::tuple<int, int, int, int>> bruteForce(const std::vector<RandomBody>& bodies) {
  std::set<std::tuple<int, int, int, int>> out;
  for (std::size_t a = 0; a < bodies.size(); ++a) {
    for (std::size_t b = a; b < bodies.size(); ++b) {
      const auto& pa = bodies[a].posed.items;
      const auto& pb = bodies[b].posed.items;
      for (std::size_t i = 0; i < pa.size(); ++i) {
        for (std::size_t j = (a == b ? i + 1 : 0); j < pb.size(); ++j) {
          if (!pa[i].collides || !pb[j].collides) continue;
          if (a == b && !bodies[a].graph.collides(static_cast<int>(i), static_cast<int>(j)))
            continue;
          if (boundsOverlap(pa[i], pb[j]))
            out.insert({static_cast<int>(a), static_cast<int>(i), static_cast<int>(b),
                        static_cast<int>(j)});
        }
      }
    }
  }
  return out;
}

TEST(Interactions, SweepAndPruneMatchesAllPairs) {
  std::mt19937 rng(11);
  std::vector<RandomBody> bodies;
  for (int b = 0; b < 5; ++b) bodies.push_back(randomBody(rng, 12 + b));
  InteractionScratch scratch;
  InteractionList list;
  std::normal_distribution<float> jitter(0.0f, 0.02f);
  std::vector<glm::vec3> drift(bodies.size(), glm::vec3(0.0f));
  for (int frame = 0; frame < 20; ++frame) {
    std::vector<BodyView> views;
    for (std::size_t b = 0; b < bodies.size(); ++b) {
      drift[b] += glm::vec3(jitter(rng), jitter(rng), jitter(rng));
      std::vector<glm::mat4> xf(1, glm::translate(glm::mat4(1.0f), drift[b]));
      for (Primitive& p : bodies[b].set.items) p.bone = 0;
      posePrimitives(bodies[b].set, xf, bodies[b].posed);
      views.push_back({&bodies[b].graph, &bodies[b].posed});
    }
    buildInteractions(views, scratch, list);
    std::set<std::tuple<int, int, int, int>> got;
    for (const Interaction& i : list.pairs) got.insert({i.body_a, i.prim_a, i.body_b, i.prim_b});
    EXPECT_EQ(got, bruteForce(bodies)) << "frame " << frame;
    EXPECT_EQ(got.size(), list.pairs.size()) << "no duplicates";
    EXPECT_TRUE(validateInteractions(list, views).ok());
    // Directed entries: each pair twice, grouped by body.
    EXPECT_EQ(list.directed.size(), 2 * list.pairs.size());
    for (std::size_t b = 0; b < bodies.size(); ++b) {
      for (const Interaction& d : list.forBody(static_cast<int>(b))) EXPECT_EQ(d.body_a, b);
    }
    // The single-body overload agrees with the multi-body one on body 0's self pairs.
    InteractionList self;
    buildInteractions(bodies[0].graph, bodies[0].posed, self);
    std::set<std::tuple<int, int, int, int>> self_got, self_expect;
    for (const Interaction& i : self.pairs)
      self_got.insert({i.body_a, i.prim_a, i.body_b, i.prim_b});
    for (const auto& t : got) {
      if (std::get<0>(t) == 0 && std::get<2>(t) == 0) self_expect.insert(t);
    }
    EXPECT_EQ(self_got, self_expect);
  }
}

// A room: bodies in a row, neighbours' boxes overlapping at their edges, farther ones
// apart, some drifting into each other; one body without a graph (a prop).
TEST(Interactions, BodiesApartAndTouchingMatchAllPairs) {
  std::mt19937 rng(29);
  std::vector<RandomBody> bodies;
  for (int b = 0; b < 12; ++b) bodies.push_back(randomBody(rng, 6 + b % 5));
  InteractionScratch scratch;
  InteractionList list;
  std::normal_distribution<float> jitter(0.0f, 0.05f);
  std::vector<glm::vec3> place(bodies.size());
  for (std::size_t b = 0; b < bodies.size(); ++b) {
    place[b] = glm::vec3(1.1f * static_cast<float>(b % 6), 0.0f, b < 6 ? 0.0f : 1.3f);
  }
  std::size_t across = 0;
  for (int frame = 0; frame < 30; ++frame) {
    std::vector<BodyView> views;
    for (std::size_t b = 0; b < bodies.size(); ++b) {
      place[b] += glm::vec3(jitter(rng), 0.0f, jitter(rng));
      std::vector<glm::mat4> xf(1, glm::translate(glm::mat4(1.0f), place[b]));
      for (Primitive& p : bodies[b].set.items) p.bone = 0;
      posePrimitives(bodies[b].set, xf, bodies[b].posed);
      views.push_back({b == 5 ? nullptr : &bodies[b].graph, &bodies[b].posed});
    }
    buildInteractions(views, scratch, list);
    std::set<std::tuple<int, int, int, int>> got;
    for (const Interaction& i : list.pairs) {
      got.insert({i.body_a, i.prim_a, i.body_b, i.prim_b});
      if (i.body_a != i.body_b) ++across;
    }
    std::set<std::tuple<int, int, int, int>> expect = bruteForce(bodies);
    std::erase_if(expect, [](const auto& t) { return std::get<0>(t) == 5 && std::get<2>(t) == 5; });
    EXPECT_EQ(got, expect) << "frame " << frame;
    EXPECT_EQ(got.size(), list.pairs.size()) << "no duplicates";
  }
  EXPECT_GT(across, 0u);  // some bodies did touch
}

TEST(Interactions, ValidationRejectsBadReceivedLists) {
  std::mt19937 rng(5);
  std::vector<RandomBody> bodies;
  bodies.push_back(randomBody(rng, 6));
  bodies.push_back(randomBody(rng, 6));
  std::vector<BodyView> views;
  for (RandomBody& b : bodies) {
    std::vector<glm::mat4> xf(1, glm::mat4(1.0f));
    for (Primitive& p : b.set.items) p.bone = 0;
    posePrimitives(b.set, xf, b.posed);
    views.push_back({&b.graph, &b.posed});
  }
  InteractionList list;
  list.pairs = {{0, 0, 2, 0}};
  EXPECT_FALSE(validateInteractions(list, views).ok());
  list.pairs = {{0, 1, 0, 1}};
  EXPECT_FALSE(validateInteractions(list, views).ok());
  list.pairs = {{0, 1, 1, 9}};
  EXPECT_FALSE(validateInteractions(list, views).ok());
  list.pairs = {{0, 3, 1, 1}};  // primitive 3 does not collide
  EXPECT_FALSE(validateInteractions(list, views).ok());
  list.pairs = {{1, 1, 0, 0}};
  EXPECT_TRUE(validateInteractions(list, views).ok());
  finalizeInteractions(list, 2);
  EXPECT_EQ(list.pairs[0], (Interaction{0, 0, 1, 1}));
}

}  // namespace
}  // namespace vistel
