// RoomView with gpu_skinning: members that need no CPU vertices are skinned by the vertex
// shader (dual quaternions, as skinDualQuaternion) and look the same as the CPU path's
// skinning, pixel for pixel up to rasterisation at the edges; a different pose looks
// different (the shader does use the joints).
#include <algorithm>
#include <cstdlib>
#include <memory>
#include <vector>

#include <gtest/gtest.h>

#include "client/render/scene_renderer.hpp"
#include "client/view/room_view.hpp"
#include "common/scene/deform_scene.hpp"
#include "tests/scene/scene_fixtures.hpp"
#include "tests/support/alloc_counter.hpp"

namespace vistel {
namespace {

Result<std::unique_ptr<RoomView>> makeView(bool gpu) {
  ViewOptions options;
  options.width = 200;
  options.height = 150;
  options.offscreen = true;
  options.view = ViewMode::kFirstPerson;
  options.show_tags = false;
  options.gpu_skinning = gpu;
  return RoomView::create(options);
}

// The viewer: a small ball 1 m behind the tube, looking at it (+z) from inside itself.
std::vector<MemberView> room(float bend) {
  BallSpec spec;
  spec.radius = 0.05f;
  Result<std::shared_ptr<const AvatarModel>> ball = makeBallAvatar(spec);
  EXPECT_TRUE(ball.ok());
  std::vector<MemberView> members(2);
  members[0].id = 1;
  members[0].avatar = ball.ok() ? *ball : nullptr;
  members[0].posture = restPosture(members[0].avatar->skeleton);
  members[0].posture.root_translation = glm::vec3(0.0f, 1.1f, -1.0f);
  members[0].is_self = true;
  members[1].id = 2;
  members[1].avatar = test::tubeAvatar();
  members[1].posture = restPosture(members[1].avatar->skeleton);
  test::bendTube(members[1].posture, bend);
  members[1].placement = test::at({-0.3f, 1.0f, 0.0f});
  return members;
}

// Pixels whose colour differs by more than 24/255 in a channel.
int differingPixels(const Image& a, const Image& b) {
  int count = 0;
  const std::size_t n = std::min(a.rgba.size(), b.rgba.size()) / 4;
  for (std::size_t i = 0; i < n; ++i) {
    int d = 0;
    for (std::size_t c = 0; c < 3; ++c) {
      d = std::max(
          d, std::abs(static_cast<int>(a.rgba[4 * i + c]) - static_cast<int>(b.rgba[4 * i + c])));
    }
    count += d > 24 ? 1 : 0;
  }
  return count;
}

TEST(GpuSkinning, DrawsWhatTheCpuSkins) {
  Result<std::unique_ptr<RoomView>> cpu = makeView(false);
  if (!cpu && cpu.error().message.find("no OpenGL available") != std::string::npos) {
    GTEST_SKIP() << cpu.error().message;
  }
  ASSERT_TRUE(cpu.ok()) << cpu.error().message;
  Result<std::unique_ptr<RoomView>> gpu = makeView(true);
  ASSERT_TRUE(gpu.ok()) << gpu.error().message;
  const std::vector<MemberView> members = room(1.2f);
  (*cpu)->render(members);
  (*gpu)->render(members);
  EXPECT_EQ((*cpu)->lastStats().members_gpu_skinned, 0);
  EXPECT_EQ((*gpu)->lastStats().members_gpu_skinned, 2);
  EXPECT_EQ((*gpu)->lastStats().vertices_skinned, 0);
  EXPECT_TRUE((*gpu)->skinnedPositions(2).empty());
  EXPECT_FALSE((*cpu)->skinnedPositions(2).empty());
  EXPECT_TRUE((*gpu)->lastWarning().empty()) << (*gpu)->lastWarning();

  Result<Image> a = (*cpu)->readFrame();
  Result<Image> b = (*gpu)->readFrame();
  ASSERT_TRUE(a.ok() && b.ok());
  ASSERT_EQ(a->width, b->width);
  const int total = a->width * a->height;
  // The tube covers a good part of the picture (against an empty room at rest: no tube).
  Result<std::unique_ptr<RoomView>> empty = makeView(false);
  ASSERT_TRUE(empty.ok());
  std::vector<MemberView> viewer_only = members;
  viewer_only.pop_back();
  (*empty)->render(viewer_only);
  Result<Image> c = (*empty)->readFrame();
  ASSERT_TRUE(c.ok());
  const int tube_pixels = differingPixels(*a, *c);
  EXPECT_GT(tube_pixels, total / 50) << "the tube is not in the picture";
  // GPU and CPU skinning agree but for a few edge pixels.
  EXPECT_LT(differingPixels(*a, *b), std::max(tube_pixels / 50, 10));

  // A different pose on the GPU looks different.
  (*gpu)->render(room(0.0f));
  Result<Image> straight = (*gpu)->readFrame();
  ASSERT_TRUE(straight.ok());
  EXPECT_GT(differingPixels(*a, *straight), tube_pixels / 10);
}

// Adds fixed model-space offsets: on the CPU in deform(), or through offsetsOnly() for
// the vertex shader.
class OffsetDeformer final : public PostSkinDeformer {
 public:
  OffsetDeformer(std::size_t nvert, bool offsets_only)
      : positions_(nvert), normals_(nvert, glm::vec3(0.0f)), offsets_only_(offsets_only) {}

