// Free-form deformation of the torso along the spine (DESIGN.md §4: "a free-form
// deformation lattice along the spine may shape the torso"), the paper's alternative to
// blending the torso between bone transforms.
//
// The lattice is one-dimensional: a chain of control frames along the spine (the skeleton's
// chain from the pelvis to the neck, e.g. hips-spine-chest-upper_chest-neck, ending at the
// head joint). Its control points are the chain's joint origins; the uniform Catmull-Rom
// spline through them (end points reflected) is the spine curve C(u), u in [0, n] for n
// chain joints (C(k) is joint k's origin, C(n) the head's). Each control frame carries the
// rotation of one chain joint, placed at the middle of that joint's bone (u = k + 1/2); the
// frame rotation R(u) is the normalised uniform cubic B-spline blend of the frames'
// quaternions (smooth, non-negative weights). A torso vertex keeps its lattice coordinates
// (u, and its offset from C(u) in the rest posture):
//   p' = C'(u) + R(u) (p - C(u))
// so the torso sweeps smoothly along the bent spine with rigid cross-sections (in the
// manner of sweep-based deformers, e.g. Hyun et al. 2005, and of lattice FFD, Sederberg &
// Parry 1986, whose control points here follow the spine joints). u is the parameter of the
// vertex's closest point on the rest curve (clamped to the ends).
//
// Which vertices: a vertex's torso weight is the sum of its skin weights on the chain
// joints. Torso weight 1: the sweep alone; 0: dual-quaternion skinning (Kavan et al. 2007);
// in between (shoulders, groin, the neck below the head) the sweep's rigid transform enters
// the vertex's dual-quaternion blend with the torso weight, beside its other joints.
//
// Limits: the cross-sections are rigid, so where the spine bends tighter than a vertex's
// distance from it (the front of the lower belly in a deep bow) neighbouring sections
// cross and the skin folds there, as with any sweep; the deformable component is what
// rounds such creases.
//
// The lattice is built once per mesh (buildSpineLattice: allocates, O(nvert * n)); per frame
// poseSpineLattice (O(n), no allocation) then skinSpineLattice (O(k) per vertex, no
// allocation, any sub-range of vertices on any thread).
#pragma once

#include <array>
#include <cstdint>
#include <span>
#include <string>
#include <vector>

#include <glm/glm.hpp>
#include <glm/gtc/quaternion.hpp>

#include "common/anim/skeleton.hpp"
#include "common/anim/skin_mesh.hpp"
#include "common/math/dual_quat.hpp"

namespace vistel {

// Most joints a spine chain may have (a longer chain is refused with a message).
inline constexpr int kMaxSpineJoints = 15;

// A torso vertex's lattice coordinates: the four control points and four control frames
// whose B-spline weights give C(u) and R(u), and the rest curve point C(u).
struct SpineCoord {
  std::array<std::uint8_t, 4> point{};  // control point indices (0..n)
  std::array<float, 4> point_w{};       // their weights (sum 1; some negative)
  std::array<std::uint8_t, 4> frame{};  // control frame indices (0..n-1)
  std::array<float, 4> frame_w{};       // their weights (non-negative, sum 1)
  glm::vec3 anchor{0.0f};               // C(u) at rest, model space
};

struct SpineLattice {
  // The chain, pelvis first (n joints, 2..kMaxSpineJoints); empty when there is no spine
  // (then every vertex is skinned with dual quaternions and `warning` says why).
  std::vector<int> chain;
  int end_joint = -1;                  // the head: the curve's last control point
  std::vector<glm::vec3> rest_points;  // control points at rest (n + 1), model space
  std::vector<std::uint8_t> in_chain;  // 1 for chain joints (njoint)
  std::vector<float> torso;            // torso weight per vertex (nvert), 0..1
  std::vector<SpineCoord> coords;      // lattice coordinates per vertex (nvert; used
                                       // where torso > 0)
  std::string warning;                 // why there is no lattice, or empty
  int torso_vertices = 0;              // vertices with torso weight > 0

  bool empty() const { return chain.empty(); }
};

// Builds the lattice of a validated skeleton and skin (joints < njoint, weights valid).
// head_joint: the head (e.g. a joint map's canonical "head"); -1 = find it: a joint named
// "head" in any case, else the shallowest joint whose name contains "head". The chain is the
// head's ancestors from the topmost one with skin weight down to the head's parent. No head,
// fewer than two chain joints, a chain longer than kMaxSpineJoints, or no skin weight on it:
// an empty lattice whose `warning` names the reason (the caller falls back to DQS).
SpineLattice buildSpineLattice(const Skeleton& skeleton, const SkinMesh& mesh, int head_joint = -1);

// The lattice posed for one frame: control points and frames (fixed size, no allocation).
struct SpineLatticePose {
  int points = 0;                                      // n + 1
  std::array<glm::vec3, kMaxSpineJoints + 1> point{};  // posed control points
  std::array<glm::quat, kMaxSpineJoints> frame{};      // posed frame rotations (one
                                                       // hemisphere along the chain)
};

// Poses the lattice from the joints' dual quaternions (njoint: bind -> posed, see
// toDualQuats). An empty lattice gives an empty pose.
void poseSpineLattice(const SpineLattice& lattice, std::span<const DualQuat> skin,
                      SpineLatticePose& out);

// The posed spine curve C'(u) (u clamped to [0, n]); posed with identity dual quaternions,
// the rest curve. An empty pose gives the origin. For tests and tools; O(1).
glm::vec3 spineCurvePoint(const SpineLatticePose& pose, float u);

// Posed positions and normals (model space) of vertices [first, first + out.size()):
// torso vertices by the sweep (blended into DQS by their torso weight), the others exactly
// as skinDualQuaternion. skin: one unit dual quaternion per joint; pose: this frame's
// poseSpineLattice. Allocates nothing.
void skinSpineLattice(const SkinMesh& mesh, const SpineLattice& lattice,
                      std::span<const DualQuat> skin, const SpineLatticePose& pose,
                      std::size_t first, std::span<glm::vec3> out_positions,
                      std::span<glm::vec3> out_normals);

}  // namespace vistel
