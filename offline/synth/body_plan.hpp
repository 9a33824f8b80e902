// The default avatar's body plan: the canonical humanoid skeleton in an A-pose and the
// primitives along its bones whose blended distance field is the skin. Model space:
// metres, +Y up, the body faces +Z, its left side is +X, soles on y = 0.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include <glm/glm.hpp>

#include "offline/synth/default_avatar.hpp"

namespace vistel::synth {

enum class ShapeKind : std::uint8_t {
  kEllipsoid,  // radii = size
  kRoundCone,  // segment from the local origin along +Y, length size.x; radius size.y at the
               // origin, size.z at the far end (a cone-sphere)
  kRoundBox,   // half extents = size (outer), edges rounded by `rounding`
};

// One primitive, defined in its local frame: p_local = to_local * (p_model - origin), then
// squeezed: the shape is scaled by `stretch` along the local axes (used to flatten
// cone-spheres; an ellipsoid is a unit sphere stretched by its radii).
struct Shape {
  ShapeKind kind = ShapeKind::kEllipsoid;
  glm::vec3 origin{0.0f};        // model space, metres
  glm::mat3 to_local{1.0f};      // rotation model -> local
  glm::vec3 size{0.0f};          // see ShapeKind, metres
  glm::vec3 stretch{1.0f};       // local scale factors (> 0)
  float rounding = 0.0f;         // kRoundBox only, metres
  int joint = 0;                 // skeleton joint that carries it (skin label)
  float detail = 0.0f;           // its smallest radius of curvature, about (metres):
                                 // how finely the skin must be sampled near it
  glm::vec3 bound_center{0.0f};  // bounding sphere (model space), for culling:
  float bound_radius = 0.0f;     // the shape's value at p is at least
  float bound_slope = 1.0f;      // bound_slope * (|p - bound_center| - bound_radius)
};

// A group of shapes blended by a smooth union of radius `blend`, attached to its parent part
// by a smooth union of radius `attach_blend`. Sibling parts never blend with each other
// (fingers stay apart, legs do not fuse); a part blends with its parent's own shapes.
struct Part {
  std::vector<int> shapes;    // indices into BodyPlan::shapes
  float blend = 0.0f;         // metres
  int parent = -1;            // -1 for the root part; parents precede children
  float attach_blend = 0.0f;  // metres
};

struct Box {
  glm::vec3 min{0.0f};
  glm::vec3 max{0.0f};
};

// A region whose detail needs cells `halvings` times smaller than the body's.
struct FineRegion {
  Box box;  // model space
  int halvings = 1;
};

struct BodyPlan {
  std::vector<std::string> joint_names;    // the 52 canonical names, parents first
  std::vector<int> joint_parents;          // -1 for hips (joint 0)
  std::vector<glm::vec3> joint_positions;  // rest position per joint, model space
  std::vector<glm::vec3> bone_tips;        // end of each joint's bone (its child joint, or
                                           // a fingertip, toe tip, crown), model space
  std::vector<Shape> shapes;
  std::vector<Part> parts;               // parts[0] is the trunk (root)
  std::vector<FineRegion> fine_regions;  // where detail is fine (hands, fingers)
  Box bounds;                            // bounding box of every shape, model space
  float scale = 1.0f;                    // height / 1.75 m
};

// Lays out the skeleton and the primitives for validated options (see makeDefaultAvatar).
BodyPlan makeBodyPlan(const DefaultAvatarOptions& options);

// Sets a shape's bounding sphere and detail radius from its other fields.
void finishShape(Shape& shape);

}  // namespace vistel::synth
