#include "client/deform/room_deformer.hpp"

#include <algorithm>
#include <utility>

namespace vistel {

// Steps 2-3 of one body on the view's skinning worker (see the header).
class RoomDeformer::Hook final : public PostSkinDeformer {
 public:
  Hook(std::shared_ptr<Shared> shared, int body) : shared_(std::move(shared)), body_(body) {}

  void deform(const SkinFrame& frame) override {
    std::optional<DeformScene>& scene = shared_->scene;
    if (!scene || body_ >= scene->bodyCount()) return;
    if (!scene->matchesPrepared(body_, frame.skin, frame.placement)) {
      shared_->skipped.fetch_add(1, std::memory_order_relaxed);
      return;
    }
    scene->deformBody(body_, frame.positions, frame.normals);
  }

 private:
  std::shared_ptr<Shared> shared_;
  int body_;
};

RoomDeformer::RoomDeformer(const DeformOptions& options)
    : options_(options), shared_(std::make_shared<Shared>()) {}

RoomDeformer::~RoomDeformer() {
  // Hooks still on a view find no scene and leave vertices rigid.
  shared_->scene.reset();
}

Status RoomDeformer::rebuild(std::span<const MemberView> views, RoomView& view) {
  for (const Key& k : keys_) view.setDeformer(k.id, nullptr);
  keys_.clear();
  hooks_.clear();
  shared_->scene.reset();
  ++rebuilds_;
  if (wanted_.empty()) return {};
  std::vector<SceneBody> bodies;
  bodies.reserve(wanted_.size());
  for (const MemberView& v : views) {
    if (v.avatar && v.avatar->implicit) {
      bodies.push_back(SceneBody{v.name, v.avatar, v.placement, true});
    }
  }
  SceneOptions options;
  options.deform = options_;
  Result<DeformScene> scene = DeformScene::create(std::move(bodies), options);
  if (!scene) return withContext("the room's deformable scene", scene.error());
  shared_->scene.emplace(std::move(*scene));
  keys_ = wanted_;
  for (std::size_t i = 0; i < keys_.size(); ++i) {
    hooks_.push_back(std::make_shared<Hook>(shared_, static_cast<int>(i)));
    view.setDeformer(keys_[i].id, hooks_.back());
  }
  return {};
}

Status RoomDeformer::sync(std::span<const MemberView> views, RoomView& view) {
  skipped_reported_ = shared_->skipped.exchange(0, std::memory_order_relaxed);
  // This frame's bodies: the views whose avatars have an implicit model, in view order.
  wanted_.clear();
  view_body_.assign(views.size(), -1);
  for (std::size_t i = 0; i < views.size(); ++i) {
    const MemberView& v = views[i];
    if (v.avatar && v.avatar->implicit) {
      view_body_[i] = static_cast<int>(wanted_.size());
      wanted_.push_back({v.id, v.avatar.get()});
    }
  }
  if (wanted_ != keys_) {
    if (Status st = rebuild(views, view); !st) {
      keys_ = wanted_;  // not retried every frame: a new set of bodies tries again
      return st;
    }
  }
  std::optional<DeformScene>& scene = shared_->scene;
  if (!scene) return {};
  for (std::size_t i = 0; i < views.size(); ++i) {
    const int body = view_body_[i];
    if (body < 0) continue;
    scene->setPosture(body, views[i].posture);
    scene->setPlacement(body, views[i].placement);
  }
  return {};
}

Status RoomDeformer::prepare(double time, const InteractionList* received) {
  if (!shared_->scene) return {};
  return shared_->scene->prepare(time, received);
}

void RoomDeformer::finish() {
  if (shared_->scene) shared_->scene->collectContacts();
}

int RoomDeformer::bodyOf(std::uint32_t view_id) const {
  if (!shared_->scene) return -1;
  const auto found =
      std::find_if(keys_.begin(), keys_.end(), [&](const Key& k) { return k.id == view_id; });
  return found == keys_.end() ? -1 : static_cast<int>(found - keys_.begin());
}

int RoomDeformer::bodyCount() const { return shared_->scene ? shared_->scene->bodyCount() : 0; }

std::span<const BodyView> RoomDeformer::bodyViews() const {
  return shared_->scene ? shared_->scene->bodyViews() : std::span<const BodyView>();
}

std::optional<BodyContactSummary> RoomDeformer::contact(std::uint32_t view_id) const {
  const int body = bodyOf(view_id);
  if (body < 0) return std::nullopt;
  return shared_->scene->contactSummary(body);
}

}  // namespace vistel
