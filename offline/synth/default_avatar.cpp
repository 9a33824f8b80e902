// Assembles the default avatar: body plan -> implicit body -> polygonization ->
// sizing-driven simplification -> relaxation -> skin weights -> AvatarModel.
#include "offline/synth/default_avatar.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

#include "offline/synth/body_plan.hpp"
#include "offline/synth/default_look.hpp"
#include "offline/synth/implicit_body.hpp"
#include "offline/synth/polygonize.hpp"
#include "offline/synth/relax.hpp"
#include "offline/synth/simplify.hpp"
#include "offline/synth/skin_weights.hpp"

namespace vistel {
namespace {

// Polygonization cells for a 1.75 m body: 16 mm on the body, 4 mm at the hands, 2 mm at
// the fingers (so that the 4 mm gaps between fingers are never bridged by a cell).
constexpr float kCoarseCell = 0.016f;
// Sizing: a primitive's detail radius grows by this much per metre away from it, and
// the sizing is capped here (broad parts of the body).
constexpr float kSizingSlope = 0.5f;
constexpr float kSizingCap = 0.022f;
constexpr int kRelaxRounds = 4;

Status validateOptions(const DefaultAvatarOptions& o) {
  const auto check = [](const char* name, double value, double lo, double hi) -> Status {
    if (!(value >= lo && value <= hi)) {
      return fail("default avatar option {} = {} is outside [{}, {}]", name, value, lo, hi);
    }
    return {};
  };
  if (Status s = check("height", o.height, 1.2, 2.2); !s) return s;
  if (Status s = check("girth", o.girth, 0.8, 1.25); !s) return s;
  if (Status s = check("arm_angle_deg", o.arm_angle_deg, 30.0, 55.0); !s) return s;
  if (Status s = check("finger_spread_deg", o.finger_spread_deg, 4.0, 12.0); !s) return s;
  if (Status s = check("target_vertices", o.target_vertices, 4000, 40000); !s) return s;
  return {};
}

// Desired edge length per vertex: the body's sizing field, scaled so that a mesh following
// it has about `target` vertices (a vertex per sqrt(3)/2 L^2 of area).
std::vector<float> desiredEdgeLengths(const synth::TriangleMesh& mesh,
                                      const synth::ImplicitBody& body, float scale, int target) {
  std::vector<float> lengths(mesh.positions.size());
  for (std::size_t i = 0; i < lengths.size(); ++i) {
    lengths[i] = body.sizing(mesh.positions[i], kSizingSlope, kSizingCap * scale);
  }
  double vertices_at_unit_scale = 0.0;
  for (std::size_t t = 0; t < mesh.indices.size(); t += 3) {
    const glm::vec3& a = mesh.positions[mesh.indices[t]];
    const glm::vec3& b = mesh.positions[mesh.indices[t + 1]];
    const glm::vec3& c = mesh.positions[mesh.indices[t + 2]];
    const double area = 0.5 * glm::length(glm::cross(b - a, c - a));
    const double l =
        (lengths[mesh.indices[t]] + lengths[mesh.indices[t + 1]] + lengths[mesh.indices[t + 2]]) /
        3.0;
    vertices_at_unit_scale += area / (0.5 * std::sqrt(3.0) * l * l);
  }
  const auto k = static_cast<float>(std::sqrt(vertices_at_unit_scale / target));
  for (float& l : lengths) l *= k;
  return lengths;
}

}  // namespace

Result<AvatarModel> makeDefaultAvatar(const DefaultAvatarOptions& options) {
  if (Status s = validateOptions(options); !s) return s.error();
  const synth::BodyPlan plan = synth::makeBodyPlan(options);
  const synth::ImplicitBody body(plan);

  // Skin: polygonize, simplify to the target count along the sizing field, relax.
  synth::PolygonizeSettings poly;
  poly.domain = plan.bounds;
  poly.coarse_cell = kCoarseCell * plan.scale;
  poly.fine_regions = plan.fine_regions;
  poly.shape_scale = plan.scale;
  synth::TriangleMesh mesh = synth::polygonize(body, poly);
  synth::SimplifySettings simplify;
  simplify.target_vertices = options.target_vertices;
  simplify.edge_length = desiredEdgeLengths(mesh, body, plan.scale, options.target_vertices);
  synth::simplify(mesh, simplify);
  synth::relax(mesh, body, kRelaxRounds);

  // Stand on y = 0 exactly.
  float lowest = std::numeric_limits<float>::max();
  for (const glm::vec3& p : mesh.positions) lowest = std::min(lowest, p.y);
  const glm::vec3 lift(0.0f, -lowest, 0.0f);
  for (glm::vec3& p : mesh.positions) p += lift;

  // Skin weights: each vertex belongs to the bone of its closest primitive.
  const std::size_t joint_count = plan.joint_names.size();
  std::vector<int> labels(mesh.positions.size());
  for (std::size_t i = 0; i < labels.size(); ++i) {
    labels[i] =
        plan.shapes[static_cast<std::size_t>(body.closestShape(mesh.positions[i] - lift))].joint;
  }
  std::vector<synth::BoneSegment> bones(joint_count);
  for (std::size_t j = 0; j < joint_count; ++j) {
    bones[j] = {plan.joint_positions[j] + lift, plan.bone_tips[j] + lift};
  }
  Result<synth::SkinWeights> weights =
      synth::computeSkinWeights(mesh, labels, plan.joint_parents, bones);
  if (!weights) return withContext("default avatar", weights.error());

  // Skeleton: translation-only rest transforms (joint frames parallel to model space).
  AvatarModel avatar;
  avatar.name = "vistel-default";
  Skeleton& skeleton = avatar.skeleton;
  skeleton.names = plan.joint_names;
  skeleton.parents = plan.joint_parents;
  skeleton.rest_local.resize(joint_count);
  for (std::size_t j = 0; j < joint_count; ++j) {
    const int parent = plan.joint_parents[j];
    skeleton.rest_local[j].translation =
        parent < 0
            ? plan.joint_positions[j] + lift
            : plan.joint_positions[j] - plan.joint_positions[static_cast<std::size_t>(parent)];
  }
  computeInverseBind(skeleton);

  SkinMesh& skin = avatar.skin;
  skin.positions = std::move(mesh.positions);
  skin.indices = std::move(mesh.indices);
  skin.normals.resize(skin.positions.size());
  computeVertexNormals(skin.positions, skin.indices, skin.normals);
  skin.influences = weights->influences;
  skin.joints = std::move(weights->joints);
  skin.weights = std::move(weights->weights);
  avatar.look = makeDefaultLook(avatar);  // clothes and skin, a texture drawn by code

  if (Status s = validateAvatar(avatar); !s) return withContext("default avatar", s.error());
  return avatar;
}

}  // namespace vistel
