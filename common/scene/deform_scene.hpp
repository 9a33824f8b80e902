// DeformScene: the per-frame orchestration of the rigid and deformable components over the
// bodies of one world (avatars and props), shared by vistel-avatar deform, the client and
// the benchmarks (DESIGN.md §1, §3 "Per frame, three steps", §6).
//
// One frame, all in one call (step):
//   rigid skinning of every body (options.skinning: LBS, DQS, the spine lattice or rigid +
//   slerp, in world space; common/anim/skinning_rig.hpp)
//   -> posePrimitives of every body with an implicit model
//   -> Step 1 across all bodies (buildInteractions), or an interaction list received from a
//      server (validated against the bodies; an invalid one is replaced by the local Step 1)
//   -> Steps 2-3 per deformable body (deformSkin, optionally on a TaskPool)
//   -> combined contacts (one PairContact per touching pair of bodies, equal and opposite).
//
// The same frame split for a renderer that skins every body itself on worker threads
// (client/view RoomView and its PostSkinDeformer hook):
//   prepare(time)       one thread: pose skeletons and primitives, Step 1
//   deformBody(i, ...)  any thread, concurrently for different bodies: Steps 2-3 of body i on
//                       the renderer's rigidly skinned vertices (model space, in place);
//                       reads only what prepare() wrote and body i's own state
//   collectContacts()   one thread, after every deformBody of the frame.
//
// Spaces and units: each body's avatar is in its model space; `placement` (a rigid
// transform) takes it to the world, where primitives, interactions, positions returned by
// positions() and forces live. Metres, seconds, newtons, square metres.
//
// Ownership: avatars are shared read-only (std::shared_ptr<const AvatarModel>). Everything
// per frame (postures, skinned and deformed vertices, posed primitives, interaction list,
// deform states with their warm starts and elastic memory, contacts) is owned by the scene
// and sized once by create(): after a warm-up frame with the scene's largest contact, step(),
// prepare(), deformBody() and collectContacts() allocate nothing. Results do not depend on
// the thread count (bit-identical with 1 or N threads).
#pragma once

#include <cstdint>
#include <memory>
#include <span>
#include <string>
#include <vector>

#include <glm/glm.hpp>

#include "common/anim/posture.hpp"
#include "common/anim/skinning.hpp"
#include "common/anim/skinning_rig.hpp"
#include "common/avatar/avatar_model.hpp"
#include "common/base/result.hpp"
#include "common/deform/deform.hpp"
#include "common/deform/interactions.hpp"
#include "common/deform/prop.hpp"

namespace vistel {

// One body of the scene: an avatar (or a prop built as one, see makeBallAvatar) and where
// it stands.
struct SceneBody {
  std::string name;                           // for messages and reports
  std::shared_ptr<const AvatarModel> avatar;  // required; validated by create()
  glm::mat4 placement{1.0f};                  // model -> world, rigid; setPlacement() per frame
  bool deformable = true;  // run Steps 2-3 on it when the avatar has an implicit model (else
                           // its primitives still collide with the others: a rigid body)
};

struct SceneOptions {
  SkinningMethod skinning = SkinningMethod::kDualQuaternion;  // step()'s rigid component;
                                                              // kSpineFfd falls back to DQS
                                                              // on a body without a spine
                                                              // (see skinningRig().warning)
  bool rigid_only = false;  // no deformable component: step() skins and poses primitives
                            // (for props' dynamics) but runs no Step 1-3, deformBody() leaves
                            // vertices as they are
  DeformOptions deform;     // Steps 2-3 settings, the same for every body
  int threads = 1;          // step(): threads skinning and deforming (the caller counts as
                            // one); deformBody() always runs on its caller's thread
  int skin_chunk = 2048;    // vertices per skinning task in step()
};

// One body's contact this frame (after step() or collectContacts()).
struct BodyContactSummary {
  double area = 0.0;       // m^2 of this body's contact faces, every partner (self included);
                           // for a partner against which it measured none (it is rigid or
                           // was not deformed), the partner's measure of their contact
  double self_area = 0.0;  // m^2 of that area in self-contact
  glm::dvec3 force{0.0};   // N: net reaction force from the other bodies (self-contact is
                           // internal); the forces on all bodies sum to zero
  int partner = -1;        // the other body with the largest contact area, or -1
  int partner_count = 0;   // other bodies in contact
  double max_depth = 0.0;  // deepest rigid-pose penetration of a vertex (m)
  bool deformed = false;   // Steps 2-3 ran on it this frame (else everything above is 0)
};

// Wall time of the last step() / prepare() phases, milliseconds.
struct SceneTimings {
  double skin_ms = 0.0;    // rigid skinning (step() only)
  double pose_ms = 0.0;    // skeletons and primitives
  double step1_ms = 0.0;   // interaction list (built or received and validated)
  double deform_ms = 0.0;  // Steps 2-3 over all bodies (step() only)
};

class DeformScene {
 public:
  // Validates every avatar (validateAvatar) and sizes all per-frame state. Fails on a null
  // or invalid avatar, no bodies, more than 65535 bodies, threads < 1 or skin_chunk < 1.
  // Postures start at rest. Cost: O(total vertices), allocates.
  static Result<DeformScene> create(std::vector<SceneBody> bodies,
                                    const SceneOptions& options = {});

  DeformScene(DeformScene&&) noexcept;
  DeformScene& operator=(DeformScene&&) noexcept;
  ~DeformScene();

  int bodyCount() const;
  const SceneBody& body(int index) const;
  const SceneOptions& options() const;
  // Steps 2-3 run on this body (an implicit model, deformable, not rigid_only).
  bool deforms(int index) const;

