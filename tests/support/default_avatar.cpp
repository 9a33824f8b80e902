#include "tests/support/default_avatar.hpp"

#include <gtest/gtest.h>

#include "common/motion/joint_map.hpp"
#include "offline/build/build_model.hpp"
#include "offline/build/primitive_map.hpp"
#include "offline/synth/default_avatar.hpp"

namespace vistel::test {

std::shared_ptr<const AvatarModel> defaultAvatarWithModel() {
  static const std::shared_ptr<const AvatarModel> avatar = []() -> std::shared_ptr<AvatarModel> {
    Result<AvatarModel> made = makeDefaultAvatar();
    if (!made) {
      ADD_FAILURE() << made.error().message;
      return nullptr;
    }
    auto a = std::make_shared<AvatarModel>(std::move(*made));
    Result<std::vector<JointMap>> maps = loadJointMaps();
    Result<PrimitiveMapSpec> spec = loadPrimitiveMap();
    if (!maps || !spec) {
      ADD_FAILURE() << "config: " << (!maps ? maps.error().message : spec.error().message);
      return nullptr;
    }
    Result<const JointMap*> map = selectJointMap(*maps, a->skeleton);
    Result<ImplicitModel> model = buildImplicitModel(*a, *spec, map.ok() ? *map : nullptr);
    if (!model) {
      ADD_FAILURE() << model.error().message;
      return nullptr;
    }
    a->implicit = std::move(*model);
    return a;
  }();
  return avatar;
}

}  // namespace vistel::test
