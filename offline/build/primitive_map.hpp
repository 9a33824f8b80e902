// The map from skeleton joints to implicit primitives (config/avatars/*.toml): which
// primitive each body part gets, what shape, which bone carries it, which joints' skin
// vertices it owns, and which pairs blend or do not collide. Keyed by canonical joint
// names (common/motion/joint_map.hpp) so one map serves every rig with a JointMap.
//
// Format (all keys but name/shape/bone optional; see config/avatars/humanoid.toml):
//   iso, diff_exponent, joint_weight, limb_weight, max_surface_ratio
//   [propagation] amplitude, width
//   [material] density = "wyvill"|"piecewise", knee, slope, stiffness (Pa/m, or "rigid"),
//              elasticity = "elastic"|"plastic"|"viscoelastic", time_constant (s)
//   [[primitive]] name, role = "limb"|"joint"|"bone", shape = "sphere"|"sphylinder"|
//     "cone_sphere"|"offset_polygon", bone, joints = [...], from, to (segment ends; omit
//     for a principal-axis fit), at (sphere centre joint), between = [limb, limb] (joint
//     primitives), blend (bone primitives: the joint primitive they join), offset = [x,y,z]
//     (bone primitives: direction from `at`, model space), depth (fraction of the local
//     radius), reach (bound over the nearest skin distance), normal = [x,y,z] (polygon
//     plane normal; else principal axes), collides, and any [material] key.
//   no_collide = [[name, name], ...]
#pragma once

#include <array>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include <glm/glm.hpp>

#include "common/base/result.hpp"
#include "common/deform/implicit_model.hpp"

namespace vistel {

struct Material {
  Density density;
  float stiffness = 3.0e4f;
  Elasticity elasticity = Elasticity::kElastic;
  float time_constant = 0.5f;
};

struct PrimitiveSpec {
  std::string name;
  PrimitiveRole role = PrimitiveRole::kLimb;
  ShapeKind shape = ShapeKind::kSphylinder;
  std::string bone;                    // canonical joint carrying it
  std::vector<std::string> joints;     // limb: joints whose vertices it owns
  std::string from, to;                // segment ends (joints); empty: principal-axis fit
  std::string at;                      // joint/bone sphere centre (joint)
  std::array<std::string, 2> between;  // joint primitive: the two limb primitives
  std::string blend;                   // bone primitive: the joint primitive it joins
  std::optional<glm::vec3> offset;     // bone primitive: direction from `at` (model space)
  float depth = 0.6f;                  // bone primitive: offset as a fraction of the radius
  float reach = 1.1f;                  // bone primitive: bound / nearest skin distance
  std::optional<glm::vec3> normal;     // polygon plane normal (model space, rest)
  bool collides = true;
  Material material;
  int line = 0;  // where it was defined, for messages
};

struct PrimitiveMapSpec {
  std::string source;
  float iso = 0.5f;
  int diff_exponent = 4;
  float joint_weight = 0.15f;      // second limb's weight from which a vertex is a joint vertex
  float limb_weight = 0.5f;        // own-bone weight from which a vertex is a limb vertex
  float max_surface_ratio = 0.7f;  // r_in / r_out at most this (the surface inside the support)
  float propagation_amplitude = 0.3f;
  float propagation_width = 0.45f;
  Material material;
  std::vector<PrimitiveSpec> primitives;
  std::vector<std::array<std::string, 2>> no_collide;

  const PrimitiveSpec* find(std::string_view name) const;
};

// Parses a map; errors name the source, the line and the key. Checks references
// (between, blend, no_collide name primitives of the right roles; unique names).
Result<PrimitiveMapSpec> parsePrimitiveMap(std::string_view toml_text, std::string_view source);

// Reads a map file ("config/..." falls back to the embedded copy), then parses it.
Result<PrimitiveMapSpec> loadPrimitiveMap(const std::string& path = "config/avatars/humanoid.toml");

}  // namespace vistel
