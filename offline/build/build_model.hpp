// Building an avatar's implicit model offline (DESIGN.md §3): primitives chosen by a
// PrimitiveMapSpec and fitted to the skin, vertex classes from skin weights, the
// combination graph, calibration and relaxation weights. Works on any rigged humanoid
// whose joint names a JointMap translates to the map's canonical names.
#pragma once

#include <functional>
#include <string>
#include <string_view>
#include <vector>

#include "common/avatar/avatar_model.hpp"
#include "common/base/result.hpp"
#include "common/deform/calibrate.hpp"
#include "common/deform/implicit_model.hpp"
#include "common/motion/joint_map.hpp"
#include "offline/build/primitive_map.hpp"

namespace vistel {

struct BuildOptions {
  FieldCalibrationOptions calibration;
  // Give the skin's free vertices (fingers, toes, upper chest, crown) fields of their own
  // after calibration (adoptFreeVertices, free_vertex_adoption.hpp), so that every vertex
  // meets a partner through a field: relative deformability and the common contact surface.
  bool adopt_free_vertices = true;
  // Called with the fraction done (0..1) and the stage's name; may be empty.
  std::function<void(float, std::string_view)> progress;
};

struct BuildReport {
  CalibrationReport calibration;        // after adoption, where it ran
  int adopted_primitives = 0;           // primitives adoptFreeVertices added
  int adopted_vertices = 0;             // free vertices they took
  std::vector<std::string> primitives;  // names, in model order
  std::vector<std::string> warnings;    // primitives skipped (joints missing, no vertices)
};

// Builds the implicit model of `avatar` (validated first). `map` translates the spec's
// canonical joint names to the avatar's (null: the avatar uses canonical names). Fails
// when the avatar is invalid or no limb primitive can be placed.
Result<ImplicitModel> buildImplicitModel(const AvatarModel& avatar, const PrimitiveMapSpec& spec,
                                         const JointMap* map, const BuildOptions& options = {},
                                         BuildReport* report = nullptr);

}  // namespace vistel
