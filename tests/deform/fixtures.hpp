// Test bodies and a small scene runner for the deformable component: a two-bone skinned
// tube "arm" (as tests/anim/skinning_test.cpp), balls, and real avatars when present.
#pragma once

#include <memory>
#include <optional>
#include <string>
#include <vector>

#include <glm/glm.hpp>

#include "common/anim/posture.hpp"
#include "common/anim/skinning.hpp"
#include "common/avatar/avatar_model.hpp"
#include "common/deform/deform.hpp"
#include "common/deform/interactions.hpp"
#include "common/deform/prop.hpp"
#include "common/motion/joint_map.hpp"
#include "offline/build/build_model.hpp"

namespace vistel::test {

// The arm's primitive map: cone-spheres for the two bones, an elbow sphere and an elbow
// bone on the outside of the bend (-Y; the forearm bends towards +Y about +Z).
std::string armMapToml(std::string_view material = "");

// A tube along +X: upper arm 0..L (joint "upper"), forearm L..2L (joint "fore"), an end
// joint "tip" at 2L; weights blend linearly across the elbow over +-blend.
AvatarModel makeArmAvatar(float length = 0.3f, float radius = 0.04f, float blend = 0.06f,
                          int rings = 60, int sides = 24);

// One body of a test scene: static parts, its posture and placement, per-frame buffers.
struct Body {
  std::string name;
  Skeleton skeleton;
  SkinMesh mesh;
  ImplicitModel model;
  glm::mat4 placement{1.0f};
  Posture posture;
  bool deform = true;        // run Steps 2-3 on it
  glm::vec3 velocity{0.0f};  // its BodyView's motion (Step 3's restitution)
  float restitution = 1.0f;

  std::vector<glm::mat4> model_xf, skin_xf;
  std::vector<DualQuat> dq;
  std::vector<glm::vec3> rigid_pos, rigid_nrm;
  PosedPrimitives posed;
  DeformState state;

  void init();  // sizes the buffers and the deform state
  void pose();  // rigid component + posed primitives
  DeformInput input(double time) const;
};

std::unique_ptr<Body> armBody(std::string_view material = "");
std::unique_ptr<Body> ballBody(const BallSpec& spec, const glm::vec3& centre);

// Bodies stepped together: pose all, Step 1 across them, Steps 2-3 on each.
struct Scene {
  std::vector<Body*> bodies;
  std::vector<BodyView> views;
  InteractionScratch scratch;
  InteractionList list;
  std::vector<PairContact> contacts;
  std::vector<const DeformState*> states;
  DeformOptions options;
  TaskPool* pool = nullptr;

  void step(double time);
};

// A real avatar with its implicit model built from the default humanoid map: "default"
// (offline/synth makeDefaultAvatar) or "makehuman" (the shared glb). Built once per process
// and kept (a static cache); null, with a test failure, when it cannot be made (check that
// the shared file exists before asking for "makehuman").
struct RealAvatar {
  AvatarModel avatar;
  std::vector<JointMap> maps;
  const JointMap* map = nullptr;
  ImplicitModel model;
  BuildReport report;
};
// With ":free" appended ("makehuman:free"), the model is built with its free vertices left
// free (BuildOptions::adopt_free_vertices off), as builds before adoption.
const RealAvatar* realAvatar(const std::string& which);

// A scene body of a real avatar (a copy of its cached model), in the rest posture.
std::unique_ptr<Body> realBody(const RealAvatar& avatar);

// Elbow flexion of the arm (radians, about +Z: the forearm turns towards +Y).
void bendArm(Body& arm, float angle);

// Largest |deformed - rigid| over a body's vertices.
float maxDisplacement(const Body& b);

// A calibrated body at rest: every limb and joint vertex lies on its field's surface
// (w_v D_v = iso within 1e-5), and one scene step of the body alone moves no vertex (1e-5 m),
// leaves none unsolved and finds no contact. Failures name `name` and the vertex.
void expectRestsExactly(Body& body, const std::string& name);

// A rigid ball of `radius` brought in along vertex v's rigid normal (from 6 cm out in 1 mm
// steps, then by halves to 0.01 mm) until it first touches the body's posed primitives
// (stepBall, as the server decides contact): the mesh's deepest vertex inside the ball then,
// and how deep (m; negative: a gap). Nothing where v is in a concave place the ball cannot
// reach along the normal (a vertex already inside it 6 cm out). The body must be posed.
struct BallTouch {
  float depth = 0.0f;
  int vertex = -1;
};
std::optional<BallTouch> rigidBallTouch(const Body& body, int v, float radius);

// A soft ball (3e4 Pa/m, r 0.1 m) placed 2 cm into a real avatar's skin along the outward
// normal at vertex v; one scene step. The body's share of the overlap (its deepest contact
// vertex's move over both bodies' deepest moves) against the stiffness ratio
// k_ball / (k_ball + k_body), and the two contact areas (Step 3).
struct SoftBallShare {
  float body_move = 0.0f, ball_move = 0.0f;
  float expected = 0.0f;  // the body's share by the stiffness ratio
  double area_body = 0.0, area_ball = 0.0;
  bool free_site = false;  // v is a free vertex
  float share() const {
    const float total = body_move + ball_move;
    return total > 0.0f ? body_move / total : 0.0f;
  }
};
SoftBallShare softBallAt(const RealAvatar& avatar, int v);

}  // namespace vistel::test
