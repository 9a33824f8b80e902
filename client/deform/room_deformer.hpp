// RoomDeformer: the deformable component on everything a site client draws (DESIGN.md §3,
// §6). Every member view whose avatar carries an implicit model (avatars built with
// `vistel-avatar build`, the default avatar, balls) becomes a body of one DeformScene; each
// frame the client calls, before RoomView::render,
//   sync(views, view)         bodies, postures and placements in (a PostSkinDeformer per
//                             body installed on the view when the bodies change)
//   prepare(time[, received]) skeletons and primitives posed, Step 1 (the server's list
//                             when given and valid, else the scene's own)
// and after it
//   finish()                  contacts and forces per body.
// The view's skinning workers then run Steps 2-3 of each body on its rigidly skinned
// vertices (DeformScene::deformBody), concurrently for different bodies. A body whose
// skinning does not match what prepare() posed (the view drew it at rest, say) is left
// rigid that frame and counted. Each body is posed once per frame: prepare() poses it
// for Step 1 and the view takes those matrices (PostSkinDeformer::copyPose).
//
// Level of detail (common/scene/deform_lod.hpp, setLod): after Step 1, prepare() chooses every
// body's tier from its distance to the viewer (setViewer; by default the self member's seat) and
// its contacts this frame: kFull bodies deform every frame, kReduced ones on one frame in
// reduced_every and in between are drawn with the offsets of their last deformation
// (model space) added to their rigid skinning, kRigid ones are skinned only. With the
// view's gpu_skinning both kinds are skinned in the vertex shader (their hooks say
// needsVertices() == false, or give the offsets through offsetsOnly()). A body that has
// no offsets yet (it just became kReduced) deforms at once. lastStats() counts them.
//
// Dents shared between sites (proto/SESSION.md §2.5; client/deform/dent_sync.hpp decides
// what to send and what to take): recordDents gives a body's elastic memory as a record,
// adoptDents replaces a body's memory with another site's (at once, or when the body joins
// the scene: a record for a view without a body yet waits while the view is drawn).
//
// The scene is rebuilt (allocating) only when the set of (view id, avatar) changes: a
// member joins or leaves, an avatar arrives, a prop appears; other frames allocate
// nothing once warm. Not thread-safe: one client thread calls prepare/finish. The hooks
// stay valid if the view outlives this object (they then leave vertices rigid).
#pragma once

#include <atomic>
#include <cstdint>
#include <memory>
#include <optional>
#include <span>
#include <vector>

#include "client/deform/part_forces.hpp"
#include "client/view/room_view.hpp"
#include "common/base/result.hpp"
#include "common/scene/deform_lod.hpp"
#include "common/scene/deform_scene.hpp"
#include "common/scene/dent_record.hpp"

namespace vistel {

// The last frame's work (valid after finish()).
struct DeformFrameStats {
  int full = 0;                // bodies at full rate (tier kFull)
  int reduced = 0;             // bodies at the lower rate (kReduced): deformed this frame or held
  int rigid = 0;               // bodies skinned only (kRigid)
  int deformed = 0;            // bodies whose Steps 2-3 ran this frame
  int held = 0;                // kReduced bodies drawn with their held offsets this frame
  double prepare_ms = 0.0;     // wall time of prepare(): posing, Step 1, tiers
  double pose_ms = 0.0;        // of which posing skeletons and primitives
  double step1_ms = 0.0;       // of which Step 1 (the interaction list)
  double deform_cpu_ms = 0.0;  // Steps 2-3 and held offsets, summed over the worker threads
};

class RoomDeformer {
 public:
  // options.threads is ignored (the view's workers do the work); the skinning method is
  // the view's (dual quaternions).
  explicit RoomDeformer(const DeformOptions& options = {});
  ~RoomDeformer();
  RoomDeformer(const RoomDeformer&) = delete;
  RoomDeformer& operator=(const RoomDeformer&) = delete;

  // Before view.render(views): takes this frame's bodies, postures and placements. When the
  // set of bodies changed the scene is rebuilt, and every body that stays (same view id and
  // avatar) carries its warm starts and elastic memory (dents) over. A rebuild that fails (an
  // avatar that does not validate) leaves every body rigid until the set of bodies changes again,
  // and is returned.
  Status sync(std::span<const MemberView> views, RoomView& view);
  // After sync, before prepare: a view's body's velocity (world m/s) and restitution, for the
  // contact forces' restitution (DeformScene::setMotion; a prop's from its dynamics). Bodies
  // not given one this frame are still and elastic. False when the view is not a body.
  bool setMotion(std::uint32_t view_id, const glm::vec3& velocity, float restitution);
  // After sync: poses the bodies and runs Step 1. time: seconds (viscoelastic recovery).
  // `received`: a Step 1 list in this scene's body indices (see bodyOf); when it fails
  // validation the scene's own list is used and the error returned (the frame is still
  // complete).
  Status prepare(double time, const InteractionList* received = nullptr);
  // Level of detail from the next prepare() on (invalid settings are refused and the
  // previous ones kept). Default: DeformLodSettings{} (on).
  Status setLod(const DeformLodSettings& settings);
  const DeformLodSettings& lod() const { return lod_; }
  // Where the viewer is (room space) for the level of detail; nullopt (the default): the
  // self member's seat, or the room's origin when no member is the self.
  void setViewer(std::optional<glm::vec3> p_room) { viewer_override_ = p_room; }
  // After view.render(views): combines the contacts of the bodies deformed this frame.
  void finish();

