#include "client/deform/room_deformer.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <utility>

namespace vistel {

namespace {
using Clock = std::chrono::steady_clock;
// Generations of held offsets, unique in the process (SkinOffsets::generation).
std::atomic<std::uint64_t> g_offsets_generation{0};
}  // namespace

// Steps 2-3 of one body on the view's skinning worker (see the header).
class RoomDeformer::Hook final : public PostSkinDeformer {
 public:
  Hook(std::shared_ptr<Shared> shared, int body) : shared_(std::move(shared)), body_(body) {}

  // The scene's pose of this body, when prepare() posed the same posture.
  bool copyPose(const Posture& posture, std::span<glm::mat4> joint_model,
                std::span<glm::mat4> skin) override {
    const std::optional<DeformScene>& scene = shared_->scene;
    if (!scene || body_ >= scene->bodyCount() || !scene->posedWith(body_, posture)) return false;
    const std::span<const glm::mat4> joints = scene->jointTransforms(body_);
    const std::span<const glm::mat4> matrices = scene->skinMatrices(body_);
    if (joints.size() != joint_model.size() || matrices.size() != skin.size()) return false;
    std::copy(joints.begin(), joints.end(), joint_model.begin());
    std::copy(matrices.begin(), matrices.end(), skin.begin());
    return true;
  }

  // Whether deform() would touch the vertices this frame (a rigid-tier body: no).
  bool needsVertices() override {
    const Shared& shared = *shared_;
    if (!shared.scene || body_ >= shared.scene->bodyCount()) return false;
    const auto b = static_cast<std::size_t>(body_);
    return b >= shared.action.size() || shared.action[b] != Action::kRigid;
  }

  // A lower-rate body between deformations: its held offsets, for the GPU to add.
  bool offsetsOnly(SkinOffsets& out) override {
    Shared& shared = *shared_;
    if (!shared.scene || body_ >= shared.scene->bodyCount()) return false;
    const auto b = static_cast<std::size_t>(body_);
    if (b >= shared.action.size() || shared.action[b] != Action::kHold ||
        shared.held_valid[b] == 0 || shared.held_pos[b].empty()) {
      return false;
    }
    out = SkinOffsets{shared.held_pos[b], shared.held_nrm[b], shared.held_generation[b]};
    shared.held.fetch_add(1, std::memory_order_relaxed);
    return true;
  }

