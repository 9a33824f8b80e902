#include "common/scene/deform_scene.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstring>
#include <limits>
#include <utility>

#include <fmt/format.h>

#include "common/deform/posed_primitives.hpp"
#include "common/deform/prop.hpp"
#include "common/deform/task_pool.hpp"

namespace vistel {
namespace {

using Clock = std::chrono::steady_clock;

double msSince(Clock::time_point start) {
  return std::chrono::duration<double, std::milli>(Clock::now() - start).count();
}

bool finite(const glm::vec3& v) {
  return std::isfinite(v.x) && std::isfinite(v.y) && std::isfinite(v.z);
}

// The posture fits the skeleton (sizes) and is finite: what RoomView checks too, so that a
// renderer and the scene fall back to the rest posture on the same frames.
bool postureFits(const Skeleton& skeleton, const Posture& p) {
  const auto n = static_cast<std::size_t>(skeleton.jointCount());
  if (p.rotations.size() != n || (!p.translations.empty() && p.translations.size() != n)) {
    return false;
  }
  if (!finite(p.root_translation)) return false;
  for (const glm::quat& q : p.rotations) {
    if (!std::isfinite(q.x) || !std::isfinite(q.y) || !std::isfinite(q.z) || !std::isfinite(q.w))
      return false;
  }
  for (const glm::vec3& t : p.translations) {
    if (!finite(t)) return false;
  }
  return true;
}

// Two arrays of the same size and bytes (empty ones are equal).
template <typename T>
bool sameBits(std::span<const T> a, std::span<const T> b) {
  return a.size() == b.size() &&
         (a.empty() || std::memcmp(a.data(), b.data(), a.size_bytes()) == 0);
}

// A range of one body's vertices for the parallel skinning of step().
struct SkinItem {
  int body = 0;
  int first = 0;
  int count = 0;
};

// Everything per body: static references, this frame's inputs, per-frame buffers.
struct SceneSlot {
  SceneBody def;
  const AvatarModel* avatar = nullptr;
  const ImplicitModel* model = nullptr;  // null: no implicit model
  bool deforms = false;                  // Steps 2-3 run on it
  Posture posture;                       // this frame's input
  Posture rest;
  const Posture* used = nullptr;  // posture or rest, whichever this frame used
  glm::mat4 inverse_placement{1.0f};
  glm::mat3 normal_to_world{1.0f};  // inverse transpose of the placement's linear part
  glm::mat3 normal_to_model{1.0f};

  std::vector<glm::mat4> joint_model;  // (njoint) posed joints, model space
  std::vector<glm::mat4> skin_model;   // (njoint) bind -> posed, model space
  std::vector<glm::mat4> skin_world;   // (njoint) bind -> world (placement * skin_model)
  std::vector<DualQuat> dq;            // (njoint) skin_world as dual quaternions
  SkinningRig rig;                     // the rigid component's per-mesh data (options.skinning)
  RigFrame rig_frame;                  // the rig's per-frame data (world)
  std::vector<glm::vec3> rigid_pos;    // (nvert) world
  std::vector<glm::vec3> rigid_nrm;    // (nvert) world
  PosedPrimitives posed;               // world (empty items without a model)
  DeformState state;                   // sized when it deforms
  bool deformed = false;               // Steps 2-3 ran since the last prepare
  BodyContactSummary summary;
};

}  // namespace

struct DeformScene::Impl {
  SceneOptions options;
  std::vector<SceneSlot> bodies;  // sized once
  std::vector<BodyView> views;    // (nbody) into bodies
  InteractionScratch scratch;
  InteractionList list;
  std::vector<PairContact> pairs;
  std::vector<const DeformState*> states;  // (nbody)
  std::vector<SkinItem> skin_items;
  std::unique_ptr<TaskPool> pool;  // threads > 1
  SceneTimings timings;
  int postures_at_rest = 0;
  double time = 0.0;