  // The scene body of a view id, or -1 (not drawn, or its avatar has no implicit model).
  int bodyOf(std::uint32_t view_id) const;
  int bodyCount() const;
  // Step 1's view of every body (graphs; posed primitives as of the last prepare()).
  std::span<const BodyView> bodyViews() const;
  // This frame's contact of a view's body (area, net force; for force-feedback devices),
  // or nullopt when it is not a body. Valid after finish().
  std::optional<BodyContactSummary> contact(std::uint32_t view_id) const;
  // Step 3's per-vertex results of a view's body this frame, for computePartForces
  // (client/deform/part_forces.hpp; forces in the body's model space), or nullopt when it is
  // not a body or was not deformed this frame (a lower-rate or rigid tier: no contact
  // measured). The spans stay valid until the next prepare() or sync(). Valid after finish().
  std::optional<PartForceInput> partForceInput(std::uint32_t view_id) const;
  // Bodies the view skinned differently from prepare() in the last frame (left rigid).
  int skippedLastFrame() const { return skipped_reported_; }
  // The tier of a view's body this frame (after prepare()), or nullopt when not a body.
  std::optional<DeformTier> tier(std::uint32_t view_id) const;
  const DeformFrameStats& lastStats() const { return stats_; }
  // Scene rebuilds so far.
  int rebuilds() const { return rebuilds_; }

  // A view's body's elastic memory (dents) as a record; false when it is not a body that
  // deforms. Call between frames (after finish(), before the next sync()).
  bool recordDents(std::uint32_t view_id, DentRecord& out) const;
  // Another site's record for a view's body, sampled age_s ago, replaces its memory, now when
  // the view is a body of this scene, else when it becomes one (the newest record per view
  // waits while that view is drawn, and ages by the prepare() times in between); viscoelastic
  // dents recover over the age (adoptElasticMemory). Fails on a malformed record, one for
  // another vertex count than the body's skin, or a negative age. Call between frames.
  Status adoptDents(std::uint32_t view_id, const DentRecord& record, double age_s = 0.0);
  // Records waiting for their views to become bodies.
  int pendingDents() const { return static_cast<int>(pending_dents_.size()); }
  // Whether the bodies of two views were in contact this frame (either measured it; valid
  // after finish()).
  bool touching(std::uint32_t view_a, std::uint32_t view_b) const;

 private:
  class Hook;
  struct Key {
    std::uint32_t id = 0;
    const AvatarModel* avatar = nullptr;
    friend bool operator==(const Key&, const Key&) = default;
  };

  // What a hook does to its body this frame (decided by prepare()).
  enum class Action : std::uint8_t { kDeform, kDeformAndHold, kHold, kRigid };

  // What the hooks on the view share with this object (they may outlive it). The
  // per-body vectors are written by prepare() (this thread) and by body i's hook only
  // (held_*[i]) while the view's workers run.
  struct Shared {
    std::optional<DeformScene> scene;
    std::atomic<int> skipped{0};
    std::atomic<int> deformed{0};
    std::atomic<int> held{0};
    std::atomic<std::int64_t> deform_ns{0};
    std::vector<Action> action;                    // (nbody)
    std::vector<std::uint8_t> held_valid;          // (nbody) held offsets are usable
    std::vector<std::uint64_t> held_generation;    // (nbody) SkinOffsets::generation
    std::vector<std::vector<glm::vec3>> held_pos;  // (nbody)(nvert) deformed - rigid, model
    std::vector<std::vector<glm::vec3>> held_nrm;  // (nbody)(nvert) normal offsets, model
  };

  Status rebuild(std::span<const MemberView> views, RoomView& view);
  // Writes a record, sampled age_s ago, into a body's memory.
  Status applyDents(int body, const DentRecord& record, double age_s);

  DeformOptions options_;
  std::shared_ptr<Shared> shared_;
  std::vector<Key> keys_;                     // the scene's bodies, in order
  std::vector<Key> wanted_;                   // scratch: this frame's bodies
  std::vector<int> view_body_;                // views index -> body (this frame)
  std::vector<std::shared_ptr<Hook>> hooks_;  // per body, installed on the view
  int skipped_reported_ = 0;
  int rebuilds_ = 0;
  // Level of detail.
  DeformLodSettings lod_;
  std::optional<glm::vec3> viewer_override_;
  glm::vec3 self_position_{0.0f};  // this frame's self member's seat (sync)
  bool have_self_ = false;
  std::int64_t frame_ = 0;
  DeformLodScratch lod_scratch_;
  std::vector<glm::vec3> body_positions_;   // (nbody) room space
  std::vector<std::uint8_t> in_contact_;    // (nbody)
  std::vector<std::uint8_t> deforms_now_;   // (nbody) its Steps 2-3 run this frame
  std::vector<DeformTier> tiers_;           // (nbody) this frame
  std::vector<DeformTier> previous_tiers_;  // (nbody) last frame (empty after a rebuild)
  DeformFrameStats stats_;
  // Dents for views that are not bodies yet, and scratch.
  struct PendingDents {
    std::uint32_t view_id = 0;
    DentRecord record;
    double age_s = 0.0;       // when adopted
    double adopted_at = 0.0;  // last_time_ then
  };
  std::vector<PendingDents> pending_dents_;
  std::vector<float> dent_memory_;
  double last_time_ = 0.0;  // the last prepare()'s time
};

}  // namespace vistel
