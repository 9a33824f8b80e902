// Balls as the bodies of a client's deformable scene (RoomDeformer over a headless RoomView),
// for the tests of this folder: a ball avatar, its view at a place, the view itself.
#pragma once

#include <cstdint>
#include <memory>
#include <string>

#include <gtest/gtest.h>
#include <glm/gtc/matrix_transform.hpp>

#include "client/view/room_view.hpp"
#include "common/deform/prop.hpp"

namespace vistel::test {

inline std::shared_ptr<const AvatarModel> ballAvatar(float radius, float stiffness,
                                                     Elasticity elasticity = Elasticity::kElastic) {
  BallSpec spec;
  spec.radius = radius;
  spec.stiffness = stiffness;
  spec.elasticity = elasticity;
  Result<std::shared_ptr<const AvatarModel>> b = makeBallAvatar(spec);
  EXPECT_TRUE(b.ok()) << (b.ok() ? "" : b.error().message);
  return b.ok() ? *b : nullptr;
}

// A member view of `avatar` at rest, placed at `at` (room space).
inline MemberView ballView(std::uint32_t id, std::shared_ptr<const AvatarModel> avatar,
                           const glm::vec3& at, bool is_self = false) {
  MemberView v;
  v.id = id;
  v.name = "ball " + std::to_string(id);
  v.avatar = std::move(avatar);
  v.placement = glm::translate(glm::mat4(1.0f), at);
  v.posture = restPosture(v.avatar->skeleton);
  v.is_self = is_self;
  return v;
}

// A headless view skinning on the calling thread (null, with a test failure, if it fails).
inline std::unique_ptr<RoomView> headlessView() {
  ViewOptions options;
  options.headless = true;
  options.worker_threads = 1;
  Result<std::unique_ptr<RoomView>> view = RoomView::create(options);
  EXPECT_TRUE(view.ok()) << (view.ok() ? "" : view.error().message);
  return view.ok() ? std::move(*view) : nullptr;
}

}  // namespace vistel::test