  void setShift(const glm::vec3& shift) {
    std::fill(positions_.begin(), positions_.end(), shift);
    ++generation_;
  }
  void deform(const SkinFrame& frame) override {
    for (std::size_t v = 0; v < positions_.size(); ++v) {
      frame.positions[v] += positions_[v];
      frame.normals[v] = glm::normalize(frame.normals[v] + normals_[v]);
    }
  }
  bool offsetsOnly(SkinOffsets& out) override {
    if (!offsets_only_) return false;
    out = SkinOffsets{positions_, normals_, generation_};
    return true;
  }

 private:
  std::vector<glm::vec3> positions_;
  std::vector<glm::vec3> normals_;
  std::uint64_t generation_ = 0;
  bool offsets_only_;
};

TEST(GpuSkinning, AddsADeformersOffsetsAsTheCpuDoes) {
  Result<std::unique_ptr<RoomView>> cpu = makeView(false);
  if (!cpu && cpu.error().message.find("no OpenGL available") != std::string::npos) {
    GTEST_SKIP() << cpu.error().message;
  }
  ASSERT_TRUE(cpu.ok()) << cpu.error().message;
  Result<std::unique_ptr<RoomView>> gpu = makeView(true);
  ASSERT_TRUE(gpu.ok()) << gpu.error().message;
  const std::vector<MemberView> members = room(1.2f);
  const std::size_t nvert = test::tubeAvatar()->skin.positions.size();
  auto on_cpu = std::make_shared<OffsetDeformer>(nvert, false);
  auto on_gpu = std::make_shared<OffsetDeformer>(nvert, true);
  (*cpu)->setDeformer(2, on_cpu);
  (*gpu)->setDeformer(2, on_gpu);

  // Unshifted, then lifted 12 cm, then lifted and moved sideways: the same pictures.
  Result<std::unique_ptr<RoomView>> plain = makeView(false);
  ASSERT_TRUE(plain.ok());
  (*plain)->render(members);
  Result<Image> unshifted = (*plain)->readFrame();
  ASSERT_TRUE(unshifted.ok());
  for (const glm::vec3 shift : {glm::vec3(0.0f, 0.12f, 0.0f), glm::vec3(0.1f, 0.12f, 0.0f)}) {
    on_cpu->setShift(shift);
    on_gpu->setShift(shift);
    for (int frame = 0; frame < 2; ++frame) {
      (*cpu)->render(members);
      (*gpu)->render(members);
      const FrameStats& s = (*gpu)->lastStats();
      EXPECT_EQ(s.gpu_offsets, 1);
      EXPECT_EQ(s.gpu_offset_uploads, frame == 0 ? 1 : 0) << "uploaded only when changed";
      EXPECT_EQ((*cpu)->lastStats().gpu_offsets, 0);
      Result<Image> a = (*cpu)->readFrame();
      Result<Image> b = (*gpu)->readFrame();
      ASSERT_TRUE(a.ok() && b.ok());
      const int moved = differingPixels(*a, *unshifted);
      EXPECT_GT(moved, 200) << "the offsets move the tube";
      EXPECT_LT(differingPixels(*a, *b), std::max(moved / 50, 10));
    }
  }
}

TEST(GpuSkinning, NoHeapAllocationPerFrame) {
  Result<std::unique_ptr<RoomView>> gpu = makeView(true);
  if (!gpu && gpu.error().message.find("no OpenGL available") != std::string::npos) {
    GTEST_SKIP() << gpu.error().message;
  }
  ASSERT_TRUE(gpu.ok()) << gpu.error().message;
  std::vector<MemberView> members = room(1.2f);
  auto offsets = std::make_shared<OffsetDeformer>(test::tubeAvatar()->skin.positions.size(), true);
  (*gpu)->setDeformer(2, offsets);
  for (int i = 0; i < 3; ++i) (*gpu)->render(members);  // warm-up
  const test::AllocationCounter counter;
  for (int i = 0; i < 4; ++i) {
    test::bendTube(members[1].posture, 1.0f + 0.1f * static_cast<float>(i));
    offsets->setShift(glm::vec3(0.0f, 0.01f * static_cast<float>(i), 0.0f));
    (*gpu)->render(members);
  }
  EXPECT_EQ(counter.count(), 0);
  EXPECT_EQ((*gpu)->lastStats().gpu_offset_uploads, 1);
}

}  // namespace
}  // namespace vistel
