// AvatarModel: everything static about one avatar (DESIGN.md §2), built offline and
// shared read-only at run time.
#pragma once

#include <optional>
#include <string>

#include "common/anim/skeleton.hpp"
#include "common/anim/skin_mesh.hpp"
#include "common/avatar/avatar_look.hpp"
#include "common/base/result.hpp"
#include "common/deform/implicit_model.hpp"

namespace vistel {

struct AvatarModel {
  std::string name;   // display name, e.g. the file stem
  Skeleton skeleton;  // model space, metres, +Y up
  SkinMesh skin;      // prototype skin in the bind (= rest) posture
  // The deformable component (primitives, combination graph, calibration), fitted by
  // `vistel-avatar build`; empty = the avatar is drawn with the rigid component only.
  std::optional<ImplicitModel> implicit;
  // Texture coordinates, materials and textures of the skin (avatar_look.hpp); empty =
  // drawn in the renderer's plain skin colour.
  AvatarLook look;
};

// Validates skeleton, skin, implicit model and look together (the message names the part and
// the element).
Status validateAvatar(const AvatarModel& avatar);

}  // namespace vistel