  // Per-frame inputs. The posture is on the body's skeleton (njoint rotations, translations
  // empty or njoint, all finite); one that does not fit is used as the rest posture and
  // counted (posturesAtRest). Copying a posture of the same size allocates nothing.
  Posture& posture(int index);
  void setPosture(int index, const Posture& posture);
  void setPlacement(int index, const glm::mat4& placement);
  // The body's linear velocity (world m/s; a prop's, from its dynamics) and restitution
  // ([0, 1]), for Step 3's restitution (prop.hpp "The contact law"). Default: still, 1.
  void setMotion(int index, const glm::vec3& velocity, float restitution);

  // The whole frame (see the top of the file). `received`: Step 1's list from a server in
  // this scene's body indices (only `pairs` is read); when it fails validation the scene
  // builds its own list and returns the validation error (the frame is still complete).
  // time: seconds (viscoelastic recovery).
  Status step(double time, const InteractionList* received = nullptr);

  // Split frame, part 1 (one thread): postures -> joints, skinning matrices, posed
  // primitives, Step 1 (`received` as in step()). Marks every body not yet deformed.
  // self_contact = false leaves each body's own pairs out of a list the scene builds (and
  // out of a received one that lacks them), for addSelfInteractions to add for the bodies
  // that deform this frame.
  Status prepare(double time, const InteractionList* received = nullptr, bool self_contact = true);
  // After prepare(..., false): adds the own pairs of the bodies whose `deforms` entry is
  // non-zero (nbody entries; a body left out has none this frame) to this frame's list, so
  // that a room pays self-contact only for the bodies it deforms (own pairs a received list
  // already has are merged, not doubled). Counted in timings().step1_ms. O(those bodies'
  // collide pairs).
  void addSelfInteractions(std::span<const std::uint8_t> deforms);
  // Whether a renderer's skinning of body `index` used what prepare() posed: the same
  // skinning matrices (bind -> posed model space, njoint) and placement, bit for bit.
  bool matchesPrepared(int index, std::span<const glm::mat4> skin,
                       const glm::mat4& placement) const;
  // Whether the last prepare() or step() posed body `index` from exactly this posture (root
  // translation, rotations and translations equal bit for bit; a posture that did not fit
  // was posed at rest, so pass the rest posture then). When true, jointTransforms() and
  // skinMatrices() are what poseSkeleton and skinningMatrices would give for it, so a
  // renderer can take them instead of posing the body a second time. O(njoint).
  bool posedWith(int index, const Posture& posture) const;
  // Split frame, part 2 (any thread; concurrently only for different bodies): Steps 2-3 on
  // body `index`'s rigidly skinned vertices, given and returned in the body's model space
  // (nvert each; normals unit). A body that does not deform, or spans of the wrong size,
  // are left as they are. Single-threaded inside.
  void deformBody(int index, std::span<glm::vec3> positions, std::span<glm::vec3> normals);
  // Split frame, part 3 (one thread): combines the contacts of the bodies deformed since
  // prepare().
  void collectContacts();

  // Results of the last frame. positions/normals: world space (nvert); after step() every
  // body's, after deformBody() that body's deformed ones (bodies deformBody did not see:
  // stale). rigidPositions: step()'s skinning (world).
  std::span<const glm::vec3> positions(int index) const;
  std::span<const glm::vec3> normals(int index) const;
  std::span<const glm::vec3> rigidPositions(int index) const;
  // Posed model-space joint transforms and skinning matrices of the last prepare/step.
  std::span<const glm::mat4> jointTransforms(int index) const;
  std::span<const glm::mat4> skinMatrices(int index) const;
  // The interaction list used by the last frame (empty when rigid_only).
  const InteractionList& interactions() const;
  // Every body as Step 1 sees it this frame (graph and posed primitives; a body without an
  // implicit model has none), e.g. for stepBall (common/deform/prop.hpp).
  std::span<const BodyView> bodyViews() const;
  // Contact pairs between different bodies (equal and opposite), and per-body summaries.
  std::span<const PairContact> contacts() const;
  BodyContactSummary contactSummary(int index) const;
  // The body's deform state (counters, flags, per-partner contacts), or null when it does
  // not deform.
  const DeformState* deformState(int index) const;
  // Carries a body's state over from a scene this one replaces (see carryDeformState):
  // false when the body does not deform or the state is another mesh's.
  bool carryState(int index, const DeformState& from);
  // Replaces a body's elastic memory with another site's, sampled age_s ago (see
  // adoptElasticMemory): false when the body does not deform or the memory is another mesh's.
  bool adoptMemory(int index, std::span<const float> memory, float age_s = 0.0f);
  // The body's rigid component as create() built it for options.skinning: the method that
  // runs (rig.method) and why it differs from the requested one (rig.warning, e.g. a ball
  // or a skeleton without a spine under kSpineFfd).
  const SkinningRig& skinningRig(int index) const;
  // Bodies whose posture did not fit in the last frame.
  int posturesAtRest() const;
  const SceneTimings& timings() const;

 private:
  struct Impl;
  explicit DeformScene(std::unique_ptr<Impl> impl);
  std::unique_ptr<Impl> impl_;
};

// A prop as a scene body's avatar: the ball of makeBall (one joint "ball", an icosphere skin
// and its implicit model). Fails on out-of-range parameters.
Result<std::shared_ptr<const AvatarModel>> makeBallAvatar(const BallSpec& spec,
                                                          std::string name = "ball");

}  // namespace vistel
