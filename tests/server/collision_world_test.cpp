// The server's collision world (issue 4, DESIGN.md §6) over a simulated network with a fake
// clock: the interaction lists it computes match a direct computation and reach every
// client; a ball spawned above a head falls, bounces off it by the fields' reaction, and
// every client sees the same states; collision models past the server's limits are
// refused at upload without disturbing anyone else.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <functional>
#include <map>
#include <set>
#include <string>
#include <tuple>
#include <vector>

#include <gtest/gtest.h>
#include <spdlog/spdlog.h>

#include "common/anim/posture.hpp"
#include "common/avatar/avatar_io.hpp"
#include "common/deform/interactions.hpp"
#include "common/scene/seat_layout.hpp"
#include "server/core/collision_model.hpp"
#include "server/core/server_core.hpp"
#include "tests/net/sim_network.hpp"
#include "tests/net/synthetic_avatar.hpp"
#include "tests/server/seated_room.hpp"

namespace vistel::server {
namespace {

using net::SessionState;
using test::SimNetwork;

using End = test::PairEnd;
using test::IdPair;

std::set<IdPair> serverPairs(const RoomWorld& world) {
  std::set<IdPair> out;
  const auto bodies = world.bodies();
  for (const Interaction& p : world.interactions().pairs) {
    const WorldBody& a = bodies[p.body_a];
    const WorldBody& b = bodies[p.body_b];
    out.insert(test::orderedPair({a.is_prop, a.id, p.prim_a}, {b.is_prop, b.id, p.prim_b}));
  }
  return out;
}

std::set<IdPair> clientPairs(const net::ClientSession& s) {
  std::set<IdPair> out;
  for (const net::ServerPair& p : s.latestInteractions().pairs) {
    out.insert(test::orderedPair({p.a.is_prop, p.a.id, p.a.prim}, {p.b.is_prop, p.b.id, p.b.prim}));
  }
  return out;
}

ServerConfig worldConfig() {
  ServerConfig c;
  c.tick_rate_hz = 60.0;
  c.member_timeout_s = 5.0;
  c.max_members_per_room = 8;
  c.spawn_interval_s = 0.5;
  return c;
}

struct QuietLogs {
  QuietLogs() { spdlog::set_level(spdlog::level::warn); }
} quiet_logs;

// Step 1 on the server equals Step 1 computed here from the same (quantized) postures,
// models and seats; every client receives the same list.
TEST(CollisionWorld, InteractionsAcrossMembersMatchADirectComputation) {
  ServerConfig config = worldConfig();
  config.seat_layout = SeatLayout{0.3f, 0.3f, 1.0f};  // close enough for arms to reach
  SimNetwork net(config, 21);
  const auto avatar = test::encodeSynthetic(test::makeCollidingAvatar());
  const std::vector<std::string> names = {"ann", "ben", "cy"};
  for (const std::string& n : names) {
    net.connect(net.addClient(test::sessionFor("lab", n, avatar, 5)));
  }
  net.advance(0.5);
  // Everyone streams, then holds a fixed posture (member i: the wave at t = 0.4 i).
  const auto fixed = [](std::size_t i) {
    return test::syntheticPosture(0.4 * static_cast<double>(i));
  };
  double next = net.now();
  net.advance(1.0, 0.001, [&](double now) {
    if (now + 1e-9 < next) return;
    next += 1.0 / 30.0;
    for (std::size_t i = 0; i < names.size(); ++i) {
      const Posture p = now < 0.8 ? test::syntheticPosture(now) : fixed(i);
      ASSERT_TRUE(net.session(i).sendPosture(p, net.localTime(i)));
    }
  });
  net.advance(0.2);
  const Room* room = net.server().findRoom("lab");
  ASSERT_NE(room, nullptr);

  // The direct computation: decode the avatar, pose each member at its seat.
  auto model = decodeAvatar(avatar.bytes, "test");
  ASSERT_TRUE(model) << model.error().message;
  auto collision = makeCollisionModel(std::move(*model), {}, "test");
  ASSERT_TRUE(collision);
  const CollisionModel& cm = **collision;
  std::vector<PosedPrimitives> posed(names.size());
  std::vector<BodyView> views;
  std::vector<std::uint32_t> ids;
  const auto& roster = net.session(0).members();
  ASSERT_EQ(roster.size(), names.size());
  for (std::size_t i = 0; i < names.size(); ++i) {
    wire::PostureRecord record;
    ASSERT_TRUE(wire::encodePostureRecord(fixed(i), 1, 0.0, record));
    Posture p;
    wire::decodePostureRecord(record, 0.0, p);  // what the server holds
    std::vector<glm::mat4> model_xf(5), skin(5);
    poseSkeleton(cm.skeleton, p, model_xf);
    skinningMatrices(cm.skeleton, model_xf, skin);
    const net::Seat& seat = roster[i]->seat;
    const glm::mat4 placement = seatTransform(SeatPlacement{seat.x, seat.z, seat.yaw});
    for (glm::mat4& xf : skin) xf = placement * xf;
    posePrimitives(cm.primitives, skin, posed[i]);
    views.push_back({&cm.graph, &posed[i]});
    ids.push_back(roster[i]->id);
  }
  InteractionScratch scratch;
  InteractionList direct;
  buildInteractions(views, scratch, direct);
  std::set<IdPair> expected;
  std::set<IdPair> expected_across;  // what the server sends: self-contact is left out
  std::map<std::uint32_t, std::size_t> self_pairs;
  int across = 0;
  for (const Interaction& p : direct.pairs) {
    const IdPair pair =
        test::orderedPair({false, ids[p.body_a], p.prim_a}, {false, ids[p.body_b], p.prim_b});
    expected.insert(pair);
    across += p.body_a != p.body_b ? 1 : 0;
    if (p.body_a != p.body_b) expected_across.insert(pair);
    if (p.body_a == p.body_b) ++self_pairs[ids[p.body_a]];
  }
  std::printf("[ measure  ] 3 members: %zu interaction pairs (%d between members)\n",
              expected.size(), across);
  EXPECT_GT(across, 0);
  EXPECT_LT(static_cast<std::size_t>(across), expected.size());  // self-contact too
  EXPECT_EQ(serverPairs(room->world()), expected_across);  // self-contact is the clients' part
  EXPECT_FALSE(room->world().truncated());

  // Every client holds the same list (the pairs between members), and maps it onto its
  // scene (members in roster order) with each body's self-contact computed locally: the
  // whole of Step 1 again.
  for (std::size_t i = 0; i < names.size(); ++i) {
    const net::ClientSession& s = net.session(i);
    EXPECT_GT(s.interactionsVersion(), 10u);
    EXPECT_TRUE(s.latestInteractions().self_omitted);
    EXPECT_EQ(clientPairs(s), expected_across) << names[i];
    std::vector<BodyView> scene;
    for (const auto& m : s.members()) {
      std::size_t k = 0;
      while (ids[k] != m->id) ++k;
      scene.push_back(views[k]);
    }
    InteractionList mapped;
    int dropped = -1;
    const Status st = s.sceneInteractions(scene, mapped, &dropped);
    ASSERT_TRUE(st) << st.error().message;
    EXPECT_EQ(dropped, 0);
    std::set<IdPair> mapped_ids;
    for (const Interaction& p : mapped.pairs) {
      mapped_ids.insert(test::orderedPair({false, s.members()[p.body_a]->id, p.prim_a},
                                          {false, s.members()[p.body_b]->id, p.prim_b}));
    }
    EXPECT_EQ(mapped_ids, expected) << names[i];
    // A body the caller does not have: its pairs with others are left out (counted), its
    // own are not made, the rest stay valid.
    scene[1].posed = nullptr;
    ASSERT_TRUE(s.sceneInteractions(scene, mapped, &dropped));
    EXPECT_GT(dropped, 0);
    EXPECT_EQ(mapped.pairs.size() + static_cast<std::size_t>(dropped),
              expected.size() - self_pairs[s.members()[1]->id]);
  }
}

// "The ball bounces off a head by the fields' reaction": a member asks for a ball; the
// server drops it above the member's head; it falls, bounces up off the head (far above
// the floor), and all clients see the same states.
TEST(CollisionWorld, ABallSpawnedAboveAHeadBouncesOffItAndEveryoneSeesIt) {
  SimNetwork net(worldConfig(), 22);
  const auto avatar = test::encodeSynthetic(test::makeCollidingAvatar());
  const std::vector<std::string> names = {"juggler", "a", "b"};
  for (const std::string& n : names) {
    net.connect(net.addClient(test::sessionFor("lab", n, avatar, 5)));
  }
  net.advance(0.5);
  const Posture rest = restPosture(test::makeSyntheticAvatar().skeleton);
  double next = net.now();
  const auto stream = [&](double duration, const std::function<void(double)>& also) {
    net.advance(duration, 0.001, [&](double now) {
      if (now + 1e-9 >= next) {
        next += 1.0 / 30.0;
        for (std::size_t i = 0; i < names.size(); ++i) {
          net.session(i).sendPosture(rest, net.localTime(i));
        }
      }
      if (also) also(now);
    });
  };
  stream(0.3, nullptr);
  ASSERT_TRUE(net.session(0).requestBall());
  const Room* room = net.server().findRoom("lab");
  while (net.server().lobby().propsOf("lab").empty() && net.now() < 2.0) stream(0.001, nullptr);
  const auto props = net.server().lobby().propsOf("lab");
  ASSERT_EQ(props.size(), 1u);
  const PropId ball = props[0];
  // Where it appeared (before its first tick): spawn_height_m above the head joint.
  const float start_y = room->world().propState(ball)->position.y;
  stream(0.1, nullptr);
  for (std::size_t i = 0; i < names.size(); ++i) {
    ASSERT_EQ(net.session(i).props().size(), 1u);
    EXPECT_EQ(net.session(i).props()[0]->spawned_by, net.session(0).memberId());
  }

  // Follow the ball tick by tick on the server, and the pairs the clients receive.
  const float head_y = 1.6f;            // the synthetic avatar's head joint at rest
  std::map<double, BallState> by_time;  // server state at each tick's time
  std::uint32_t last_tick = room->tickCount();
  float fastest_fall = 0.0f, bounce_y = 0.0f, top_after = 0.0f;
  bool bounced = false;
  std::vector<bool> saw_head_pair(names.size(), false);
  const std::uint32_t juggler = net.session(0).memberId();
  stream(1.5, [&](double /*now*/) {
    if (room->tickCount() != last_tick) {
      last_tick = room->tickCount();
      const BallState& b = *room->world().propState(ball);
      by_time[room->lastTickTime()] = b;
      if (!bounced) {
        fastest_fall = std::min(fastest_fall, b.velocity.y);
        if (b.velocity.y > 0.5f && fastest_fall < -1.0f) {
          bounced = true;
          bounce_y = b.position.y;
        }
      } else {
        top_after = std::max(top_after, b.position.y);
      }
    }
    for (std::size_t i = 0; i < names.size(); ++i) {
      for (const net::ServerPair& p : net.session(i).latestInteractions().pairs) {
        const bool head = !p.a.is_prop && p.a.id == juggler && p.a.prim == 2 && p.b.is_prop;
        const bool head_rev = !p.b.is_prop && p.b.id == juggler && p.b.prim == 2 && p.a.is_prop;
        if (head || head_rev) saw_head_pair[i] = true;
      }
    }
  });
  std::printf(
      "[ measure  ] ball from y %.3f m: fell at up to %.2f m/s, bounced at y %.3f m "
      "(head joint %.2f m), rose to %.3f m\n",
      start_y, -fastest_fall, bounce_y, head_y, top_after);
  EXPECT_NEAR(start_y, head_y + 0.6f, 0.005f);  // at most one tick of fall since
  ASSERT_TRUE(bounced);
  EXPECT_GT(bounce_y, head_y);  // off the head, nowhere near the floor
  EXPECT_GT(top_after, bounce_y + 0.02f);
  EXPECT_EQ(room->world().propResets(), 0u);
  for (std::size_t i = 0; i < names.size(); ++i) EXPECT_TRUE(saw_head_pair[i]) << names[i];

  // Every client holds the same states, those the server had at each tick (to 1 mm).
  const net::RemoteProp& p0 = *net.session(0).props()[0];
  ASSERT_GE(p0.track.size(), 10);
  const double newest = p0.track.newest().time;
  for (double t = newest - 0.15; t <= newest; t += 0.005) {
    net::PropSample s0;
    ASSERT_TRUE(net.session(0).sampleProp(ball.value, t, s0));
    for (std::size_t i = 1; i < names.size(); ++i) {
      net::PropSample si;
      ASSERT_TRUE(net.session(i).sampleProp(ball.value, t, si));
      EXPECT_EQ(si.position, s0.position) << names[i] << " at " << t;
      EXPECT_EQ(si.velocity, s0.velocity) << names[i] << " at " << t;
    }
  }
  auto it = by_time.find(newest);
  ASSERT_NE(it, by_time.end());
  EXPECT_LE(glm::length(p0.track.newest().position - it->second.position), 1e-3f);
}

// Spawn requests: faster than the interval are ignored (the member stays), and a full room
// drops its oldest client-spawned prop for a new one.
TEST(CollisionWorld, SpawnRequestsAreRateLimitedAndTheOldestPropMakesRoom) {
  ServerConfig config = worldConfig();
  config.max_props_per_room = 2;
  config.spawn_interval_s = 0.2;
  SimNetwork net(config, 23);
  const auto avatar = test::encodeSynthetic(test::makeCollidingAvatar());
  const auto c = net.addClient(test::sessionFor("lab", "c", avatar, 5));
  net.connect(c);
  net.advance(0.5);
  for (int k = 0; k < 5; ++k) ASSERT_TRUE(net.session(c).requestBall());
  net.advance(0.1);
  auto props = net.server().lobby().propsOf("lab");
  EXPECT_EQ(props.size(), 1u);
  EXPECT_EQ(net.server().lobby().drops().count("spawn rate"), 4u);
  EXPECT_EQ(net.session(c).state(), SessionState::kLive);
  const PropId first = props[0];
  for (int k = 0; k < 2; ++k) {
    net.advance(0.25);
    ASSERT_TRUE(net.session(c).requestBall());
  }
  net.advance(0.1);
  props = net.server().lobby().propsOf("lab");
  ASSERT_EQ(props.size(), 2u);
  EXPECT_NE(props[0], first);
  EXPECT_EQ(net.server().findRoom("lab")->world().propCount(), 2);
  EXPECT_EQ(net.server().findRoom("lab")->world().propState(first), nullptr);
  EXPECT_EQ(net.session(c).props().size(), 2u);
}

// Config props: every room starts with them.
TEST(CollisionWorld, RoomsStartWithTheConfiguredProps) {
  auto config = parseServerConfig(
      "[props]\nball_radius = 0.2\nball_stiffness = \"rigid\"\nball_restitution = 0.3\n"
      "[[prop]]\nkind = \"ball\"\nposition = [0.5, 1.0, 0.0]\n"
      "[[prop]]\nposition = [-0.5, 1.0, 0.0]\nradius = 0.05\nelasticity = \"plastic\"\n",
      "props.toml");
  ASSERT_TRUE(config) << config.error().message;
  ASSERT_EQ(config->room_props.size(), 2u);
  EXPECT_EQ(config->room_props[0].spec.ball.radius, 0.2f);
  EXPECT_EQ(config->room_props[1].spec.ball.radius, 0.05f);
  EXPECT_EQ(config->room_props[1].spec.ball.elasticity, Elasticity::kPlastic);
  SimNetwork net(*config, 24);
  const auto avatar = test::encodeSynthetic(test::makeSyntheticAvatar());  // no primitives
  const auto c = net.addClient(test::sessionFor("lab", "c", avatar, 5));
  net.connect(c);
  net.advance(3.0);
  ASSERT_EQ(net.session(c).props().size(), 2u);
  EXPECT_EQ(net.session(c).props()[1]->ball.radius, 0.05f);
  EXPECT_TRUE(std::isinf(net.session(c).props()[0]->ball.stiffness));
  // The balls fell to the floor and rest there; they touch nothing else.
  net::PropSample s;
  ASSERT_TRUE(net.session(c).sampleProp(net.session(c).props()[0]->id, 1e9, s));
  EXPECT_NEAR(s.position.y, 0.2f, 0.01f);
  EXPECT_TRUE(net.session(c).latestInteractions().pairs.empty());
  // Bad prop entries name themselves.
  auto bad = parseServerConfig("[[prop]]\nkind = \"cube\"\n", "bad.toml");
  ASSERT_FALSE(bad);
  EXPECT_NE(bad.error().message.find("prop[0]"), std::string::npos) << bad.error().message;
  bad = parseServerConfig("[[prop]]\nrestitution = 2\n", "bad.toml");
  ASSERT_FALSE(bad);
  EXPECT_NE(bad.error().message.find("restitution"), std::string::npos) << bad.error().message;
}

// Collision models past the server's limits, or invalid, are refused at upload with a
// clear error; a member already streaming carries on, its body in the world.
TEST(CollisionWorld, BadOrOversizedPrimitiveSetsAreRejectedAtUpload) {
  ServerConfig config = worldConfig();
  config.max_primitives_per_avatar = 5;
  config.max_primitive_extent_m = 1.0f;
  SimNetwork net(config, 25);
  const auto good = test::encodeSynthetic(test::makeCollidingAvatar("good"));
  const auto alice = net.addClient(test::sessionFor("lab", "alice", good, 5));
  net.connect(alice);
  net.advance(0.5);

  // Too many primitives: a sixth one.
  AvatarModel many = test::makeCollidingAvatar("many");
  many.implicit->primitives.items.push_back(many.implicit->primitives.items.back());
  many.implicit->primitives.items.back().name = "extra";
  finalizeGraph(many.implicit->graph, 6);
  // A primitive whose field spans 2.4 m.
  AvatarModel huge = test::makeCollidingAvatar("huge");
  Primitive& head = huge.implicit->primitives.items[2];
  head.r_out = 1.2f;
  head.weight = shapeWeight(head.density, huge.implicit->primitives.iso, head.r_in, head.r_out);
  // An invalid primitive (its surface outside its bound).
  AvatarModel broken = test::makeCollidingAvatar("broken");
  broken.implicit->primitives.items[1].r_in = 0.5f;
  struct Case {
    std::string name;
    AvatarModel model;
    std::string reason;
  };
  std::vector<Case> cases = {{"many", many, "6 primitives"},
                             {"huge", huge, "spans 2.40 m"},
                             {"broken", broken, "r_in < r_out"}};
  double next = net.now();
  for (const Case& k : cases) {
    const auto encoded = test::encodeSynthetic(k.model);
    const auto i = net.addClient(test::sessionFor("lab", k.name, encoded, 5));
    net.connect(i);
    net.advance(0.3, 0.001, [&](double now) {
      if (now + 1e-9 < next) return;
      next += 1.0 / 30.0;
      net.session(alice).sendPosture(test::syntheticPosture(now), net.localTime(alice));
    });
    EXPECT_EQ(net.session(i).state(), SessionState::kClosed) << k.name;
    EXPECT_NE(net.session(i).error().find("AVATAR_REJECTED"), std::string::npos)
        << net.session(i).error();
    EXPECT_NE(net.session(i).error().find(k.reason), std::string::npos) << net.session(i).error();
  }
  EXPECT_EQ(net.session(alice).state(), SessionState::kLive);
  EXPECT_EQ(net.server().lobby().memberCount(), 1);
  const Room* room = net.server().findRoom("lab");
  ASSERT_EQ(room->world().bodies().size(), 1u);
  EXPECT_EQ(room->world().bodies()[0].id, net.session(alice).memberId());
  EXPECT_GE(room->posturesAccepted(), 25u);
}

}  // namespace
}  // namespace vistel::server
