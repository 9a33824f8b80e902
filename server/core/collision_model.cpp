#include "server/core/collision_model.hpp"

#include <algorithm>
#include <string>

#include "common/anim/posture.hpp"

namespace vistel::server {

Result<std::shared_ptr<const CollisionModel>> makeCollisionModel(AvatarModel&& avatar,
                                                                 const CollisionLimits& limits,
                                                                 std::string_view source) {
  auto model = std::make_shared<CollisionModel>();
  model->skeleton = std::move(avatar.skeleton);
  model->head_joint = findHeadJoint(model->skeleton);
  if (!avatar.implicit) return std::shared_ptr<const CollisionModel>(std::move(model));

  // The primitives must stay within the server's limits (the decoder has validated them).
  const PrimitiveSet& set = avatar.implicit->primitives;
  if (static_cast<int>(set.items.size()) > limits.max_primitives) {
    return fail("{}: {} primitives in the implicit model (this server accepts at most {})", source,
                set.items.size(), limits.max_primitives);
  }
  for (std::size_t i = 0; i < set.items.size(); ++i) {
    const Primitive& p = set.items[i];
    const Bounds box = shapeBounds(p.shape, p.r_out);
    const glm::vec3 size = box.max - box.min;
    const float extent = std::max({size.x, size.y, size.z});
    if (!(extent <= limits.max_extent_m)) {
      return fail("{}: primitive {} '{}' spans {:.2f} m (this server accepts at most {:.2f} m)",
                  source, i, p.name, extent, limits.max_extent_m);
    }
  }
  model->collides = true;
  model->primitives = std::move(avatar.implicit->primitives);
  model->graph = std::move(avatar.implicit->graph);
  return std::shared_ptr<const CollisionModel>(std::move(model));
}

}  // namespace vistel::server