  void poseBody(SceneSlot& b);
  Status interactionsFor(const InteractionList* received, bool self_contact);
  bool self_pending = false;  // the list was built without the bodies' own pairs
  void deformWorld(int index, TaskPool* task_pool);
  void summarize();
};

// Joints and skinning matrices of the frame's posture, the world transforms, and the
// posed primitives.
void DeformScene::Impl::poseBody(SceneSlot& b) {
  const Skeleton& skeleton = b.avatar->skeleton;
  const bool fits = postureFits(skeleton, b.posture);
  if (!fits) ++postures_at_rest;
  b.used = fits ? &b.posture : &b.rest;
  poseSkeleton(skeleton, *b.used, b.joint_model);
  skinningMatrices(skeleton, b.joint_model, b.skin_model);
  const glm::mat4& placement = b.def.placement;
  for (std::size_t j = 0; j < b.skin_model.size(); ++j) {
    b.skin_world[j] = placement * b.skin_model[j];
  }
  b.inverse_placement = glm::inverse(placement);
  b.normal_to_world = glm::transpose(glm::inverse(glm::mat3(placement)));
  b.normal_to_model = glm::transpose(glm::mat3(placement));
  if (b.model != nullptr) posePrimitives(b.model->primitives, b.skin_world, b.posed);
}

// Step 1: the received list when valid, else the scene's own.
Status DeformScene::Impl::interactionsFor(const InteractionList* received, bool self_contact) {
  const int n = static_cast<int>(bodies.size());
  self_pending = false;
  if (received != nullptr) {
    list.pairs.assign(received->pairs.begin(), received->pairs.end());
    Status valid = validateInteractions(list, views);
    if (valid) {
      finalizeInteractions(list, n);
      self_pending = !self_contact;
      return {};
    }
    buildInteractions(views, scratch, list, self_contact);
    self_pending = !self_contact;
    return withContext("received interaction list (replaced by the local Step 1)", valid.error());
  }
  buildInteractions(views, scratch, list, self_contact);
  self_pending = !self_contact;
  return {};
}

// Steps 2-3 of one body whose rigid_pos/rigid_nrm hold its world-space skinning.
void DeformScene::Impl::deformWorld(int index, TaskPool* task_pool) {
  SceneSlot& b = bodies[static_cast<std::size_t>(index)];
  DeformInput input;
  input.rigid_positions = b.rigid_pos;
  input.rigid_normals = b.rigid_nrm;
  input.indices = b.avatar->skin.indices;
  input.rest_positions = b.avatar->skin.positions;
  input.time = time;
  deformSkin(*b.model, views, index, list, input, b.state, options.deform, task_pool);
  b.deformed = true;
}

// Combined pairs and per-body summaries from the bodies deformed this frame.
void DeformScene::Impl::summarize() {
  for (std::size_t i = 0; i < bodies.size(); ++i) {
    states[i] = bodies[i].deformed ? &bodies[i].state : nullptr;
  }
  combineContacts(states, pairs);
  for (std::size_t i = 0; i < bodies.size(); ++i) {
    SceneSlot& b = bodies[i];
    BodyContactSummary s;
    s.deformed = b.deformed;
    if (b.deformed) {
      for (const BodyContact& c : b.state.contacts) {
        s.max_depth = std::max(s.max_depth, c.max_depth);
        if (c.partner == static_cast<int>(i)) s.self_area += c.area;
      }
    }
    s.area = s.self_area;
    // Partners and force from the combined pairs (a rigid partner measures no faces of its
    // own: the pair comes from the other side).
    double best_area = -1.0;
    for (const PairContact& p : pairs) {
      if (p.body_a != static_cast<int>(i) && p.body_b != static_cast<int>(i)) continue;
      if (p.area_a == 0.0 && p.area_b == 0.0 && p.force_on_a == glm::dvec3(0.0)) continue;
      const int other = p.body_a == static_cast<int>(i) ? p.body_b : p.body_a;
      ++s.partner_count;
      const double own = p.body_a == static_cast<int>(i) ? p.area_a : p.area_b;
      const double theirs = p.body_a == static_cast<int>(i) ? p.area_b : p.area_a;
      s.area += own > 0.0 ? own : theirs;  // a rigid side measures no faces of its own
      const double pair_area = std::max(own, theirs);
      if (pair_area > best_area) {
        best_area = pair_area;
        s.partner = other;
      }
      s.force += p.body_a == static_cast<int>(i) ? p.force_on_a : -p.force_on_a;
    }
    b.summary = s;
  }
}

DeformScene::DeformScene(std::unique_ptr<Impl> impl) : impl_(std::move(impl)) {}
DeformScene::DeformScene(DeformScene&&) noexcept = default;
DeformScene& DeformScene::operator=(DeformScene&&) noexcept = default;
DeformScene::~DeformScene() = default;

Result<DeformScene> DeformScene::create(std::vector<SceneBody> bodies,
                                        const SceneOptions& options) {
  if (bodies.empty()) return fail("scene: no bodies");
  if (bodies.size() > 65535) return fail("scene: {} bodies (at most 65535)", bodies.size());
  if (options.threads < 1) return fail("scene: threads must be >= 1 (got {})", options.threads);
  if (options.skin_chunk < 1) {
    return fail("scene: skin_chunk must be >= 1 (got {})", options.skin_chunk);
  }
  auto impl = std::make_unique<Impl>();
  impl->options = options;
  impl->bodies.resize(bodies.size());
  impl->views.resize(bodies.size());
  impl->states.assign(bodies.size(), nullptr);
  for (std::size_t i = 0; i < bodies.size(); ++i) {
    SceneSlot& b = impl->bodies[i];
    b.def = std::move(bodies[i]);
    const std::string label = fmt::format("body {} ('{}')", i, b.def.name);
    if (!b.def.avatar) return fail("scene: {}: no avatar", label);
    if (Status valid = validateAvatar(*b.def.avatar); !valid) {
      return withContext(fmt::format("scene: {}", label), valid.error());
    }
    b.avatar = b.def.avatar.get();
    const bool has_model = b.avatar->implicit.has_value();
    b.model = has_model ? &*b.avatar->implicit : nullptr;
    b.deforms = has_model && b.def.deformable && !options.rigid_only;
    const auto nj = static_cast<std::size_t>(b.avatar->skeleton.jointCount());
    const auto nv = static_cast<std::size_t>(b.avatar->skin.vertexCount());
    b.rest = restPosture(b.avatar->skeleton);
    b.posture = b.rest;
    b.used = &b.rest;
    b.joint_model.assign(nj, glm::mat4(1.0f));
    b.skin_model.assign(nj, glm::mat4(1.0f));
    b.skin_world.assign(nj, glm::mat4(1.0f));
    b.dq.assign(nj, DualQuat{});
    b.rig = makeSkinningRig(b.avatar->skeleton, b.avatar->skin, options.skinning);
    b.rig_frame = makeRigFrame(b.rig);
    b.rigid_pos.assign(nv, glm::vec3(0.0f));
    b.rigid_nrm.assign(nv, glm::vec3(0.0f, 1.0f, 0.0f));
    if (b.model != nullptr) {
      b.posed.items.resize(b.model->primitives.items.size());
    }
    if (b.deforms) {
      if (Status st = initDeformState(*b.model, b.avatar->skin.indices, b.state); !st) {
        return withContext(fmt::format("scene: {}", label), st.error());
      }
    }
    impl->views[i] = BodyView{b.model != nullptr ? &b.model->graph : nullptr, &b.posed};
    for (int first = 0; first < static_cast<int>(nv); first += options.skin_chunk) {
      impl->skin_items.push_back(SkinItem{
          static_cast<int>(i), first, std::min(options.skin_chunk, static_cast<int>(nv) - first)});
    }
  }
  if (options.threads > 1) impl->pool = std::make_unique<TaskPool>(options.threads);
  // Room for the lists of the first frames (they grow to the scene's largest).
  impl->list.body_offsets.reserve(bodies.size() + 1);
  impl->pairs.reserve(bodies.size() * 2);
  return DeformScene(std::move(impl));
}

int DeformScene::bodyCount() const { return static_cast<int>(impl_->bodies.size()); }
const SceneBody& DeformScene::body(int index) const {
  return impl_->bodies[static_cast<std::size_t>(index)].def;
}
const SceneOptions& DeformScene::options() const { return impl_->options; }
bool DeformScene::deforms(int index) const {
  return impl_->bodies[static_cast<std::size_t>(index)].deforms;
}

Posture& DeformScene::posture(int index) {
  return impl_->bodies[static_cast<std::size_t>(index)].posture;
}
void DeformScene::setPosture(int index, const Posture& posture) {
  impl_->bodies[static_cast<std::size_t>(index)].posture = posture;
}
void DeformScene::setPlacement(int index, const glm::mat4& placement) {
  impl_->bodies[static_cast<std::size_t>(index)].def.placement = placement;
}

void DeformScene::setMotion(int index, const glm::vec3& velocity, float restitution) {
  BodyView& v = impl_->views[static_cast<std::size_t>(index)];
  const bool finite =
      std::isfinite(velocity.x) && std::isfinite(velocity.y) && std::isfinite(velocity.z);
  v.velocity = finite ? velocity : glm::vec3(0.0f);
  v.restitution = restitution >= 0.0f && restitution <= 1.0f ? restitution : 1.0f;
}

Status DeformScene::prepare(double time, const InteractionList* received, bool self_contact) {
  Impl& s = *impl_;
  s.time = time;
  s.postures_at_rest = 0;
  // Skeletons and primitives.
  const Clock::time_point t0 = Clock::now();
  for (SceneSlot& b : s.bodies) {
    s.poseBody(b);
    b.deformed = false;
  }
  const Clock::time_point t1 = Clock::now();
  s.timings.pose_ms = std::chrono::duration<double, std::milli>(t1 - t0).count();
  s.timings.skin_ms = 0.0;
  s.timings.deform_ms = 0.0;
  // Step 1.
  Status status;
  s.self_pending = false;
  if (s.options.rigid_only) {
    s.list.pairs.clear();
    finalizeInteractions(s.list, bodyCount());
  } else {
    status = s.interactionsFor(received, self_contact);
  }
  s.timings.step1_ms = msSince(t1);
  return status;
}

void DeformScene::addSelfInteractions(std::span<const std::uint8_t> deforms) {
  Impl& s = *impl_;
  if (!s.self_pending) return;
  s.self_pending = false;
  const Clock::time_point t0 = Clock::now();
  const std::size_t before = s.list.pairs.size();
  for (std::size_t i = 0; i < s.bodies.size() && i < deforms.size(); ++i) {
    if (deforms[i] == 0 || s.views[i].graph == nullptr) continue;
    appendSelfInteractions(*s.views[i].graph, *s.views[i].posed, static_cast<std::uint16_t>(i),
                           s.list.pairs);
  }
  if (s.list.pairs.size() != before) finalizeInteractions(s.list, bodyCount());
  s.timings.step1_ms += msSince(t0);
}

bool DeformScene::matchesPrepared(int index, std::span<const glm::mat4> skin,
                                  const glm::mat4& placement) const {
  const SceneSlot& b = impl_->bodies[static_cast<std::size_t>(index)];
  return skin.size() == b.skin_model.size() &&
         std::memcmp(skin.data(), b.skin_model.data(), skin.size_bytes()) == 0 &&
         std::memcmp(&placement, &b.def.placement, sizeof(glm::mat4)) == 0;
}

bool DeformScene::posedWith(int index, const Posture& posture) const {
  const SceneSlot& b = impl_->bodies[static_cast<std::size_t>(index)];
  const Posture& used = *b.used;
  return sameBits(std::span(&posture.root_translation, 1), std::span(&used.root_translation, 1)) &&
         sameBits(std::span(posture.rotations), std::span(used.rotations)) &&
         sameBits(std::span(posture.translations), std::span(used.translations));
}

void DeformScene::deformBody(int index, std::span<glm::vec3> positions,
                             std::span<glm::vec3> normals) {
  Impl& s = *impl_;
  SceneSlot& b = s.bodies[static_cast<std::size_t>(index)];
  if (!b.deforms || positions.size() != b.rigid_pos.size() ||
      normals.size() != b.rigid_nrm.size()) {
    return;
  }
  // Model -> world, Steps 2-3, world -> model.
  const glm::mat4& to_world = b.def.placement;
  for (std::size_t v = 0; v < positions.size(); ++v) {
    b.rigid_pos[v] = glm::vec3(to_world * glm::vec4(positions[v], 1.0f));
    b.rigid_nrm[v] = glm::normalize(b.normal_to_world * normals[v]);
  }
  s.deformWorld(index, nullptr);
  for (std::size_t v = 0; v < positions.size(); ++v) {
    positions[v] = glm::vec3(b.inverse_placement * glm::vec4(b.state.positions[v], 1.0f));
    normals[v] = glm::normalize(b.normal_to_model * b.state.normals[v]);
  }
}

void DeformScene::collectContacts() { impl_->summarize(); }

Status DeformScene::step(double time, const InteractionList* received) {
  Impl& s = *impl_;
  Status status = prepare(time, received);
  // Rigid component: every body's vertices in world space, in chunks across the pool.
  const Clock::time_point t0 = Clock::now();
  for (SceneSlot& b : s.bodies) prepareRigFrame(b.rig, b.skin_world, b.dq, b.rig_frame);
  auto skin = [&s](int t) {
    const SkinItem& item = s.skin_items[static_cast<std::size_t>(t)];
    SceneSlot& b = s.bodies[static_cast<std::size_t>(item.body)];
    const auto first = static_cast<std::size_t>(item.first);
    const auto count = static_cast<std::size_t>(item.count);
    const std::span<glm::vec3> pos = std::span(b.rigid_pos).subspan(first, count);
    const std::span<glm::vec3> nrm = std::span(b.rigid_nrm).subspan(first, count);
    skinRigRange(b.avatar->skin, b.rig, b.skin_world, b.dq, b.rig_frame, first, pos, nrm);
  };
  parallelFor(s.pool.get(), static_cast<int>(s.skin_items.size()), skin);
  const Clock::time_point t1 = Clock::now();
  s.timings.skin_ms = std::chrono::duration<double, std::milli>(t1 - t0).count();
  // Steps 2-3, body after body, each across the pool.
  for (int i = 0; i < bodyCount(); ++i) {
    if (s.bodies[static_cast<std::size_t>(i)].deforms) s.deformWorld(i, s.pool.get());
  }
  s.summarize();
  s.timings.deform_ms = msSince(t1);
  return status;
}

std::span<const glm::vec3> DeformScene::positions(int index) const {
  const SceneSlot& b = impl_->bodies[static_cast<std::size_t>(index)];
  return b.deforms && b.deformed ? std::span<const glm::vec3>(b.state.positions)
                                 : std::span<const glm::vec3>(b.rigid_pos);
}
std::span<const glm::vec3> DeformScene::normals(int index) const {
  const SceneSlot& b = impl_->bodies[static_cast<std::size_t>(index)];
  return b.deforms && b.deformed ? std::span<const glm::vec3>(b.state.normals)
                                 : std::span<const glm::vec3>(b.rigid_nrm);
}
std::span<const glm::vec3> DeformScene::rigidPositions(int index) const {
  return impl_->bodies[static_cast<std::size_t>(index)].rigid_pos;
}
std::span<const glm::mat4> DeformScene::jointTransforms(int index) const {
  return impl_->bodies[static_cast<std::size_t>(index)].joint_model;
}
std::span<const glm::mat4> DeformScene::skinMatrices(int index) const {
  return impl_->bodies[static_cast<std::size_t>(index)].skin_model;
}
const InteractionList& DeformScene::interactions() const { return impl_->list; }
std::span<const BodyView> DeformScene::bodyViews() const { return impl_->views; }
std::span<const PairContact> DeformScene::contacts() const { return impl_->pairs; }
BodyContactSummary DeformScene::contactSummary(int index) const {
  return impl_->bodies[static_cast<std::size_t>(index)].summary;
}
const DeformState* DeformScene::deformState(int index) const {
  const SceneSlot& b = impl_->bodies[static_cast<std::size_t>(index)];
  return b.deforms ? &b.state : nullptr;
}
bool DeformScene::carryState(int index, const DeformState& from) {
  SceneSlot& b = impl_->bodies[static_cast<std::size_t>(index)];
  return b.deforms && carryDeformState(from, b.state);
}
bool DeformScene::adoptMemory(int index, std::span<const float> memory, float age_s) {
  SceneSlot& b = impl_->bodies[static_cast<std::size_t>(index)];
  return b.deforms && adoptElasticMemory(*b.model, memory, b.state, age_s);
}
const SkinningRig& DeformScene::skinningRig(int index) const {
  return impl_->bodies[static_cast<std::size_t>(index)].rig;
}
int DeformScene::posturesAtRest() const { return impl_->postures_at_rest; }
const SceneTimings& DeformScene::timings() const { return impl_->timings; }

Result<std::shared_ptr<const AvatarModel>> makeBallAvatar(const BallSpec& spec, std::string name) {
  Result<BallBody> ball = makeBall(spec);
  if (!ball) return ball.error();
  auto avatar = std::make_shared<AvatarModel>();
  avatar->name = std::move(name);
  avatar->skeleton = std::move(ball->skeleton);
  avatar->skin = std::move(ball->mesh);
  avatar->implicit = std::move(ball->model);
  return std::shared_ptr<const AvatarModel>(std::move(avatar));
}

}  // namespace vistel
