// RoomView end to end on an offscreen (EGL surfaceless) context: what is drawn where,
// stereo modes, the first-person camera, screenshots, and the skinning pipeline.
#include "client/view/room_view.hpp"

#include <atomic>
#include <chrono>
#include <cstdio>
#include <cstring>
#include <filesystem>

#include <gtest/gtest.h>
#include <stb_image.h>
#include <glm/gtc/matrix_transform.hpp>

#include "common/anim/skinning.hpp"
#include "render_checks.hpp"
#include "test_avatar.hpp"
#include "tests/support/test_support.hpp"

namespace vistel {
namespace {

ViewOptions smallOffscreen(int width = 320, int height = 240) {
  ViewOptions options;
  options.width = width;
  options.height = height;
  options.offscreen = true;
  options.show_tags = false;
  return options;
}

glm::mat4 placeAt(float x, float z, float yaw_degrees = 0.0f) {
  return glm::rotate(glm::translate(glm::mat4(1.0f), glm::vec3(x, 0.0f, z)),
                     glm::radians(yaw_degrees), glm::vec3(0, 1, 0));
}

MemberView member(std::uint32_t id, const test::TestAvatar& avatar, const glm::mat4& placement,
                  bool is_self = false, const char* name = "") {
  return MemberView{id,        name,   avatar.model, test::makeTestPosture(*avatar.model),
                    placement, is_self};
}

// The posed skin computed independently of the view (DQS on the calling thread).
std::vector<glm::vec3> cpuSkin(const AvatarModel& avatar, const Posture& posture) {
  const auto njoint = static_cast<std::size_t>(avatar.skeleton.jointCount());
  std::vector<glm::mat4> model(njoint), skin(njoint);
  std::vector<DualQuat> dq(njoint);
  poseSkeleton(avatar.skeleton, posture, model);
  skinningMatrices(avatar.skeleton, model, skin);
  std::vector<glm::vec3> positions(avatar.skin.positions.size()), normals(positions.size());
  skinMesh(avatar.skin, SkinningMethod::kDualQuaternion, skin, dq, positions, normals);
  return positions;
}

std::vector<glm::vec3> toRoom(std::span<const glm::vec3> model, const glm::mat4& placement) {
  std::vector<glm::vec3> out;
  out.reserve(model.size());
  for (const glm::vec3& p : model) out.emplace_back(placement * glm::vec4(p, 1.0f));
  return out;
}

// Centroid x of the pixels that pass `pick`, and their count.
template <typename Pick>
std::pair<double, int> centroidX(const Image& image, int x0, int x1, Pick pick) {
  double sum = 0.0;
  int count = 0;
  for (int y = 0; y < image.height; ++y) {
    for (int x = x0; x < x1; ++x) {
      if (pick(image.pixel(x, y))) {
        sum += x;
        ++count;
      }
    }
  }
  return {count > 0 ? sum / count : -1.0, count};
}

TEST(RoomViewRender, PosedAvatarIsSkinInsideItsSilhouetteAndBackdropOutside) {
  VISTEL_MAKE_VIEW(view, smallOffscreen());
  const test::TestAvatar avatar = test::makeTestAvatar();
  const MemberView m = member(0, avatar, placeAt(0.3f, -0.2f, 25.0f));
  view->render(std::span(&m, 1));
  EXPECT_EQ(view->lastWarning(), "");
  EXPECT_EQ(view->lastStats().members_drawn, 1);

  // The view skinned exactly what an independent DQS pass computes.
  const std::vector<glm::vec3> expected = cpuSkin(*avatar.model, m.posture);
  const std::span<const glm::vec3> skinned = view->skinnedPositions(0);
  ASSERT_EQ(skinned.size(), expected.size());
  for (std::size_t v = 0; v < expected.size(); ++v) {
    ASSERT_LE(glm::length(skinned[v] - expected[v]), 1e-6f) << "vertex " << v;
  }

  // Rasterise the posed mesh through the same camera on the CPU.
  auto frame = view->readFrame();
  ASSERT_TRUE(frame.ok()) << frame.error().message;
  const Image& image = *frame;
  ASSERT_EQ(view->lastCameras().size(), 1u);
  const EyeCamera& eye = view->lastCameras()[0];
  const std::vector<glm::vec3> room = toRoom(expected, m.placement);
  const auto mask =
      test::rasterizeSilhouette(eye, image.width, image.height, room, avatar.model->skin.indices);
  const auto inside = test::erode(mask, image.width, image.height, 1);
  const auto outside = test::dilate(mask, image.width, image.height, 2);
  int inside_count = 0, inside_skin = 0, outside_count = 0, outside_backdrop = 0;
  for (int y = 0; y < image.height; ++y) {
    for (int x = 0; x < image.width; ++x) {
      const std::size_t i = static_cast<std::size_t>(y * image.width + x);
      if (inside[i]) {
        ++inside_count;
        inside_skin += test::isSkin(image.pixel(x, y)) ? 1 : 0;
      } else if (!outside[i]) {
        ++outside_count;
        outside_backdrop += test::isBackdrop(image.pixel(x, y)) ? 1 : 0;
      }
    }
  }
  // The avatar covers a fair part of the frame; every pixel well inside is skin, every
  // pixel well outside is background or floor.
  EXPECT_GT(inside_count, 2000);
  EXPECT_GT(outside_count, 40000);
  EXPECT_EQ(inside_skin, inside_count);
  EXPECT_EQ(outside_backdrop, outside_count);

  // The top rows look at the sky: exactly the background colour.
  const std::uint8_t* corner = image.pixel(2, 2);
  EXPECT_EQ(corner[0], 26);
  EXPECT_EQ(corner[1], 28);
  EXPECT_EQ(corner[2], 36);
}

TEST(RoomViewRender, SkinnedVerticesDoNotDependOnTheThreadCount) {
  const test::TestAvatar avatar = test::makeTestAvatar(16);  // several chunks per member
  ASSERT_GT(avatar.model->skin.vertexCount(), 3 * 2048);
  std::vector<MemberView> members = {member(5, avatar, placeAt(-1.0f, 0.0f)),
                                     member(6, avatar, placeAt(0.0f, 0.5f, 90.0f)),
                                     member(7, avatar, placeAt(1.0f, 0.0f, 180.0f))};
  members[1].posture.rotations[3] = glm::angleAxis(0.4f, glm::vec3(1, 0, 0));
  std::vector<std::vector<glm::vec3>> results;
  for (int threads : {1, 4}) {
    ViewOptions options = smallOffscreen(64, 48);
    options.worker_threads = threads;
    options.msaa_samples = 0;
    VISTEL_MAKE_VIEW(view, options);
    view->render(members);
    view->render(members);  // a second frame: the other half of the double buffer
    for (const MemberView& m : members) {
      const auto positions = view->skinnedPositions(m.id);
      results.emplace_back(positions.begin(), positions.end());
    }
  }
  ASSERT_EQ(results.size(), 6u);
  for (std::size_t i = 0; i < 3; ++i) {
    ASSERT_EQ(results[i].size(), results[i + 3].size());
    EXPECT_EQ(std::memcmp(results[i].data(), results[i + 3].data(),
                          results[i].size() * sizeof(glm::vec3)),
              0)
        << "member " << i;
  }
}

// Pushes every vertex 1 cm along its normal and counts its calls.
class InflateDeformer final : public PostSkinDeformer {
 public:
  void deform(const SkinFrame& frame) override {
    ++calls;
    vertices = static_cast<int>(frame.positions.size());
    for (std::size_t v = 0; v < frame.positions.size(); ++v) {
      frame.positions[v] += 0.01f * frame.normals[v];
    }
  }
  std::atomic<int> calls{0};
  int vertices = 0;
};

TEST(RoomViewRender, PostSkinDeformerRunsOnceAfterSkinningOfItsMember) {
  VISTEL_MAKE_VIEW(view, smallOffscreen(64, 48));
  const test::TestAvatar avatar = test::makeTestAvatar(12);
  auto deformer = std::make_shared<InflateDeformer>();
  view->setDeformer(1, deformer);
  const std::vector<MemberView> members = {member(1, avatar, placeAt(0, 0)),
                                           member(2, avatar, placeAt(0, 0))};
  view->render(members);
  view->render(members);
  EXPECT_EQ(deformer->calls.load(), 2);
  EXPECT_EQ(deformer->vertices, avatar.model->skin.vertexCount());
  // Member 1 = member 2 (no deformer) + 1 cm along the skinned normals.
  const std::vector<glm::vec3> rest = avatar.model->skin.normals;
  const auto inflated = view->skinnedPositions(1);
  const auto rigid = view->skinnedPositions(2);
  ASSERT_EQ(inflated.size(), rigid.size());
  for (std::size_t v = 0; v < rigid.size(); ++v) {
    ASSERT_NEAR(glm::length(inflated[v] - rigid[v]), 0.01f, 1e-5f) << "vertex " << v;
  }
  view->setDeformer(1, nullptr);
  view->render(members);
  EXPECT_EQ(deformer->calls.load(), 2);
}

TEST(RoomViewRender, SideBySideDrawsTwoSimilarHalfImages) {
  ViewOptions options = smallOffscreen(480, 200);
  options.stereo = StereoMode::kSideBySide;
  VISTEL_MAKE_VIEW(view, options);
  const test::TestAvatar avatar = test::makeTestAvatar();
  const std::vector<MemberView> members = {member(0, avatar, placeAt(-0.5f, 0.0f)),
                                           member(3, avatar, placeAt(0.6f, 0.3f, -30.0f))};
  view->render(members);
  ASSERT_EQ(view->lastCameras().size(), 2u);
  EXPECT_EQ(view->lastCameras()[0].viewport, glm::ivec4(0, 0, 240, 200));
  EXPECT_EQ(view->lastCameras()[1].viewport, glm::ivec4(240, 0, 240, 200));
  // The eyes are apart by the interocular distance.
  EXPECT_NEAR(glm::distance(view->lastCameras()[0].position, view->lastCameras()[1].position),
              options.eye_separation, 1e-4f);
  auto frame = view->readFrame();
  ASSERT_TRUE(frame.ok());
  const auto [left_x, left_n] = centroidX(*frame, 0, 240, test::isSkin);
  const auto [right_x, right_n] = centroidX(*frame, 240, 480, test::isSkin);
  ASSERT_GT(left_n, 500);
  ASSERT_GT(right_n, 500);
  // Same content in both halves: similar amounts of skin at nearly the same place.
  EXPECT_NEAR(static_cast<double>(right_n) / left_n, 1.0, 0.1);
  EXPECT_NEAR(right_x - 240.0, left_x, 6.0);
  // Pixel by pixel the halves agree almost everywhere (they differ by parallax only).
  int same = 0;
  for (int y = 0; y < 200; ++y) {
    for (int x = 0; x < 240; ++x) {
      same += test::isSkin(frame->pixel(x, y)) == test::isSkin(frame->pixel(x + 240, y)) ? 1 : 0;
    }
  }
  EXPECT_GT(same, 240 * 200 * 95 / 100);
}

TEST(RoomViewRender, AnaglyphPutsTheLeftEyeInRedAndTheRightEyeInCyan) {
  ViewOptions options = smallOffscreen(320, 240);
  options.stereo = StereoMode::kAnaglyph;
  options.eye_separation = 0.30f;  // exaggerated, so the disparity is several pixels
  VISTEL_MAKE_VIEW(view, options);
  const test::TestAvatar avatar = test::makeTestAvatar();
  const std::vector<MemberView> members = {member(0, avatar, placeAt(-0.6f, -1.0f)),
                                           member(4, avatar, placeAt(0.6f, 1.0f))};
  view->render(members);
  ASSERT_EQ(view->lastCameras().size(), 2u);
  auto frame = view->readFrame();
  ASSERT_TRUE(frame.ok());
  // Bright red channel = the left eye's skin; bright green = the right eye's.
  const auto red = [](const std::uint8_t* p) { return p[0] > 130; };
  const auto green = [](const std::uint8_t* p) { return p[1] > 120; };
  const auto [red_x, red_n] = centroidX(*frame, 0, 320, red);
  const auto [green_x, green_n] = centroidX(*frame, 0, 320, green);
  ASSERT_GT(red_n, 500);
  ASSERT_GT(green_n, 500);
  // Everything lies behind the convergence plane: the left (red) image sits to the left.
  EXPECT_LT(red_x + 1.0, green_x);
  // Pure red fringes and pure cyan fringes both exist.
  int red_only = 0, cyan_only = 0;
  for (int y = 0; y < 240; ++y) {
    for (int x = 0; x < 320; ++x) {
      const std::uint8_t* p = frame->pixel(x, y);
      red_only += red(p) && p[1] < 50 ? 1 : 0;
      cyan_only += !red(p) && p[0] < 50 && green(p) ? 1 : 0;
    }
  }
  EXPECT_GT(red_only, 50);
  EXPECT_GT(cyan_only, 50);
}

TEST(RoomViewRender, FirstPersonCameraSitsInTheSelfMembersHead) {
  ViewOptions options = smallOffscreen(320, 240);
  options.view = ViewMode::kFirstPerson;
  VISTEL_MAKE_VIEW(view, options);
  const test::TestAvatar avatar = test::makeTestAvatar();
  // Self at the origin looking along +Z; another member 2.5 m ahead, facing us.
  const glm::mat4 self_place = placeAt(0.0f, 0.0f);
  std::vector<MemberView> members = {member(9, avatar, self_place, true),
                                     member(0, avatar, placeAt(0.0f, 2.5f, 180.0f))};
  members[0].posture = restPosture(avatar.model->skeleton);
  view->render(members);
  ASSERT_EQ(view->lastCameras().size(), 1u);
  const EyeCamera& eye = view->lastCameras()[0];

  // The eye is in the head: near the head joint, inside the head's capsule.
  const Skeleton& skeleton = avatar.model->skeleton;
  std::vector<glm::mat4> joints(static_cast<std::size_t>(skeleton.jointCount()));
  poseSkeleton(skeleton, members[0].posture, joints);
  const glm::vec3 head_joint(self_place *
                             joints[static_cast<std::size_t>(skeleton.find("head"))][3]);
  EXPECT_LT(glm::distance(eye.position, head_joint), 0.2f);
  EXPECT_GT(eye.position.y, head_joint.y);
  const test::TestCapsule& head = avatar.capsules[3];
  EXPECT_LT(glm::distance(eye.position, (head.a + head.b) * 0.5f), head.radius);
  // It looks where the head faces (+Z): the view's forward axis is -row 2.
  const glm::vec3 forward = -glm::vec3(eye.view[0][2], eye.view[1][2], eye.view[2][2]);
  EXPECT_GT(glm::dot(forward, glm::vec3(0, 0, 1)), 0.99f);

  // The other member fills the middle of the picture; our own head is not in the way.
  auto frame = view->readFrame();
  ASSERT_TRUE(frame.ok());
  int x = 0, row = 0;
  ASSERT_TRUE(test::pixelOf(eye, 240, glm::vec3(0.0f, 1.25f, 2.5f), x, row));
  EXPECT_NEAR(x, 160, 3);
  EXPECT_TRUE(test::isSkin(frame->pixel(x, row)));

  // Turning the head turns the camera.
  members[0].posture.rotations[static_cast<std::size_t>(skeleton.find("head"))] =
      glm::angleAxis(glm::radians(90.0f), glm::vec3(0, 1, 0));
  view->render(members);
  const glm::mat4& turned = view->lastCameras()[0].view;
  const glm::vec3 turned_forward = -glm::vec3(turned[0][2], turned[1][2], turned[2][2]);
  EXPECT_GT(glm::dot(turned_forward, glm::vec3(1, 0, 0)), 0.99f);

  // Without a self member the view falls back to the room camera.
  members[0].is_self = false;
  view->render(members);
  EXPECT_GT(glm::distance(view->lastCameras()[0].position, head_joint), 1.0f);
}

TEST(RoomViewRender, ScreenshotPngHasTheRequestedSizeAndTheFramesPixels) {
  VISTEL_MAKE_VIEW(view, smallOffscreen(200, 150));
  const std::string dir = test::scratchDir();
  // Nothing rendered yet: a clear error, no file.
  const Status early = view->saveScreenshot(dir + "/early.png");
  ASSERT_FALSE(early.ok());
  EXPECT_NE(early.error().message.find("no frame"), std::string::npos);

  const test::TestAvatar avatar = test::makeTestAvatar();
  const MemberView m = member(0, avatar, placeAt(0, 0));
  view->render(std::span(&m, 1));
  EXPECT_EQ(view->framesRendered(), 1);
  auto frame = view->readFrame();
  ASSERT_TRUE(frame.ok());
  for (const bool fast : {false, true}) {
    const std::string path = dir + (fast ? "/frame.png" : "/shot.png");
    const Status saved = fast ? view->saveFrame(path) : view->saveScreenshot(path);
    ASSERT_TRUE(saved.ok()) << saved.error().message;
    int w = 0, h = 0, channels = 0;
    stbi_uc* pixels = stbi_load(path.c_str(), &w, &h, &channels, 4);
    ASSERT_NE(pixels, nullptr) << stbi_failure_reason();
    EXPECT_EQ(w, 200);
    EXPECT_EQ(h, 150);
    EXPECT_EQ(std::memcmp(pixels, frame->rgba.data(), frame->rgba.size()), 0);
    stbi_image_free(pixels);
  }
  // An unwritable path is an error naming it.
  const Status bad = view->saveScreenshot(dir + "/no/such/folder/x.png");
  ASSERT_FALSE(bad.ok());
  EXPECT_NE(bad.error().message.find("no/such/folder"), std::string::npos);
}

TEST(RoomViewRender, NameTagsAndMarkersAppearAboveTheHeads) {
  const test::TestAvatar avatar = test::makeTestAvatar();
  // Member 2's colour is green: nothing else in the scene is green-dominant.
  const MemberView m = member(2, avatar, placeAt(0, 0), false, "alice");
  for (const bool tags : {false, true}) {
    ViewOptions options = smallOffscreen(320, 240);
    options.show_tags = tags;
    VISTEL_MAKE_VIEW(view, options);
    view->render(std::span(&m, 1));
    auto frame = view->readFrame();
    ASSERT_TRUE(frame.ok());
    int head_x = 0, head_row = 0;
    ASSERT_TRUE(
        test::pixelOf(view->lastCameras()[0], 240, glm::vec3(0.0f, 1.87f, 0.0f), head_x, head_row));
    int green_above = 0, green_below = 0, white_above = 0;
    for (int y = 0; y < 240; ++y) {
      for (int x = 0; x < 320; ++x) {
        const std::uint8_t* p = frame->pixel(x, y);
        const bool green = p[1] > p[0] + 40 && p[1] > p[2] + 40;
        const bool white = p[0] > 240 && p[1] > 240 && p[2] > 240;
        (y < head_row ? green_above : green_below) += green ? 1 : 0;
        white_above += white && y < head_row ? 1 : 0;
      }
    }
    EXPECT_EQ(green_below, 0);
    if (tags) {
      EXPECT_GT(green_above, 150);  // the tag's box and the marker
      EXPECT_GT(white_above, 15);   // the name's letters
    } else {
      EXPECT_EQ(green_above, 0);
      EXPECT_EQ(white_above, 0);
    }
  }
}

TEST(RoomViewRender, RoomCameraKeepsEveryoneInTheFrame) {
  VISTEL_MAKE_VIEW(view, smallOffscreen(320, 240));
  const test::TestAvatar avatar = test::makeTestAvatar();
  std::vector<MemberView> members;
  for (std::uint32_t i = 0; i < 6; ++i) {
    const float angle = static_cast<float>(i) * 60.0f;
    const glm::vec3 at =
        2.5f * glm::vec3(std::sin(glm::radians(angle)), 0.0f, std::cos(glm::radians(angle)));
    members.push_back(member(i, avatar, placeAt(at.x, at.z, angle + 180.0f)));
  }
  for (int frame = 0; frame < 3; ++frame) view->render(members);
  EXPECT_EQ(view->lastStats().members_drawn, 6);
  const EyeCamera& eye = view->lastCameras()[0];
  for (const MemberView& m : members) {
    for (const glm::vec3& p : toRoom(view->skinnedPositions(m.id), m.placement)) {
      glm::vec3 pixel;
      ASSERT_TRUE(projectToPixel(eye, p, pixel));
      EXPECT_TRUE(pixel.x >= 0 && pixel.x <= 320 && pixel.y >= 0 && pixel.y <= 240 &&
                  pixel.z > -1 && pixel.z < 1)
          << "member " << m.id << " leaves the frame";
    }
  }
}

// A member taken out of the framing (a prop far away) does not pull the room camera back;
// drawn alone, it is framed anyway.
TEST(RoomViewRender, UnframedMembersDoNotWidenTheRoomCamera) {
  const test::TestAvatar avatar = test::makeTestAvatar();
  const std::vector<MemberView> members = {member(1, avatar, placeAt(0.0f, 0.0f, 0.0f)),
                                           member(2, avatar, placeAt(25.0f, 0.0f, 0.0f))};
  // Distance from the room camera to `target` after a few frames.
  const auto cameraDistance = [&](bool frame_far, const std::vector<MemberView>& drawn,
                                  const glm::vec3& target) {
    auto created = RoomView::create(smallOffscreen(320, 240));
    if (!created) return -1.0f;
    if (!frame_far) (*created)->setFramed(2, false);
    for (int frame = 0; frame < 3; ++frame) (*created)->render(drawn);
    return glm::distance((*created)->lastCameras()[0].position, target);
  };
  VISTEL_MAKE_VIEW(probe, smallOffscreen(32, 32));  // skips without OpenGL
  const float both = cameraDistance(true, members, glm::vec3(12.5f, 1.0f, 0.0f));
  const float near_only = cameraDistance(false, members, glm::vec3(0.0f, 1.0f, 0.0f));
  ASSERT_GT(both, 0.0f);
  ASSERT_GT(near_only, 0.0f);
  EXPECT_LT(near_only, 0.5f * both)
      << "framing both: " << both << " m, the near one: " << near_only;
  // Alone, the unframed member is framed all the same.
  const float alone = cameraDistance(false, {members[1]}, glm::vec3(25.0f, 1.0f, 0.0f));
  EXPECT_GT(alone, 0.0f);
  EXPECT_LT(alone, 1.5f * near_only);
}

TEST(RoomViewRender, MembersComeAndGoAndBadInputStaysContained) {
  VISTEL_MAKE_VIEW(view, smallOffscreen(96, 72));
  const test::TestAvatar avatar = test::makeTestAvatar();
  std::vector<MemberView> members = {member(1, avatar, placeAt(-0.5f, 0)),
                                     member(2, avatar, placeAt(0.5f, 0))};
  view->render(members);
  EXPECT_EQ(view->lastStats().members_drawn, 2);
  EXPECT_EQ(view->lastStats().vertices_skinned, 2 * avatar.model->skin.vertexCount());

  // One leaves: its buffers go.
  members.pop_back();
  view->render(members);
  EXPECT_EQ(view->lastStats().members_drawn, 1);
  EXPECT_TRUE(view->skinnedPositions(2).empty());

  // A posture for another skeleton and a non-finite one: drawn at rest, counted.
  members.push_back(member(3, avatar, placeAt(0.5f, 0)));
  members.push_back(member(4, avatar, placeAt(1.5f, 0)));
  members[1].posture.rotations.pop_back();
  members[2].posture.rotations[2] = glm::quat(NAN, 0, 0, 0);
  view->render(members);
  EXPECT_EQ(view->lastStats().members_drawn, 3);
  EXPECT_EQ(view->lastStats().postures_at_rest, 2);
  for (const glm::vec3& p : view->skinnedPositions(4)) ASSERT_TRUE(std::isfinite(p.x + p.y + p.z));

  // A repeated id is drawn once; a null avatar is skipped.
  members.push_back(members[0]);
  members.push_back(MemberView{8, "ghost", nullptr, Posture{}, glm::mat4(1.0f), false});
  view->render(members);
  EXPECT_EQ(view->lastStats().members_drawn, 3);

  // An avatar that fails validation is not drawn, and the view says why.
  auto broken = std::make_shared<AvatarModel>(*avatar.model);
  broken->skin.indices.push_back(999999);
  broken->skin.indices.push_back(0);
  broken->skin.indices.push_back(1);
  members.push_back(
      MemberView{10, "broken", broken, restPosture(broken->skeleton), glm::mat4(1.0f), false});
  view->render(members);
  EXPECT_EQ(view->lastStats().members_drawn, 3);
  EXPECT_NE(view->lastWarning().find("broken"), std::string::npos) << view->lastWarning();
  EXPECT_EQ(view->framesRendered(), 5);
}

TEST(RoomViewRender, HeadJointGivenByTheCallerMovesTheFirstPersonEye) {
  ViewOptions options = smallOffscreen(64, 48);
  options.view = ViewMode::kFirstPerson;
  VISTEL_MAKE_VIEW(view, options);
  const test::TestAvatar avatar = test::makeTestAvatar();
  MemberView self = member(1, avatar, placeAt(0, 0), true);
  self.posture = restPosture(avatar.model->skeleton);
  view->render(std::span(&self, 1));
  const glm::vec3 at_head = view->lastCameras()[0].position;
  // Say the "head" is the chest: the eye moves down with it.
  view->setHeadJoint(1, avatar.model->skeleton.find("chest"));
  view->render(std::span(&self, 1));
  EXPECT_LT(view->lastCameras()[0].position.y, at_head.y - 0.15f);
}

TEST(RoomViewRender, RejectsBadOptionsWithAClearError) {
  ViewOptions options = smallOffscreen(0, 240);
  auto view = RoomView::create(options);
  ASSERT_FALSE(view.ok());
  EXPECT_NE(view.error().message.find("0x240"), std::string::npos) << view.error().message;
}

// Frame times for the report (not an assertion; run with --gtest_also_run_disabled_tests).
TEST(RoomViewRender, DISABLED_MeasureFrameTimes) {
  for (const int msaa : {-1, 4})
    for (const int members_count : {1, 4, 16}) {
      ViewOptions options;
      options.offscreen = true;
      options.width = 1280;
      options.height = 720;
      options.msaa_samples = msaa;
      VISTEL_MAKE_VIEW(view, options);
      const test::TestAvatar avatar = test::makeTestAvatar(16);  // 17408 vertices
      std::vector<MemberView> members;
      for (int i = 0; i < members_count; ++i) {
        members.push_back(
            member(static_cast<std::uint32_t>(i), avatar,
                   placeAt(static_cast<float>(i % 4) - 1.5f, static_cast<float>(i / 4) * 1.2f),
                   false, "member"));
      }
      for (int i = 0; i < 3; ++i) view->render(members);
      const int frames = 20;
      double skin = 0.0, draw = 0.0;
      const auto start = std::chrono::steady_clock::now();
      for (int i = 0; i < frames; ++i) {
        view->render(members);
        skin += view->lastStats().skin_ms;
        draw += view->lastStats().draw_ms;
      }
      auto read = view->readFrame();  // includes waiting for the GPU
      const double total =
          std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start)
              .count();
      std::printf(
          "%2d members x %d vertices, 1280x720, MSAA option %d: %.2f ms/frame (skin %.2f, draw "
          "%.2f) %s\n",
          members_count, avatar.model->skin.vertexCount(), msaa, total / frames, skin / frames,
          draw / frames, view->backendDescription().c_str());
    }
}

}  // namespace
}  // namespace vistel
