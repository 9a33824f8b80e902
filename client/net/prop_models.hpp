// Props as something a member view can draw (DESIGN.md §6): a ball is an AvatarModel of its
// own (common/scene makeBallAvatar: a one-joint skeleton, an icosphere skin and its calibrated
// sphere primitive), posed by putting the joint at the ball's centre. The renderer (and a
// deformer) then treat it like any avatar.
//
// Thread-safe (a mutex guards the cache); models are immutable once made and shared.
#pragma once

#include <cstdint>
#include <memory>
#include <mutex>
#include <vector>

#include <glm/glm.hpp>

#include "common/anim/posture.hpp"
#include "common/avatar/avatar_model.hpp"
#include "common/deform/prop.hpp"

namespace vistel::net {

class PropModels {
 public:
  // The model of a ball with this spec (made once per distinct spec, then shared); null if
  // makeBall refuses the spec.
  std::shared_ptr<const AvatarModel> ball(const BallSpec& spec);

 private:
  struct Entry {
    BallSpec spec;
    std::shared_ptr<const AvatarModel> model;
  };
  std::mutex mutex_;
  std::vector<Entry> entries_;
};

// An id for a prop's view that no member id can equal: member and prop ids are handles
// whose slot (low 16 bits) is below 0xFFFF, so (prop slot << 16) | 0xFFFF is free.
inline std::uint32_t propViewId(std::uint32_t prop_id) { return (prop_id << 16) | 0xFFFFu; }

// The posture of a ball model with its centre at `centre` (room space; the view's placement
// is the identity): the root joint there, not rotated.
void ballPosture(const glm::vec3& centre, Posture& out);

}  // namespace vistel::net
