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
// rigid that frame and counted.
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

#include "client/view/room_view.hpp"
#include "common/base/result.hpp"
#include "common/scene/deform_scene.hpp"

namespace vistel {

class RoomDeformer {
 public:
  // options.threads is ignored (the view's workers do the work); the skinning method is
  // the view's (dual quaternions).
  explicit RoomDeformer(const DeformOptions& options = {});
  ~RoomDeformer();
  RoomDeformer(const RoomDeformer&) = delete;
  RoomDeformer& operator=(const RoomDeformer&) = delete;

  // Before view.render(views): takes this frame's bodies, postures and placements. A
  // rebuild that fails (an avatar that does not validate) leaves every body rigid until
  // the set of bodies changes again, and is returned.
  Status sync(std::span<const MemberView> views, RoomView& view);
  // After sync: poses the bodies and runs Step 1. time: seconds (viscoelastic recovery).
  // `received`: a Step 1 list in this scene's body indices (see bodyOf); when it fails
  // validation the scene's own list is used and the error returned (the frame is still
  // complete).
  Status prepare(double time, const InteractionList* received = nullptr);
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
  // Bodies the view skinned differently from prepare() in the last frame (left rigid).
  int skippedLastFrame() const { return skipped_reported_; }
  // Scene rebuilds so far.
  int rebuilds() const { return rebuilds_; }

 private:
  class Hook;
  struct Key {
    std::uint32_t id = 0;
    const AvatarModel* avatar = nullptr;
    friend bool operator==(const Key&, const Key&) = default;
  };

  // What the hooks on the view share with this object (they may outlive it).
  struct Shared {
    std::optional<DeformScene> scene;
    std::atomic<int> skipped{0};
  };

  Status rebuild(std::span<const MemberView> views, RoomView& view);

  DeformOptions options_;
  std::shared_ptr<Shared> shared_;
  std::vector<Key> keys_;                     // the scene's bodies, in order
  std::vector<Key> wanted_;                   // scratch: this frame's bodies
  std::vector<int> view_body_;                // views index -> body (this frame)
  std::vector<std::shared_ptr<Hook>> hooks_;  // per body, installed on the view
  int skipped_reported_ = 0;
  int rebuilds_ = 0;
};

}  // namespace vistel
