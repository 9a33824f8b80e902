// The own avatar's contact force per body part (issue 25 item 10) on the live client's path:
// the default avatar (built here with its implicit model) and a rigid ball as two members of
// a headless RoomView with RoomDeformer; the ball pressed on the left hand gives a force on
// l_hand pointing away from the ball (into the hand) and none on any other part, in the
// avatar's model space whatever its seat; OwnForces streams it as CSV, summarises it for
// --stats-json and drives a fake force-feedback device.
#include <algorithm>
#include <array>
#include <cmath>
#include <cstring>
#include <deque>
#include <fstream>
#include <memory>
#include <sstream>
#include <vector>

#include <gtest/gtest.h>
#include <glm/gtc/matrix_transform.hpp>

#include "client/deform/force_log.hpp"
#include "client/deform/own_forces.hpp"
#include "client/deform/part_forces.hpp"
#include "client/deform/room_deformer.hpp"
#include "client/view/room_view.hpp"
#include "common/base/file.hpp"
#include "common/scene/deform_scene.hpp"
#include "tests/support/alloc_counter.hpp"
#include "tests/support/default_avatar.hpp"
#include "tests/support/test_support.hpp"

namespace vistel {
namespace {

constexpr float kBallRadius = 0.03f;
constexpr float kDepth = 0.006f;
constexpr std::uint32_t kSelf = 7;
constexpr std::uint32_t kBall = 9;

std::shared_ptr<const AvatarModel> defaultAvatar() { return test::defaultAvatarWithModel(); }

std::shared_ptr<const AvatarModel> rigidBall() {
  BallSpec spec;
  spec.radius = kBallRadius;
  spec.subdivisions = 3;
  Result<std::shared_ptr<const AvatarModel>> ball = makeBallAvatar(spec);
  EXPECT_TRUE(ball.ok()) << (ball.ok() ? "" : ball.error().message);
  return ball.ok() ? *ball : nullptr;
}

// Where to press the hand (bind pose = rest posture, model space): the l_hand vertex farthest
// along +z near the part's middle, and its outward normal.
struct PressPoint {
  glm::vec3 point{0.0f};
  glm::vec3 normal{0.0f};
};
PressPoint handPressPoint(const AvatarModel& a, const PartForceLayout& layout) {
  const int hand = findPart(layout, "l_hand");
  glm::vec3 centre(0.0f);
  int n = 0;
  for (int v = 0; v < layout.vertexCount(); ++v) {
    if (layout.vertex_part[static_cast<std::size_t>(v)] != hand) continue;
    centre += a.skin.positions[static_cast<std::size_t>(v)];
    ++n;
  }
  centre /= static_cast<float>(std::max(n, 1));
  PressPoint best;
  float best_z = -1e9f;
  for (int v = 0; v < layout.vertexCount(); ++v) {
    const auto vi = static_cast<std::size_t>(v);
    if (layout.vertex_part[vi] != hand) continue;
    const glm::vec3 p = a.skin.positions[vi];
    if (glm::length(glm::vec2(p.x - centre.x, p.y - centre.y)) > 0.02f) continue;
    if (p.z > best_z) {
      best_z = p.z;
      best = {p, glm::normalize(a.skin.normals[vi])};
    }
  }
  return best;
}

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

// The avatar at a seat (turned by 0.7 rad about +y, so model and room axes differ) and the
// ball at `ball_model` (the avatar's model space).
std::vector<MemberView> room(const glm::vec3& ball_model) {
  const std::shared_ptr<const AvatarModel> avatar = defaultAvatar();
  const glm::mat4 seat = glm::rotate(glm::translate(glm::mat4(1.0f), glm::vec3(1.5f, 0.0f, -2.0f)),
                                     0.7f, glm::vec3(0.0f, 1.0f, 0.0f));
  std::vector<MemberView> views(2);
  views[0].id = kSelf;
  views[0].name = "me";
  views[0].avatar = avatar;
  views[0].is_self = true;
  views[0].placement = seat;
  views[0].posture = restPosture(avatar->skeleton);
  views[1].id = kBall;
  views[1].name = "ball";
  views[1].avatar = rigidBall();
  views[1].placement = glm::translate(glm::mat4(1.0f), glm::vec3(seat * glm::vec4(ball_model, 1)));
  views[1].posture = restPosture(views[1].avatar->skeleton);
  return views;
}

// One client frame: sync, prepare, render, finish.
void frame(RoomDeformer& deformer, RoomView& view, std::span<const MemberView> views, double t) {
  ASSERT_TRUE(deformer.sync(views, view).ok());
  ASSERT_TRUE(deformer.prepare(t).ok());
  view.render(views);
  deformer.finish();
}

std::vector<std::string> lines(const std::string& path) {
  std::ifstream in(path);
  std::vector<std::string> out;
  for (std::string line; std::getline(in, line);) out.push_back(line);
  return out;
}

std::vector<std::string> fields(const std::string& line) {
  std::vector<std::string> out;
  std::stringstream ss(line);
  for (std::string f; std::getline(ss, f, ',');) out.push_back(f);
  return out;
}

class FakeForceDevice final : public HidOutputDevice {
 public:
  int write(std::span<const std::uint8_t> report) override {
    if (unplugged) return -1;
    reports.emplace_back(report.begin(), report.end());
    return static_cast<int>(report.size());
  }
  std::string lastError() const override { return "device disconnected"; }
  std::string describe() const override { return "fake force feedback"; }
  std::deque<std::vector<std::uint8_t>> reports;
  bool unplugged = false;
};

TEST(PartForceLayout, PartsAreTheBodyParts) {
  ASSERT_NE(defaultAvatar(), nullptr);
  Result<PartForceLayout> layout = makePartForceLayout(*defaultAvatar());
  ASSERT_TRUE(layout.ok()) << layout.error().message;
  // One part per primitive of the map; the adopted ones ("l_hand/l_index1") join their part.
  const ImplicitModel& model = *defaultAvatar()->implicit;
  int own = 0, adopted_vertices = 0;
  for (std::size_t i = 0; i < model.primitives.items.size(); ++i) {
    const std::string& name = model.primitives.items[i].name;
    if (primitivePart(name) == name) {
      ++own;
      continue;
    }
    const int part = findPart(*layout, primitivePart(name));
    ASSERT_GE(part, 0) << name;
    EXPECT_EQ(findPart(*layout, name), -1) << name;
    for (std::size_t v = 0; v < model.calibration.prims.size(); ++v) {
      if (model.calibration.prims[v][0] != static_cast<std::int16_t>(i)) continue;
      EXPECT_EQ(layout->vertex_part[v], part) << name << " vertex " << v;
      ++adopted_vertices;
    }
  }
  EXPECT_EQ(layout->partCount(), own);
  EXPECT_GT(adopted_vertices, 100) << "fingers, toes and chest adopted by the builder";
  for (const char* part : {"head", "torso", "pelvis", "l_hand", "r_hand", "l_foot"}) {
    EXPECT_GE(findPart(*layout, part), 0) << part;
  }
  EXPECT_EQ(findPart(*layout, "tail"), -1);
  EXPECT_EQ(layout->vertexCount(), defaultAvatar()->skin.vertexCount());
  const int hand = findPart(*layout, "l_hand");
  EXPECT_GT(std::count(layout->vertex_part.begin(), layout->vertex_part.end(), hand), 20);
  // Every face is listed once under each of its vertices.
  EXPECT_EQ(layout->vf_faces.size(), defaultAvatar()->skin.indices.size());
  // An avatar without an implicit model has no parts.
  AvatarModel plain = *defaultAvatar();
  plain.implicit.reset();
  EXPECT_FALSE(makePartForceLayout(plain).ok());
}

TEST(PartForces, BallOnTheHandPushesTheHandAlone) {
  ASSERT_NE(defaultAvatar(), nullptr);
  Result<PartForceLayout> layout = makePartForceLayout(*defaultAvatar());
  ASSERT_TRUE(layout.ok());
  const int hand = findPart(*layout, "l_hand");
  ASSERT_GE(hand, 0);
  const PressPoint press = handPressPoint(*defaultAvatar(), *layout);
  ASSERT_GT(glm::length(press.normal), 0.5f);
  const glm::vec3 ball_centre = press.point + (kBallRadius - kDepth) * press.normal;

  std::unique_ptr<RoomView> view = headlessView();
  ASSERT_NE(view, nullptr);
  RoomDeformer deformer;
  const std::vector<MemberView> views = room(ball_centre);
  frame(deformer, *view, views, 0.0);
  const std::optional<PartForceInput> input = deformer.partForceInput(kSelf);
  ASSERT_TRUE(input.has_value());
  EXPECT_FALSE(deformer.partForceInput(12345).has_value());
  std::vector<PartForce> forces(static_cast<std::size_t>(layout->partCount()));
  computePartForces(*layout, *input, forces);

  // The hand is pushed away from the ball (into the hand, along -normal, in model space).
  const PartForce& f = forces[static_cast<std::size_t>(hand)];
  const float magnitude = glm::length(f.force);
  EXPECT_GT(magnitude, 0.5f);
  EXPECT_GT(f.vertices, 2);
  EXPECT_GT(f.area, 1e-5f);
  EXPECT_LT(f.area, 0.01f);
  const glm::vec3 away = glm::normalize(press.point - ball_centre);
  EXPECT_GT(glm::dot(f.force / magnitude, away), 0.8f)
      << "force " << f.force.x << " " << f.force.y << " " << f.force.z;
  // No other part feels anything.
  for (int p = 0; p < layout->partCount(); ++p) {
    if (p == hand) continue;
    EXPECT_EQ(forces[static_cast<std::size_t>(p)].force, glm::vec3(0.0f))
        << layout->names[static_cast<std::size_t>(p)];
    EXPECT_EQ(forces[static_cast<std::size_t>(p)].vertices, 0);
  }
  // The same as a brute-force sum over faces (each face's area shared by its three
  // vertices), turned into model space by the inverse of the seat.
  const PartForceLayout& l = *layout;
  const AvatarModel& a = *defaultAvatar();
  std::vector<double> vertex_area(input->positions.size(), 0.0);
  for (std::size_t t = 0; t + 2 < a.skin.indices.size(); t += 3) {
    const glm::dvec3 p0(input->positions[a.skin.indices[t]]);
    const glm::dvec3 p1(input->positions[a.skin.indices[t + 1]]);
    const glm::dvec3 p2(input->positions[a.skin.indices[t + 2]]);
    const double third = glm::length(glm::cross(p1 - p0, p2 - p0)) / 6.0;
    for (int k = 0; k < 3; ++k)
      vertex_area[a.skin.indices[t + static_cast<std::size_t>(k)]] += third;
  }
  glm::dvec3 brute(0.0);
  for (std::size_t v = 0; v < vertex_area.size(); ++v) {
    if (l.vertex_part[v] != hand || input->contact_body[v] < 0) continue;
    brute -=
        static_cast<double>(input->pressure[v]) * vertex_area[v] * glm::dvec3(input->normals[v]);
  }
  const glm::vec3 brute_model = glm::vec3(glm::inverse(glm::dmat3(views[0].placement)) * brute);
  EXPECT_LT(glm::distance(brute_model, f.force), 1e-4f * magnitude);
  // It agrees in direction with the body's net contact force of Step 3 (world space; its
  // size differs: that one is the pair's combined measure, see part_forces.hpp).
  const std::optional<BodyContactSummary> summary = deformer.contact(kSelf);
  ASSERT_TRUE(summary.has_value());
  const glm::vec3 net_model = input->world_to_model * glm::vec3(summary->force);
  ASSERT_GT(glm::length(net_model), 0.0f);
  EXPECT_GT(glm::dot(glm::normalize(net_model), f.force / magnitude), 0.8f);

  // Ball gone: no force anywhere.
  const std::vector<MemberView> apart = room(ball_centre + 0.5f * press.normal);
  frame(deformer, *view, apart, 1.0 / 60.0);
  const std::optional<PartForceInput> after = deformer.partForceInput(kSelf);
  ASSERT_TRUE(after.has_value());
  computePartForces(*layout, *after, forces);
  for (const PartForce& pf : forces) EXPECT_EQ(pf.force, glm::vec3(0.0f));
}

TEST(PartForces, HandWorkedSquare) {
  // A unit square in the xz plane (two triangles, normals +y), vertices 0, 1 in part 0 and
  // 2, 3 in part 1. Vertex 0 touches body 4 at 100 Pa, vertex 1 touches itself (body 2, the
  // self: left out), vertex 2 touches body 4 at 300 Pa, vertex 3 nothing.
  PartForceLayout l;
  l.names = {"a", "b"};
  l.vertex_part = {0, 0, 1, 1};
  l.indices = {0, 2, 1, 0, 3, 2};
  l.vf_offsets = {0, 2, 3, 5, 6};
  l.vf_faces = {0, 1, 0, 0, 1, 1};
  const std::vector<glm::vec3> pos = {{0, 0, 0}, {1, 0, 0}, {1, 0, 1}, {0, 0, 1}};
  const std::vector<glm::vec3> nrm(4, glm::vec3(0, 1, 0));
  const std::vector<float> pressure = {100.0f, 50.0f, 300.0f, 0.0f};
  const std::vector<std::int16_t> contact = {4, 2, 4, -1};
  PartForceInput in{pos, nrm, pressure, contact, 2, glm::mat3(1.0f)};
  // World to model: a quarter turn about +y.
  in.world_to_model =
      glm::mat3(glm::rotate(glm::mat4(1.0f), 0.5f * 3.14159265f, glm::vec3(0, 1, 0)));
  std::vector<PartForce> out(2);
  computePartForces(l, in, out);
  // Vertex 0: faces 0 and 1 (0.5 m^2 each) -> 1/3 m^2; 100 Pa -> 33.3 N along -y.
  EXPECT_NEAR(out[0].force.y, -100.0f / 3.0f, 1e-4f);
  EXPECT_NEAR(out[0].area, 1.0f / 3.0f, 1e-6f);
  EXPECT_EQ(out[0].vertices, 1);
  // Vertex 2: both faces too -> 300 Pa * 1/3 m^2.
  EXPECT_NEAR(out[1].force.y, -100.0f, 1e-4f);
  EXPECT_EQ(out[1].vertices, 1);
  EXPECT_NEAR(out[0].force.x, 0.0f, 1e-5f);
  EXPECT_NEAR(out[0].force.z, 0.0f, 1e-5f);
  // Forces come out in model space: a world -x push is turned by world_to_model (onto z).
  const std::vector<glm::vec3> side(4, glm::vec3(1, 0, 0));
  in.normals = side;
  computePartForces(l, in, out);
  const glm::vec3 expected = in.world_to_model * glm::vec3(-100.0f / 3.0f, 0.0f, 0.0f);
  EXPECT_NEAR(glm::distance(out[0].force, expected), 0.0f, 1e-4f);
  EXPECT_NEAR(std::abs(out[0].force.z), 100.0f / 3.0f, 1e-3f);
}

TEST(PartForces, WrongSizesGiveZero) {
  ASSERT_NE(defaultAvatar(), nullptr);
  Result<PartForceLayout> layout = makePartForceLayout(*defaultAvatar());
  ASSERT_TRUE(layout.ok());
  std::vector<PartForce> forces(static_cast<std::size_t>(layout->partCount()));
  forces[0].force = glm::vec3(1.0f);
  computePartForces(*layout, PartForceInput{}, forces);
  EXPECT_EQ(forces[0].force, glm::vec3(0.0f));
}

TEST(ForceLog, CsvRowsForForcesAndReleases) {
  const std::string path = test::scratchDir() + "/forces.csv";
  ForceLog log({"head", "l_hand", "r_hand"});
  ASSERT_TRUE(log.openCsv(path).ok());
  std::vector<PartForce> f(3);
  ASSERT_TRUE(log.add(0.0, f).ok());  // nothing: no rows
  f[1].force = glm::vec3(0.0f, -3.0f, 4.0f);
  f[1].area = 0.002f;
  f[1].vertices = 5;
  ASSERT_TRUE(log.add(0.5, f).ok());
  f[2].force = glm::vec3(1.0f, 0.0f, 0.0f);
  ASSERT_TRUE(log.add(1.0, f).ok());
  f[1] = PartForce{};
  ASSERT_TRUE(log.add(1.5, f).ok());  // l_hand lets go: a row of zeros
  f[2] = PartForce{};
  ASSERT_TRUE(log.add(2.0, f).ok());
  ASSERT_TRUE(log.add(2.5, f).ok());  // nothing again
  ASSERT_TRUE(log.close().ok());
  const std::vector<std::string> rows = lines(path);
  ASSERT_EQ(rows.size(), 7u);
  EXPECT_EQ(rows[0], "time_s,part,fx_n,fy_n,fz_n,magnitude_n,area_m2");
  EXPECT_EQ(rows[1], "0.5000,l_hand,0.0000,-3.0000,4.0000,5.0000,0.002000");
  EXPECT_EQ(rows[2], "1.0000,l_hand,0.0000,-3.0000,4.0000,5.0000,0.002000");
  EXPECT_EQ(rows[3], "1.0000,r_hand,1.0000,0.0000,0.0000,1.0000,0.000000");
  EXPECT_EQ(rows[4], "1.5000,l_hand,0.0000,0.0000,0.0000,0.0000,0.000000");
  EXPECT_EQ(rows[5], "1.5000,r_hand,1.0000,0.0000,0.0000,1.0000,0.000000");
  EXPECT_EQ(rows[6], "2.0000,r_hand,0.0000,0.0000,0.0000,0.0000,0.000000");
  EXPECT_EQ(log.rowsWritten(), 6);
  EXPECT_EQ(log.frames(), 6);
  const std::string json = log.json();
  EXPECT_NE(json.find("\"own_forces\""), std::string::npos);
  EXPECT_NE(json.find("\"frames\": 6"), std::string::npos) << json;
  EXPECT_NE(json.find("\"frames_in_contact\": 3"), std::string::npos) << json;
  EXPECT_NE(json.find("\"l_hand\": {\"frames_in_contact\": 2, \"peak_n\": 5.0000"),
            std::string::npos)
      << json;
  EXPECT_EQ(json.find("\"head\""), std::string::npos) << json;
  // Names CSV or JSON would misread are quoted.
  ForceLog odd({"a,b", "q\"x"});
  const std::string odd_path = test::scratchDir() + "/odd.csv";
  ASSERT_TRUE(odd.openCsv(odd_path).ok());
  std::vector<PartForce> g(2);
  g[0].force = g[1].force = glm::vec3(1.0f, 0.0f, 0.0f);
  ASSERT_TRUE(odd.add(0.0, g).ok());
  ASSERT_TRUE(odd.close().ok());
  const std::vector<std::string> odd_rows = lines(odd_path);
  ASSERT_EQ(odd_rows.size(), 3u);
  EXPECT_EQ(odd_rows[1].substr(0, 14), "0.0000,\"a,b\",1");
  EXPECT_EQ(odd_rows[2].substr(0, 15), "0.0000,\"q\"\"x\",1");
  EXPECT_NE(odd.json().find("\"q\\\"x\""), std::string::npos) << odd.json();
  // A file that cannot be written is an error naming it.
  ForceLog bad({"head"});
  const Status st = bad.openCsv("/nonexistent/folder/forces.csv");
  ASSERT_FALSE(st.ok());
  EXPECT_NE(st.error().message.find("/nonexistent/folder/forces.csv"), std::string::npos);
}

constexpr const char* kForceFeedbackToml = R"(
[force_feedback]
vendor_id = 0x1234
product_id = 0x9abc
report_id = 3
report_size = 16
max_rate_hz = 30

[[force_feedback.channel]]
part = "l_hand"
offset = 1
type = "u8"
scale = 0.05      # 0.05 N per count
axis = "magnitude"

[[force_feedback.channel]]
part = "l_hand"
offset = 2
type = "i16"
scale = 0.001
axis = "z"

[[force_feedback.channel]]
part = "l_hand"
offset = 4
type = "f32"
scale = 1.0
axis = "magnitude"

[[force_feedback.channel]]
part = "head"
offset = 8
type = "u8"
scale = 0.05

[[force_feedback.channel]]
part = "tail"
offset = 9
)";

TEST(OwnForces, BallOnTheHandReachesTheCsvTheStatsAndTheDevice) {
  ASSERT_NE(defaultAvatar(), nullptr);
  const std::string dir = test::scratchDir();
  const std::string config = dir + "/ff.toml";
  ASSERT_TRUE(writeFileText(config, kForceFeedbackToml).ok());
  OwnForcesOptions options;
  options.csv_path = dir + "/forces.csv";
  options.force_feedback_config = config;
  options.frame_rate_hz = 60.0;
  auto device = std::make_unique<FakeForceDevice>();
  FakeForceDevice* fake = device.get();
  Result<std::unique_ptr<OwnForces>> created =
      OwnForces::create(*defaultAvatar(), options, std::move(device));
  ASSERT_TRUE(created.ok()) << created.error().message;
  OwnForces& own = **created;
  // The unknown part is a warning naming it, not a failure.
  ASSERT_EQ(own.warnings().size(), 1u);
  EXPECT_NE(own.warnings()[0].find("'tail'"), std::string::npos) << own.warnings()[0];
  EXPECT_NE(own.warnings()[0].find("ff.toml"), std::string::npos);

  const PressPoint press = handPressPoint(*defaultAvatar(), own.layout());
  const glm::vec3 pressed = press.point + (kBallRadius - kDepth) * press.normal;
  const glm::vec3 apart = pressed + 0.5f * press.normal;
  std::unique_ptr<RoomView> view = headlessView();
  ASSERT_NE(view, nullptr);
  RoomDeformer deformer;
  // Apart, pressed, pressed, apart; 0.1 s apart (slower than the device's 30 Hz limit): after
  // every frame the device holds that frame's forces, encoded as the config says.
  Result<SensorSetup> setup = loadSensorSetup(config);
  ASSERT_TRUE(setup.ok()) << setup.error().message;
  const ForceFeedbackConfig& ff = setup->force_feedback;
  const std::vector<int> channel_part = bindForceChannels(ff, own.layout().names);
  const int hand = findPart(own.layout(), "l_hand");
  ASSERT_EQ(channel_part[0], hand);
  EXPECT_EQ(channel_part[4], -1);
  const std::vector<glm::vec3> placements = {apart, pressed, pressed, apart};
  std::vector<glm::vec3> vectors(own.layout().names.size());
  std::vector<std::uint8_t> want(16);
  float pressed_magnitude = 0.0f;
  glm::vec3 pressed_force(0.0f);
  for (std::size_t k = 0; k < placements.size(); ++k) {
    const double t = 0.1 * static_cast<double>(k);
    const std::vector<MemberView> views = room(placements[k]);
    frame(deformer, *view, views, t);
    ASSERT_TRUE(own.frame(t, &deformer, kSelf).ok());
    const std::span<const PartForce> f = own.lastForces();
    for (std::size_t p = 0; p < f.size(); ++p) {
      vectors[p] = f[p].force;
      if (static_cast<int>(p) != hand) {
        EXPECT_EQ(f[p].force, glm::vec3(0.0f));
      }
    }
    const float m = glm::length(f[static_cast<std::size_t>(hand)].force);
    if (placements[k] == pressed) {
      EXPECT_GT(m, 0.5f) << "frame " << k;
      pressed_magnitude = m;
      pressed_force = f[static_cast<std::size_t>(hand)].force;
    } else {
      EXPECT_EQ(m, 0.0f) << "frame " << k;
    }
    encodeForceReport(ff, channel_part, vectors, want);
    ASSERT_FALSE(fake->reports.empty());
    EXPECT_EQ(fake->reports.back(), want) << "frame " << k;
  }
  // The pressed frames' report, decoded by hand.
  const auto pressed_report =
      std::find_if(fake->reports.begin(), fake->reports.end(),
                   [](const std::vector<std::uint8_t>& r) { return r[1] != 0; });
  ASSERT_NE(pressed_report, fake->reports.end());
  const std::vector<std::uint8_t>& r = *pressed_report;
  ASSERT_EQ(r.size(), 16u);
  EXPECT_EQ(r[0], 3);  // report id
  EXPECT_EQ(r[1],
            static_cast<std::uint8_t>(std::lround(std::min(pressed_magnitude / 0.05f, 255.0f))));
  float f32 = 0.0f;
  std::memcpy(&f32, &r[4], 4);
  EXPECT_NEAR(f32, pressed_magnitude, 1e-3f * pressed_magnitude);
  const auto z_counts = static_cast<std::int16_t>(r[2] | (r[3] << 8));
  EXPECT_NEAR(z_counts * 0.001f, std::clamp(pressed_force.z, -32.768f, 32.767f), 0.001f);
  EXPECT_EQ(r[8], 0);  // head: nothing
  EXPECT_EQ(r[9], 0);  // unknown part
  // Apart, pressed (maybe once more, when the second frame's bits differ), apart.
  EXPECT_GE(fake->reports.size(), 3u);
  EXPECT_LE(fake->reports.size(), 4u);
  EXPECT_EQ(fake->reports.front(), fake->reports.back());
  ASSERT_TRUE(own.close().ok());

  // The CSV: the header, l_hand in the two pressed frames, its release; nothing else.
  const std::vector<std::string> rows = lines(options.csv_path);
  ASSERT_EQ(rows.size(), 4u);
  EXPECT_EQ(rows[0], "time_s,part,fx_n,fy_n,fz_n,magnitude_n,area_m2");
  for (std::size_t k = 1; k < 4; ++k) {
    const std::vector<std::string> row = fields(rows[k]);
    ASSERT_EQ(row.size(), 7u) << rows[k];
    EXPECT_EQ(row[1], "l_hand");
    EXPECT_NEAR(std::stod(row[0]), 0.1 * static_cast<double>(k), 1e-9);
    if (k < 3) {
      EXPECT_NEAR(std::stod(row[5]), pressed_magnitude, 1e-3);
      EXPECT_GT(std::stod(row[6]), 0.0);
    } else {
      EXPECT_EQ(std::stod(row[5]), 0.0);
    }
  }
  // The stats: l_hand in contact in two frames.
  const std::string json = own.json();
  EXPECT_NE(json.find("\"l_hand\": {\"frames_in_contact\": 2"), std::string::npos) << json;
  EXPECT_NE(own.summary().find("fake force feedback"), std::string::npos);
}

TEST(OwnForces, NoDeformerNoDeviceAndBadConfigs) {
  ASSERT_NE(defaultAvatar(), nullptr);
  const std::string dir = test::scratchDir();
  const std::string config = dir + "/ff.toml";
  ASSERT_TRUE(writeFileText(config, kForceFeedbackToml).ok());
  OwnForcesOptions options;
  options.force_feedback_config = config;
  auto device = std::make_unique<FakeForceDevice>();
  FakeForceDevice* fake = device.get();
  Result<std::unique_ptr<OwnForces>> created =
      OwnForces::create(*defaultAvatar(), options, std::move(device));
  ASSERT_TRUE(created.ok()) << created.error().message;
  OwnForces& own = **created;
  ASSERT_TRUE(own.frame(0.0, nullptr, kSelf).ok());
  for (const PartForce& f : own.lastForces()) EXPECT_EQ(f.force, glm::vec3(0.0f));
  EXPECT_EQ(fake->reports.size(), 1u);  // the first report: all zero
  // Without a device on this machine: warnings (the unknown part, the device not found),
  // not a failure; forces still computed and logged.
  Result<std::unique_ptr<OwnForces>> alone = OwnForces::create(*defaultAvatar(), options, nullptr);
  ASSERT_TRUE(alone.ok()) << alone.error().message;
  ASSERT_EQ((*alone)->warnings().size(), 2u);
  EXPECT_NE((*alone)->warnings()[0].find("'tail'"), std::string::npos);
  EXPECT_NE((*alone)->warnings()[1].find("force feedback hid 1234:9abc"), std::string::npos)
      << (*alone)->warnings()[1];
  EXPECT_TRUE((*alone)->frame(0.0, nullptr, std::nullopt).ok());
  // A config without the section: a warning only when the device was asked for.
  OwnForcesOptions plain;
  plain.force_feedback_config = "config/sensors/hid.toml";
  Result<std::unique_ptr<OwnForces>> quiet = OwnForces::create(*defaultAvatar(), plain, nullptr);
  ASSERT_TRUE(quiet.ok()) << quiet.error().message;
  EXPECT_TRUE((*quiet)->warnings().empty());
  plain.require_force_feedback = true;
  Result<std::unique_ptr<OwnForces>> asked = OwnForces::create(*defaultAvatar(), plain, nullptr);
  ASSERT_TRUE(asked.ok()) << asked.error().message;
  ASSERT_EQ((*asked)->warnings().size(), 1u);
  EXPECT_NE((*asked)->warnings()[0].find("no [force_feedback] section"), std::string::npos);
  // A broken config is an error naming the file and key.
  ASSERT_TRUE(writeFileText(dir + "/bad.toml",
                            "[force_feedback]\nreport_size = 4\n[[force_feedback.channel]]\n"
                            "part = \"head\"\noffset = 2\ntype = \"f32\"\n")
                  .ok());
  OwnForcesOptions bad = options;
  bad.force_feedback_config = dir + "/bad.toml";
  Result<std::unique_ptr<OwnForces>> refused = OwnForces::create(*defaultAvatar(), bad, nullptr);
  ASSERT_FALSE(refused.ok());
  EXPECT_NE(refused.error().message.find("bad.toml"), std::string::npos) << refused.error().message;
  EXPECT_NE(refused.error().message.find("force_feedback.channel[0].offset"), std::string::npos)
      << refused.error().message;
}

// Keeps the last report in place (no allocation).
class CountingForceDevice final : public HidOutputDevice {
 public:
  int write(std::span<const std::uint8_t> report) override {
    const std::size_t n = std::min(report.size(), last.size());
    std::copy_n(report.begin(), n, last.begin());
    ++writes;
    return static_cast<int>(report.size());
  }
  std::string lastError() const override { return {}; }
  std::string describe() const override { return "counting force feedback"; }
  std::array<std::uint8_t, 16> last{};
  int writes = 0;
};

TEST(OwnForces, NoAllocationPerFrame) {
  ASSERT_NE(defaultAvatar(), nullptr);
  const std::string dir = test::scratchDir();
  const std::string config = dir + "/ff.toml";
  ASSERT_TRUE(writeFileText(config, kForceFeedbackToml).ok());
  OwnForcesOptions options;
  options.csv_path = dir + "/forces.csv";
  options.force_feedback_config = config;
  auto device = std::make_unique<CountingForceDevice>();
  CountingForceDevice* counting = device.get();
  Result<std::unique_ptr<OwnForces>> created =
      OwnForces::create(*defaultAvatar(), options, std::move(device));
  ASSERT_TRUE(created.ok()) << created.error().message;
  OwnForces& own = **created;
  Result<PartForceLayout> layout = makePartForceLayout(*defaultAvatar());
  ASSERT_TRUE(layout.ok());
  const PressPoint press = handPressPoint(*defaultAvatar(), *layout);
  const glm::vec3 pressed = press.point + (kBallRadius - kDepth) * press.normal;
  const std::vector<MemberView> in_contact = room(pressed);
  const std::vector<MemberView> apart = room(pressed + 0.5f * press.normal);
  std::unique_ptr<RoomView> view = headlessView();
  ASSERT_NE(view, nullptr);
  RoomDeformer deformer;
  // Contact and release, every frame sending a report and writing rows; only own.frame()
  // is counted (the room's own frame is not this test's).
  long allocations = 0;
  for (int k = 0; k < 8; ++k) {
    frame(deformer, *view, k % 2 == 0 ? in_contact : apart, 0.1 * k);
    test::AllocationCounter counter;
    ASSERT_TRUE(own.frame(0.1 * k, &deformer, kSelf).ok());
    if (k >= 2) allocations += counter.count();
  }
  EXPECT_EQ(allocations, 0);
  EXPECT_EQ(counting->writes, 8);
  ASSERT_TRUE(own.close().ok());
  EXPECT_EQ(lines(options.csv_path).size(), 1u + 8u);  // header, 4 contacts, 4 releases
}

}  // namespace
}  // namespace vistel
