// AvatarModel: everything static about one avatar (DESIGN.md §2), built offline and
// shared read-only at run time.
#pragma once

#include <string>

#include "common/anim/skeleton.hpp"
#include "common/anim/skin_mesh.hpp"
#include "common/base/result.hpp"

namespace vistel {

struct AvatarModel {
  std::string name;   // display name, e.g. the file stem
  Skeleton skeleton;  // model space, metres, +Y up
  SkinMesh skin;      // prototype skin in the bind (= rest) posture
  // The deformable component (PrimitiveSet, CombinationGraph, Calibration) joins here
  // with the deformable-component issue.
};

// Validates skeleton and skin together (the message names the part and the element).
Status validateAvatar(const AvatarModel& avatar);

}  // namespace vistel