  void deform(const SkinFrame& frame) override {
    Shared& shared = *shared_;
    std::optional<DeformScene>& scene = shared.scene;
    if (!scene || body_ >= scene->bodyCount()) return;
    const auto b = static_cast<std::size_t>(body_);
    const Action action = b < shared.action.size() ? shared.action[b] : Action::kDeform;
    if (action == Action::kRigid) return;
    if (!scene->matchesPrepared(body_, frame.skin, frame.placement)) {
      shared.skipped.fetch_add(1, std::memory_order_relaxed);
      return;
    }
    const Clock::time_point start = Clock::now();
    const std::span<glm::vec3> held_pos = b < shared.held_pos.size()
                                              ? std::span<glm::vec3>(shared.held_pos[b])
                                              : std::span<glm::vec3>();
    const std::span<glm::vec3> held_nrm = b < shared.held_nrm.size()
                                              ? std::span<glm::vec3>(shared.held_nrm[b])
                                              : std::span<glm::vec3>();
    const bool fits = !held_pos.empty() && held_pos.size() == frame.positions.size() &&
                      held_nrm.size() == frame.normals.size();
    if (action == Action::kHold && fits) {
      // Between deformations: the last deformation's offsets on this frame's skinning.
      for (std::size_t v = 0; v < held_pos.size(); ++v) {
        frame.positions[v] += held_pos[v];
        frame.normals[v] = glm::normalize(frame.normals[v] + held_nrm[v]);
      }
      shared.held.fetch_add(1, std::memory_order_relaxed);
    } else {
      // Steps 2-3; for a lower-rate body also its offsets from the rigid skinning.
      const bool hold = action != Action::kDeform && fits;
      if (hold) {
        std::copy(frame.positions.begin(), frame.positions.end(), held_pos.begin());
        std::copy(frame.normals.begin(), frame.normals.end(), held_nrm.begin());
      }
      scene->deformBody(body_, frame.positions, frame.normals);
      if (hold) {
        for (std::size_t v = 0; v < held_pos.size(); ++v) {
          held_pos[v] = frame.positions[v] - held_pos[v];
          held_nrm[v] = frame.normals[v] - held_nrm[v];
        }
        shared.held_valid[b] = 1;
        shared.held_generation[b] = g_offsets_generation.fetch_add(1) + 1;
      }
      shared.deformed.fetch_add(1, std::memory_order_relaxed);
    }
    shared.deform_ns.fetch_add(
        std::chrono::duration_cast<std::chrono::nanoseconds>(Clock::now() - start).count(),
        std::memory_order_relaxed);
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
  // The scene being replaced: the bodies that stay carry their state over from it (elastic
  // memory: dents survive rebuilds).
  std::optional<DeformScene> old_scene = std::move(shared_->scene);
  const std::vector<Key> old_keys = std::move(keys_);
  for (const Key& k : old_keys) view.setDeformer(k.id, nullptr);
  keys_.clear();
  hooks_.clear();
  shared_->scene.reset();
  shared_->action.clear();
  shared_->held_valid.clear();
  shared_->held_generation.clear();
  shared_->held_pos.clear();
  shared_->held_nrm.clear();
  previous_tiers_.clear();
  tiers_.clear();
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
  // Per-body LOD state, sized once: room for the held offsets of every deforming body.
  const int n = shared_->scene->bodyCount();
  const auto nbody = static_cast<std::size_t>(n);
  shared_->action.assign(nbody, Action::kDeform);
  shared_->held_valid.assign(nbody, 0);
  shared_->held_generation.assign(nbody, 0);
  shared_->held_pos.resize(nbody);
  shared_->held_nrm.resize(nbody);
  for (int i = 0; i < n; ++i) {
    if (!shared_->scene->deforms(i)) continue;
    const auto nvert = static_cast<std::size_t>(shared_->scene->body(i).avatar->skin.vertexCount());
    shared_->held_pos[static_cast<std::size_t>(i)].assign(nvert, glm::vec3(0.0f));
    shared_->held_nrm[static_cast<std::size_t>(i)].assign(nvert, glm::vec3(0.0f));
  }
  body_positions_.assign(nbody, glm::vec3(0.0f));
  in_contact_.assign(nbody, 0);
  deforms_now_.assign(nbody, 0);
  tiers_.assign(nbody, DeformTier::kFull);
  previous_tiers_.reserve(nbody);
  keys_ = wanted_;
  for (std::size_t i = 0; old_scene && i < old_keys.size(); ++i) {
    const DeformState* state = old_scene->deformState(static_cast<int>(i));
    const auto found = std::find(keys_.begin(), keys_.end(), old_keys[i]);
    if (state != nullptr && found != keys_.end())
      shared_->scene->carryState(static_cast<int>(found - keys_.begin()), *state);
  }
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
  have_self_ = false;
  for (std::size_t i = 0; i < views.size(); ++i) {
    const MemberView& v = views[i];
    if (v.is_self && !have_self_) {
      have_self_ = true;
      self_position_ = glm::vec3(v.placement[3]);
    }
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
  // Dents waiting for their bodies: applied once the view is a body, dropped once it is not
  // drawn any more. (A failure is returned after the frame's work.)
  Status dents_status;
  std::erase_if(pending_dents_, [&](const PendingDents& p) {
    if (const int body = bodyOf(p.view_id); body >= 0) {
      const double age = p.age_s + std::max(0.0, last_time_ - p.adopted_at);
      if (Status st = applyDents(body, p.record, age); !st && dents_status) {
        dents_status = fail("dents for view {:#x}: {}", p.view_id, st.error().message);
      }
      return true;
    }
    return std::none_of(views.begin(), views.end(),
                        [&](const MemberView& v) { return v.id == p.view_id; });
  });
  std::optional<DeformScene>& scene = shared_->scene;
  if (!scene) return dents_status;
  for (std::size_t i = 0; i < views.size(); ++i) {
    const int body = view_body_[i];
    if (body < 0) continue;
    scene->setPosture(body, views[i].posture);
    scene->setPlacement(body, views[i].placement);
    scene->setMotion(body, glm::vec3(0.0f), 1.0f);  // until setMotion says otherwise
  }
  return dents_status;
}

Status RoomDeformer::prepare(double time, const InteractionList* received) {
  const Clock::time_point start = Clock::now();
  last_time_ = time;
  stats_ = DeformFrameStats{};
  shared_->deformed.store(0, std::memory_order_relaxed);
  shared_->held.store(0, std::memory_order_relaxed);
  shared_->deform_ns.store(0, std::memory_order_relaxed);
  if (!shared_->scene) return {};
  DeformScene& scene = *shared_->scene;
  // Step 1 between bodies now; each body's own pairs once its tier says it deforms.
  Status status = scene.prepare(time, received, /*self_contact=*/false);
  stats_.pose_ms = scene.timings().pose_ms;

  // Level of detail: who touches another body this frame (Step 1's pairs), where each
  // body stands, then every body's tier and what its hook does.
  const int n = scene.bodyCount();
  std::fill(in_contact_.begin(), in_contact_.end(), std::uint8_t{0});
  for (const Interaction& pair : scene.interactions().pairs) {
    if (pair.body_a == pair.body_b) continue;
    in_contact_[pair.body_a] = 1;
    in_contact_[pair.body_b] = 1;
  }
  for (int i = 0; i < n; ++i) {
    // Where the body's root joint is this frame (an avatar's hips, a ball's centre).
    const std::span<const glm::mat4> joints = scene.jointTransforms(i);
    const glm::vec4 root = joints.empty() ? glm::vec4(0.0f, 0.0f, 0.0f, 1.0f) : joints[0][3];
    body_positions_[static_cast<std::size_t>(i)] = glm::vec3(scene.body(i).placement * root);
  }
  DeformLodInput input;
  input.positions = body_positions_;
  input.viewer = viewer_override_ ? *viewer_override_
                 : have_self_     ? self_position_
                                  : glm::vec3(0.0f);
  input.in_contact = in_contact_;
  input.previous = previous_tiers_;
  chooseDeformTiers(lod_, input, lod_scratch_, tiers_);
  for (int i = 0; i < n; ++i) {
    const auto b = static_cast<std::size_t>(i);
    if (!scene.deforms(i)) tiers_[b] = DeformTier::kRigid;  // nothing to deform
    Action& action = shared_->action[b];
    switch (tiers_[b]) {
      case DeformTier::kFull:
        action = Action::kDeform;
        shared_->held_valid[b] = 0;
        ++stats_.full;
        break;
      case DeformTier::kReduced:
        action = deformsOnFrame(DeformTier::kReduced, i, frame_, lod_.reduced_every) ||
                         shared_->held_valid[b] == 0
                     ? Action::kDeformAndHold
                     : Action::kHold;
        ++stats_.reduced;
        break;
      case DeformTier::kRigid:
        action = Action::kRigid;
        shared_->held_valid[b] = 0;
        ++stats_.rigid;
        break;
    }
    deforms_now_[b] = action == Action::kDeform || action == Action::kDeformAndHold ? 1 : 0;
  }
  scene.addSelfInteractions(deforms_now_);
  stats_.step1_ms = scene.timings().step1_ms;
  previous_tiers_.assign(tiers_.begin(), tiers_.end());
  ++frame_;
  stats_.prepare_ms = std::chrono::duration<double, std::milli>(Clock::now() - start).count();
  return status;
}

Status RoomDeformer::setLod(const DeformLodSettings& settings) {
  if (Status valid = validateDeformLodSettings(settings); !valid) return valid;
  lod_ = settings;
  return {};
}

void RoomDeformer::finish() {
  if (!shared_->scene) return;
  shared_->scene->collectContacts();
  stats_.deformed = shared_->deformed.load(std::memory_order_relaxed);
  stats_.held = shared_->held.load(std::memory_order_relaxed);
  stats_.deform_cpu_ms =
      static_cast<double>(shared_->deform_ns.load(std::memory_order_relaxed)) * 1e-6;
}

bool RoomDeformer::recordDents(std::uint32_t view_id, DentRecord& out) const {
  const int body = bodyOf(view_id);
  const DeformState* state = body >= 0 ? shared_->scene->deformState(body) : nullptr;
  if (state == nullptr) return false;
  vistel::recordDents(state->memory, out);
  return true;
}

Status RoomDeformer::applyDents(int body, const DentRecord& record, double age_s) {
  const DeformState* state = shared_->scene->deformState(body);
  if (state == nullptr) return fail("body {} does not deform", body);
  dent_memory_.resize(state->memory.size());
  if (Status st = vistel::applyDents(record, dent_memory_); !st) return st;
  if (!shared_->scene->adoptMemory(body, dent_memory_, static_cast<float>(age_s))) {
    return fail("body {} refused the memory", body);  // (sizes and age checked before)
  }
  return {};
}

Status RoomDeformer::adoptDents(std::uint32_t view_id, const DentRecord& record, double age_s) {
  if (!(age_s >= 0.0) || !std::isfinite(age_s)) return fail("dents: an age of {} s", age_s);
  if (Status st = checkDents(record.vertex_count, record.gaps, record.depths, record.gaps.size());
      !st) {
    return st;
  }
  if (const int body = bodyOf(view_id); body >= 0) return applyDents(body, record, age_s);
  auto it = std::find_if(pending_dents_.begin(), pending_dents_.end(),
                         [&](const PendingDents& p) { return p.view_id == view_id; });
  if (it == pending_dents_.end()) it = pending_dents_.insert(pending_dents_.end(), PendingDents{});
  it->view_id = view_id;
  it->record = record;
  it->age_s = age_s;
  it->adopted_at = last_time_;
  return {};
}

bool RoomDeformer::touching(std::uint32_t view_a, std::uint32_t view_b) const {
  const int a = bodyOf(view_a);
  const int b = bodyOf(view_b);
  if (a < 0 || b < 0 || a == b) return false;
  const auto measured = [&](int self, int partner) {
    const DeformState* state = shared_->scene->deformState(self);
    if (state == nullptr || !shared_->scene->contactSummary(self).deformed) return false;
    return std::any_of(state->contacts.begin(), state->contacts.end(), [&](const BodyContact& c) {
      return c.partner == partner && c.vertices > 0;
    });
  };
  return measured(a, b) || measured(b, a);
}

bool RoomDeformer::setMotion(std::uint32_t view_id, const glm::vec3& velocity, float restitution) {
  const int body = bodyOf(view_id);
  if (body < 0) return false;
  shared_->scene->setMotion(body, velocity, restitution);
  return true;
}

std::optional<DeformTier> RoomDeformer::tier(std::uint32_t view_id) const {
  const int body = bodyOf(view_id);
  if (body < 0 || static_cast<std::size_t>(body) >= tiers_.size()) return std::nullopt;
  return tiers_[static_cast<std::size_t>(body)];
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

std::optional<PartForceInput> RoomDeformer::partForceInput(std::uint32_t view_id) const {
  const int body = bodyOf(view_id);
  if (body < 0) return std::nullopt;
  const DeformScene& scene = *shared_->scene;
  const DeformState* state = scene.deformState(body);
  if (state == nullptr || !scene.contactSummary(body).deformed) return std::nullopt;
  PartForceInput in;
  in.positions = state->positions;
  in.normals = state->normals;
  in.pressure = state->pressure;
  in.contact_body = state->contact_body;
  in.self_body = body;
  // Placements are rigid: world -> model is the transpose of their rotation.
  in.world_to_model = glm::transpose(glm::mat3(scene.body(body).placement));
  return in;
}

}  // namespace vistel
