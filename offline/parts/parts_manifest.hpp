// Reading a PARTS.toml (the file vistel-avatar cut writes with partsToml; the input of
// vistel-avatar synthesize):
//
//   source = "avatar.glb"        # the skeleton source: an avatar file whose skeleton (and
//                                # skin weights, when it has a skin) the parts are placed on
//   band_m = 0.03                # optional: the band cut away at each joint, metres
//   [[part]]                     # one per part mesh
//   file = "torso.obj"           # .obj, .ply, .off or .stl, relative to the PARTS.toml
//   segment = "torso"            # unique among the parts
//   bone = "pelvis"              # the skeleton joint the part hangs on
//   vertices = 1346              # optional counts (informative)
//   triangles = 2545
//   [[joint]]                    # one per blend region
//   name = "l_forearm"           # canonical joint name
//   bone = "lowerarm_l"          # the skeleton's joint
//   between = ["l_upperarm", "l_forearm"]   # parent and child segments (parts)
//   position = [x, y, z]         # the joint's rest position, model space, metres
//   blend_radius_m = 0.015       # the blend region's radius around the seam, metres
//
// A relative `source` is taken from the working folder when it exists there (as cut
// writes what it was given), else from the PARTS.toml's folder. Errors name the file, the
// table and the key.
#pragma once

#include <string>
#include <string_view>
#include <vector>

#include <glm/glm.hpp>

#include "common/base/result.hpp"

namespace vistel {

struct ManifestPart {
  std::string file;  // resolved path
  std::string segment;
  std::string bone;
};

struct ManifestJoint {
  std::string name;
  std::string bone;
  std::string parent_segment, child_segment;  // both name parts of the manifest
  glm::vec3 position{0.0f};                   // model space, metres
  float blend_radius_m = 0.0f;                // > 0
};

struct PartsManifest {
  std::string source;   // resolved path ("" when the file names none)
  float band_m = 0.0f;  // 0 when not given
  std::vector<ManifestPart> parts;
  std::vector<ManifestJoint> joints;
};

// `text` of a PARTS.toml in `folder` (for relative paths); `name` for messages.
Result<PartsManifest> parsePartsManifest(std::string_view text, const std::string& folder,
                                         std::string_view name);

// Reads and parses the file at `path`.
Result<PartsManifest> readPartsManifest(const std::string& path);

}  // namespace vistel
