#include "client/view/room_view.hpp"

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <limits>
#include <unordered_map>
#include <unordered_set>
#include <utility>

#include <glm/gtc/matrix_transform.hpp>

#include "client/render/gl_context.hpp"
#include "client/render/gl_util.hpp"
#include "client/render/gpu_mesh.hpp"
#include "client/render/gpu_skin_mesh.hpp"
#include "client/render/label_renderer.hpp"
#include "client/render/render_target.hpp"
#include "client/render/scene_renderer.hpp"
#include "client/view/head_landmarks.hpp"
#include "client/view/worker_pool.hpp"
#include "common/anim/skinning.hpp"
#include "common/anim/skinning_rig.hpp"
#include "common/motion/auto_joint_map.hpp"
#include "common/motion/joint_map.hpp"

namespace vistel {

namespace {

using Clock = std::chrono::steady_clock;

constexpr int kChunkVertices = 2048;  // vertices per skinning work item
constexpr float kMarkerSize = 0.12f;  // metres
constexpr float kMarkerLift = 0.14f;  // marker centre above the top of the head, metres
constexpr float kLabelLift = 0.24f;   // name tag's bottom above the top of the head, metres

double millisecondsSince(Clock::time_point start) {
  return std::chrono::duration<double, std::milli>(Clock::now() - start).count();
}

// One member's per-frame data: written by the skinning batch (the back frame), then
// drawn (the front frame). Sized once per avatar.
struct MemberFrame {
  Posture posture;            // what was posed (the member's, or the rest posture)
  glm::mat4 placement{1.0f};  // model -> room
  std::string name;
  bool is_self = false;
  std::vector<glm::mat4> joint_model;  // posed joint transforms, model space (njoint)
  std::vector<glm::mat4> skin;         // skinning matrices (njoint)
  std::vector<DualQuat> dq;            // their rigid parts (njoint)
  RigFrame rig_frame;                  // the rig's per-frame data (sized once per avatar)
  std::vector<glm::vec3> positions;    // skinned (+ deformed), model space (nvert)
  std::vector<glm::vec3> normals;      // (nvert)
  glm::vec3 box_min{0.0f};             // room-space bounds of positions
  glm::vec3 box_max{0.0f};
  glm::mat4 head_delta{1.0f};  // posed head transform * inverse(rest), model space
  bool gpu = false;            // skinned in the vertex shader (positions, normals unused)
  bool has_offsets = false;    // gpu, plus the deformer's offsets
  SkinOffsets offsets;         // (has_offsets)
};

// Everything the view keeps about one member between frames.
struct MemberSlot {
  std::uint32_t id = 0;
  std::shared_ptr<const AvatarModel> avatar;
  bool valid = false;  // avatar passed validation and has a skin
  int head_hint = -1;  // setHeadJoint() value the head was measured with
  Posture rest;        // fallback posture
  SkinningRig rig;     // the rigid component's per-mesh data (options.skinning)
  HeadLandmarks head;
  glm::mat4 head_rest_inverse{1.0f};
  std::shared_ptr<PostSkinDeformer> deformer;  // of the frame being skinned
  MemberFrame frames[2];
  int front = 0;                    // frames[front] is drawn, the other one written
  bool has_front = false;           // frames[front] holds a finished frame
  bool in_batch = false;            // skinned in this render()
  bool seen = false;                // present in this render()
  std::atomic<int> chunks_left{0};  // skinning items of this member still running
  GpuMesh mesh;
  bool gpu_capable = false;            // gpu_skinning on and the avatar fits it
  GpuSkinMesh gpu_mesh;                // (gpu_capable, not headless)
  GpuLook look;                        // the avatar's materials and textures (not headless)
  float reach = 0.0f;                  // farthest vertex from its first joint at rest (m): bounds
  std::uint64_t uploaded_offsets = 0;  // generation of the offsets in gpu_mesh (0: none)

  MemberFrame& back() { return frames[1 - front]; }
  const MemberFrame& shown() const { return frames[front]; }
};

struct WorkItem {
  MemberSlot* slot;
  int first;  // first vertex
  int count;  // vertices
};

bool finitePosture(const Posture& posture) {
  if (!std::isfinite(posture.root_translation.x + posture.root_translation.y +
                     posture.root_translation.z)) {
    return false;
  }
  for (const glm::quat& q : posture.rotations) {
    if (!std::isfinite(q.w + q.x + q.y + q.z)) return false;
  }
  for (const glm::vec3& t : posture.translations) {
    if (!std::isfinite(t.x + t.y + t.z)) return false;
  }
  return true;
}

}  // namespace

struct RoomView::Impl final : WorkerPool::Job {
  explicit Impl(const ViewOptions& view_options)
      : options(view_options), pool(std::max(view_options.worker_threads, 1) - 1) {
    cameras.reserve(2);
    items.reserve(64);
  }
  ~Impl() {
    pool.wait();
    if (context) context->makeCurrent();
  }

  // Declaration order matters: GL objects below are destroyed before the context.
  ViewOptions options;
  std::unique_ptr<GlContext> context;
  std::string backend;
  WorkerPool pool;
  std::vector<std::unique_ptr<MemberSlot>> slots;
  std::vector<std::pair<float, MemberSlot*>> looks_by_depth;  // drawFrame's, reused
  std::unique_ptr<RenderTarget> target;
  std::unique_ptr<SceneRenderer> scene;
  std::unique_ptr<LabelRenderer> labels;
  std::vector<WorkItem> items;
  std::vector<EyeCamera> cameras;
  FrameStats stats;
  std::string warning;
  std::unordered_map<std::uint32_t, std::shared_ptr<PostSkinDeformer>> deformers;
  std::unordered_map<std::uint32_t, int> head_joints;
  std::unordered_set<std::uint32_t> unframed;  // setFramed(id, false)
  bool joint_maps_loaded = false;
  std::vector<JointMap> joint_maps;  // config/skeletons, loaded at the first new avatar
  int frames = 0;
  bool frame_valid = false;
  // Room camera: a smoothed bounding sphere of everyone, and the user's orbit.
  bool have_sphere = false;
  Sphere sphere;
  float yaw = 0.0f;
  float pitch = 0.30f;
  float zoom = 1.0f;
  std::string keys;  // unclaimed key presses (takeKeyPresses)

  void runItem(int index) override;
  void render(std::span<const MemberView> members);

 private:
  MemberSlot* findSlot(std::uint32_t id);
  void prepareSlot(MemberSlot& slot, const MemberView& member, int head_hint);
  int headHint(std::uint32_t id) const;
  int headFromJointMaps(const Skeleton& skeleton);
  void poseBack(MemberSlot& slot, const MemberView& member);
  static void finishMember(MemberSlot& slot);
  static void jointBounds(MemberSlot& slot);
  void drawFrame();
  void applyInput();
  void computeCameras(glm::ivec2 size);
  glm::vec3 headTop(const MemberSlot& slot) const;
};

MemberSlot* RoomView::Impl::findSlot(std::uint32_t id) {
  for (auto& slot : slots) {
    if (slot->id == id) return slot.get();
  }
  return nullptr;
}

// The head joint the caller set for a member id, or -1.
int RoomView::Impl::headHint(std::uint32_t id) const {
  const auto it = head_joints.find(id);
  return it == head_joints.end() ? -1 : it->second;
}

// The joint named by the canonical "head" of the joint map that fits this skeleton, or -1
// (no map fits, or the maps could not be loaded: then a warning says why).
int RoomView::Impl::headFromJointMaps(const Skeleton& skeleton) {
  if (!joint_maps_loaded) {
    joint_maps_loaded = true;
    auto maps = loadJointMaps();
    if (maps) {
      joint_maps = std::move(*maps);
    } else {
      warning = "joint maps: " + maps.error().message;
    }
  }
  auto map = chooseJointMap(joint_maps, skeleton);  // a config map, else one inferred
  if (!map) return -1;
  const std::string_view name = map->map.jointFor("head");
  return name.empty() ? -1 : skeleton.find(name);
}

// A new avatar for this member: validate it once, size every per-frame array, upload
// the triangles and measure the head. (Allocation happens here, not per frame.)
void RoomView::Impl::prepareSlot(MemberSlot& slot, const MemberView& member, int head_hint) {
  slot.avatar = member.avatar;
  slot.head_hint = head_hint;
  slot.has_front = false;
  slot.valid = false;
  const AvatarModel& avatar = *slot.avatar;
  if (Status status = validateAvatar(avatar); !status.ok()) {
    warning = fmt::format("member {} ('{}'): avatar not drawn: {}", member.id, member.name,
                          status.error().message);
    return;
  }
  if (avatar.skin.vertexCount() == 0) {
    warning = fmt::format("member {} ('{}'): avatar not drawn: it has no skin vertices", member.id,
                          member.name);
    return;
  }
  const auto njoint = static_cast<std::size_t>(avatar.skeleton.jointCount());
  const auto nvert = static_cast<std::size_t>(avatar.skin.vertexCount());
  for (MemberFrame& frame : slot.frames) {
    frame.joint_model.assign(njoint, glm::mat4(1.0f));
    frame.skin.assign(njoint, glm::mat4(1.0f));
    frame.dq.assign(njoint, DualQuat{});
    frame.positions.assign(nvert, glm::vec3(0.0f));
    frame.normals.assign(nvert, glm::vec3(0.0f, 1.0f, 0.0f));
    frame.posture.rotations.reserve(njoint);
    frame.posture.translations.reserve(njoint);
    frame.name.reserve(64);
  }
  slot.rest = restPosture(avatar.skeleton);
  // The head: the caller's joint, else the joint map's "head", else a search by name.
  int head_joint = head_hint >= 0 && head_hint < avatar.skeleton.jointCount()
                       ? head_hint
                       : headFromJointMaps(avatar.skeleton);
  if (head_joint < 0) head_joint = findHeadJoint(avatar.skeleton);
  slot.head = measureHead(avatar, head_joint);
  // The rigid component; a single-joint prop needs no spine, so its fallback is no news.
  slot.rig = makeSkinningRig(avatar.skeleton, avatar.skin, options.skinning, head_joint);
  for (MemberFrame& frame : slot.frames) frame.rig_frame = makeRigFrame(slot.rig);
  if (!slot.rig.warning.empty() && avatar.skeleton.jointCount() > 1) {
    warning = fmt::format("member {} ('{}'): {}", member.id, member.name, slot.rig.warning);
  }
  slot.head_rest_inverse = glm::inverse(slot.head.rest_model);
  if (!options.headless) {
    slot.mesh.create(avatar.skin.vertexCount(), avatar.skin.indices);
    // The look: textures decoded and uploaded once; texture coordinates on the mesh.
    slot.look.create(avatar.look, avatar.skin.indices.size());
    if (!avatar.look.empty()) slot.mesh.attachUvs(avatar.look.uvs);
    if (!slot.look.warning().empty()) {
      warning = fmt::format("member {} ('{}'): {}", member.id, member.name, slot.look.warning());
    }
  }
  // Rigid skinning on the GPU where it fits, and how far the skin reaches from the joints.
  slot.gpu_capable = false;
  slot.uploaded_offsets = 0;
  // (The vertex shader does dual quaternions only; other methods skin on the CPU.)
  if (options.gpu_skinning && slot.rig.method == SkinningMethod::kDualQuaternion &&
      GpuSkinMesh::supports(avatar.skin, avatar.skeleton.jointCount())) {
    if (options.headless) {
      slot.gpu_capable = true;
    } else if (Status st = slot.gpu_mesh.create(avatar.skin, avatar.skeleton.jointCount()); st) {
      slot.gpu_capable = true;
      if (!avatar.look.empty()) slot.gpu_mesh.attachUvs(avatar.look.uvs);
    } else {
      warning = fmt::format("member {}: {}", member.id, st.error().message);
    }
    std::vector<glm::vec3> joint_rest(njoint);
    for (std::size_t j = 0; j < njoint; ++j) {
      joint_rest[j] = glm::vec3(glm::inverse(avatar.skeleton.inverse_bind[j])[3]);
    }
    const auto k = static_cast<std::size_t>(avatar.skin.influences);
    slot.reach = 0.0f;
    for (std::size_t v = 0; v < nvert; ++v) {
      const glm::vec3& joint = joint_rest[avatar.skin.joints[v * k]];
      slot.reach = std::max(slot.reach, glm::distance(avatar.skin.positions[v], joint));
    }
  }
  slot.valid = true;
}

// Copies what the batch needs into the back frame and poses the skeleton (cheap:
// per joint; taken from the member's deformer when it posed the same posture already);
// the vertices are skinned by the batch.
void RoomView::Impl::poseBack(MemberSlot& slot, const MemberView& member) {
  MemberFrame& frame = slot.back();
  const Skeleton& skeleton = slot.avatar->skeleton;
  const auto njoint = static_cast<std::size_t>(skeleton.jointCount());
  const Posture& given = member.posture;
  const bool fits = given.rotations.size() == njoint &&
                    (given.translations.empty() || given.translations.size() == njoint) &&
                    finitePosture(given);
  if (!fits) ++stats.postures_at_rest;
  frame.posture = fits ? given : slot.rest;  // same sizes: reuses capacity
  frame.placement = member.placement;
  frame.name = member.name;
  frame.is_self = member.is_self;
  const auto deformer = deformers.find(member.id);
  if (deformer == deformers.end()) {
    slot.deformer.reset();
  } else {
    slot.deformer = deformer->second;
  }
  if (slot.deformer && slot.deformer->copyPose(frame.posture, frame.joint_model, frame.skin)) {
    ++stats.poses_copied;
  } else {
    poseSkeleton(skeleton, frame.posture, frame.joint_model);
    skinningMatrices(skeleton, frame.joint_model, frame.skin);
  }
  prepareRigFrame(slot.rig, frame.skin, frame.dq, frame.rig_frame);
  // On the GPU: members whose deformer leaves the vertices rigid, or only adds offsets.
  frame.gpu = false;
  frame.has_offsets = false;
  if (slot.gpu_capable) {
    if (!slot.deformer || !slot.deformer->needsVertices()) {
      frame.gpu = true;
    } else if (slot.deformer->offsetsOnly(frame.offsets)) {
      const auto nvert = static_cast<std::size_t>(slot.avatar->skin.vertexCount());
      frame.gpu = frame.has_offsets =
          frame.offsets.positions.size() == nvert && frame.offsets.normals.size() == nvert;
    }
  }
  frame.head_delta =
      slot.head.joint >= 0
          ? frame.joint_model[static_cast<std::size_t>(slot.head.joint)] * slot.head_rest_inverse
          : glm::mat4(1.0f);
}

// One chunk of one member's vertices, on any thread. The last chunk of a member runs
// its deformer and measures its bounds.
void RoomView::Impl::runItem(int index) {
  const WorkItem& item = items[static_cast<std::size_t>(index)];
  MemberSlot& slot = *item.slot;
  MemberFrame& frame = slot.back();
  const auto first = static_cast<std::size_t>(item.first);
  const auto count = static_cast<std::size_t>(item.count);
  skinRigRange(slot.avatar->skin, slot.rig, frame.skin, frame.dq, frame.rig_frame, first,
               std::span(frame.positions).subspan(first, count),
               std::span(frame.normals).subspan(first, count));
  if (slot.chunks_left.fetch_sub(1, std::memory_order_acq_rel) == 1) finishMember(slot);
}

void RoomView::Impl::finishMember(MemberSlot& slot) {
  MemberFrame& frame = slot.back();
  if (slot.deformer) {
    const SkinFrame skin_frame{*slot.avatar,    frame.posture,   frame.joint_model, frame.skin,
                               frame.placement, frame.positions, frame.normals};
    slot.deformer->deform(skin_frame);
  }
  // Room-space bounds: the model-space box's corners through the placement.
  const Bounds model = computeBounds(frame.positions);
  glm::vec3 lo(std::numeric_limits<float>::max());
  glm::vec3 hi(std::numeric_limits<float>::lowest());
  for (int c = 0; c < 8; ++c) {
    const glm::vec3 corner((c & 1) ? model.max.x : model.min.x, (c & 2) ? model.max.y : model.min.y,
                           (c & 4) ? model.max.z : model.min.z);
    const glm::vec3 p(frame.placement * glm::vec4(corner, 1.0f));
    lo = glm::min(lo, p);
    hi = glm::max(hi, p);
  }
  frame.box_min = lo;
  frame.box_max = hi;
}

// Room-space bounds of a GPU-skinned member: its posed joints, swollen by the skin's reach.
void RoomView::Impl::jointBounds(MemberSlot& slot) {
  MemberFrame& frame = slot.back();
  glm::vec3 lo(std::numeric_limits<float>::max());
  glm::vec3 hi(std::numeric_limits<float>::lowest());
  for (const glm::mat4& joint : frame.joint_model) {
    const glm::vec3 p(frame.placement * joint[3]);
    lo = glm::min(lo, p);
    hi = glm::max(hi, p);
  }
  frame.box_min = lo - glm::vec3(slot.reach);
  frame.box_max = hi + glm::vec3(slot.reach);
}

void RoomView::Impl::render(std::span<const MemberView> members) {
  const Clock::time_point start = Clock::now();
  if (context) context->makeCurrent();
  stats = FrameStats{};

  // Match members to slots (by id), preparing new avatars and posing skeletons.
  for (auto& slot : slots) {
    slot->seen = false;
    slot->in_batch = false;
  }
  items.clear();
  for (const MemberView& member : members) {
    if (!member.avatar) continue;
    MemberSlot* slot = findSlot(member.id);
    if (slot != nullptr && slot->seen) continue;  // a repeated id
    if (slot == nullptr) {
      slots.push_back(std::make_unique<MemberSlot>());
      slot = slots.back().get();
      slot->id = member.id;
    }
    slot->seen = true;
    const int head_hint = headHint(member.id);
    if (slot->avatar != member.avatar || slot->head_hint != head_hint) {
      prepareSlot(*slot, member, head_hint);
    }
    if (!slot->valid) continue;
    poseBack(*slot, member);
    slot->in_batch = true;
    if (slot->back().gpu) {
      // Skinned in the vertex shader: nothing for the workers.
      jointBounds(*slot);
      slot->chunks_left.store(0, std::memory_order_relaxed);
      ++stats.members_gpu_skinned;
      stats.gpu_offsets += slot->back().has_offsets ? 1 : 0;
      continue;
    }
    const int nvert = slot->avatar->skin.vertexCount();
    int chunks = 0;
    for (int first = 0; first < nvert; first += kChunkVertices, ++chunks) {
      items.push_back(WorkItem{slot, first, std::min(kChunkVertices, nvert - first)});
    }
    slot->chunks_left.store(chunks, std::memory_order_relaxed);
    stats.vertices_skinned += nvert;
  }
  // Members that left: free their buffers.
  std::erase_if(slots, [](const std::unique_ptr<MemberSlot>& slot) { return !slot->seen; });

  // Skin everyone in the pool (this thread helps), then show the new frames.
  pool.start(*this, static_cast<int>(items.size()));
  pool.wait();
  for (auto& slot : slots) {
    if (!slot->in_batch) continue;
    slot->front = 1 - slot->front;
    slot->has_front = true;
  }
  stats.skin_ms = millisecondsSince(start);

  const Clock::time_point draw_start = Clock::now();
  if (options.headless) {
    // No GL: count the members and place the cameras (what the deformer's level of
    // detail and the tests read), draw nothing.
    for (const auto& slot : slots) stats.members_drawn += slot->has_front ? 1 : 0;
    computeCameras(glm::ivec2(options.width, options.height));
    ++frames;
  } else {
    drawFrame();
  }
  stats.draw_ms = millisecondsSince(draw_start);
}

glm::vec3 RoomView::Impl::headTop(const MemberSlot& slot) const {
  const MemberFrame& frame = slot.shown();
  return glm::vec3(frame.placement * frame.head_delta * glm::vec4(slot.head.top_rest, 1.0f));
}

void RoomView::Impl::applyInput() {
  const InputEvents input = context->takeInput();
  yaw -= input.drag.x * 0.006f;
  pitch = std::clamp(pitch + input.drag.y * 0.006f, -0.3f, 1.4f);
  zoom = std::clamp(zoom * std::pow(1.1f, input.scroll), 0.25f, 6.0f);
  if (keys.size() < 64) keys += input.keys;
  if (input.toggle_view % 2 == 1) {
    options.view = options.view == ViewMode::kRoom ? ViewMode::kFirstPerson : ViewMode::kRoom;
  }
  for (int i = 0; i < input.cycle_stereo % 3; ++i) {
    options.stereo = options.stereo == StereoMode::kOff          ? StereoMode::kSideBySide
                     : options.stereo == StereoMode::kSideBySide ? StereoMode::kAnaglyph
                                                                 : StereoMode::kOff;
  }
}

void RoomView::Impl::computeCameras(glm::ivec2 size) {
  cameras.clear();
  const bool sbs = options.stereo == StereoMode::kSideBySide;
  const int eye_width = sbs ? size.x / 2 : size.x;
  const float aspect =
      static_cast<float>(std::max(eye_width, 1)) / static_cast<float>(std::max(size.y, 1));
  const float fov = glm::radians(std::clamp(options.vertical_fov_deg, 10.0f, 150.0f));

  // Everyone's bounds (members taken out of the framing count only when nobody else is
  // drawn), and the self member.
  glm::vec3 lo(std::numeric_limits<float>::max());
  glm::vec3 hi(std::numeric_limits<float>::lowest());
  const MemberSlot* self = nullptr;
  const bool any_framed = std::any_of(slots.begin(), slots.end(), [&](const auto& slot) {
    return slot->has_front && !unframed.count(slot->id);
  });
  for (const auto& slot : slots) {
    if (!slot->has_front) continue;
    if (any_framed && unframed.count(slot->id)) continue;
    lo = glm::min(lo, slot->shown().box_min);
    hi = glm::max(hi, slot->shown().box_max);
    // Leave room for the marker and the name tag above the head.
    if (options.show_tags) hi.y = std::max(hi.y, headTop(*slot).y + kLabelLift + 0.12f);
    if (slot->shown().is_self && self == nullptr) self = slot.get();
  }
  const Sphere target_sphere =
      lo.x <= hi.x ? sphereAroundBox(lo, hi) : Sphere{glm::vec3(0.0f, 1.0f, 0.0f), 1.5f};
  // Follow the room smoothly; the followed sphere always contains the current one.
  if (!have_sphere) {
    sphere = target_sphere;
    have_sphere = true;
  } else {
    const glm::vec3 center = glm::mix(sphere.center, target_sphere.center, 0.2f);
    const float needed = target_sphere.radius + glm::length(target_sphere.center - center);
    sphere.radius = std::max(needed, glm::mix(sphere.radius, needed, 0.05f));
    sphere.center = center;
  }

  CameraPose pose;
  Lens lens;
  float focal = 2.0f;
  if (options.view == ViewMode::kFirstPerson && self != nullptr) {
    // From the self member's eyes, looking where the head faces (+Z of the model).
    const MemberFrame& frame = self->shown();
    const glm::mat4 head = frame.placement * frame.head_delta;
    const glm::vec3 eye(head * glm::vec4(self->head.eye_rest, 1.0f));
    const glm::vec3 forward = glm::mat3(head) * glm::vec3(0.0f, 0.0f, 1.0f);
    const glm::vec3 up = glm::mat3(head) * glm::vec3(0.0f, 1.0f, 0.0f);
    pose = makePose(eye, forward, up);
    lens.vertical_fov = fov;
    lens.near_plane = 0.03f;
    lens.far_plane = 80.0f;
  } else {
    // Frame the whole room from the orbit direction.
    const Sphere framed{sphere.center, sphere.radius / zoom};
    pose = frameSphere(framed, orbitDirection(yaw, pitch), fov, aspect, 0.9f, lens,
                       std::max(12.0f, 6.0f * sphere.radius));
    const float distance = glm::length(sphere.center - pose.position);
    lens.near_plane = std::max(0.05f, (distance - sphere.radius) * 0.5f);
    focal = std::max(distance - sphere.radius, 0.5f);
  }

  // One eye, or two (side by side: half widths; anaglyph: both full size).
  const float half_sep = 0.5f * options.eye_separation;
  switch (options.stereo) {
    case StereoMode::kOff:
      cameras.push_back(makeEye(pose, lens, 0.0f, focal, glm::ivec4(0, 0, size.x, size.y)));
      break;
    case StereoMode::kSideBySide:
      cameras.push_back(makeEye(pose, lens, -half_sep, focal, glm::ivec4(0, 0, eye_width, size.y)));
      cameras.push_back(makeEye(pose, lens, half_sep, focal,
                                glm::ivec4(eye_width, 0, size.x - eye_width, size.y)));
      break;
    case StereoMode::kAnaglyph:
      cameras.push_back(makeEye(pose, lens, -half_sep, focal, glm::ivec4(0, 0, size.x, size.y)));
      cameras.push_back(makeEye(pose, lens, half_sep, focal, glm::ivec4(0, 0, size.x, size.y)));
      break;
  }
}

void RoomView::Impl::drawFrame() {
  // Upload the shown vertices.
  bool any_gpu = false;
  for (auto& slot : slots) {
    if (!slot->has_front) continue;
    ++stats.members_drawn;
    const MemberFrame& shown = slot->shown();
    any_gpu = any_gpu || shown.gpu;
    if (!shown.gpu) {
      slot->mesh.upload(shown.positions, shown.normals);
    } else if (shown.has_offsets && shown.offsets.generation != slot->uploaded_offsets) {
      slot->gpu_mesh.uploadOffsets(shown.offsets.positions, shown.offsets.normals);
      slot->uploaded_offsets = shown.offsets.generation;
      ++stats.gpu_offset_uploads;
    }
  }
  const glm::ivec2 size =
      context->isWindow() ? context->framebufferSize() : glm::ivec2(options.width, options.height);
  if (size.x <= 0 || size.y <= 0) return;  // a minimised window
  if (Status status = target->resize(size.x, size.y, options.msaa_samples); !status.ok()) {
    warning = status.error().message;
    return;
  }
  applyInput();
  computeCameras(size);

  const bool anaglyph = options.stereo == StereoMode::kAnaglyph;
  const bool first_person = options.view == ViewMode::kFirstPerson;
  const float floor_extent = std::max(12.0f, 6.0f * sphere.radius);
  const glm::vec3 floor_center(sphere.center.x, 0.0f, sphere.center.z);
  target->bindForDrawing();
  glColorMask(GL_TRUE, GL_TRUE, GL_TRUE, GL_TRUE);
  if (anaglyph) scene->clearViewport(glm::ivec4(0, 0, size.x, size.y), true, true);
  for (std::size_t e = 0; e < cameras.size(); ++e) {
    const EyeCamera& eye = cameras[e];
    // Anaglyph: the left eye writes red, the right eye green and blue.
    if (anaglyph) {
      const GLboolean left = e == 0 ? GL_TRUE : GL_FALSE;
      const GLboolean right = e == 0 ? GL_FALSE : GL_TRUE;
      glColorMask(left, right, right, GL_TRUE);
      scene->clearViewport(eye.viewport, false, true);
    } else {
      scene->clearViewport(eye.viewport, true, true);
    }
    scene->drawFloor(eye, floor_center, floor_extent);

    // Shadows on the floor (the key light's, flattened meshes).
    if (options.shadows) {
      scene->beginShadows(eye);
      for (const auto& slot : slots) {
        if (!slot->has_front || slot->shown().gpu) continue;
        scene->drawMeshShadow(slot->mesh, slot->shown().placement);
      }
      if (any_gpu) {
        scene->beginSkinnedShadows(eye);
        for (const auto& slot : slots) {
          if (!slot->has_front || !slot->shown().gpu) continue;
          scene->drawSkinnedMeshShadow(slot->gpu_mesh, slot->shown().dq, slot->shown().placement,
                                       slot->shown().has_offsets);
        }
      }
      scene->endShadows();
    }

    // Skin (plain, then with a look: materials and textures, sRGB-correct), then markers
    // above heads.
    scene->beginMeshes(eye);
    bool any_look = false;
    for (const auto& slot : slots) {
      if (!slot->has_front) continue;
      if (!slot->look.empty()) {
        any_look = true;
        continue;
      }
      if (slot->shown().gpu) continue;
      scene->drawMesh(slot->mesh, slot->shown().placement,
                      tintedSkin(memberColor(static_cast<int>(slot->id))));
    }
    if (any_gpu) {
      scene->beginSkinnedMeshes(eye);
      for (const auto& slot : slots) {
        if (!slot->has_front || !slot->shown().gpu || !slot->look.empty()) continue;
        scene->drawSkinnedMesh(slot->gpu_mesh, slot->shown().dq, slot->shown().placement,
                               tintedSkin(memberColor(static_cast<int>(slot->id))),
                               slot->shown().has_offsets);
      }
    }
    if (any_look) {
      // A look is drawn as authored (no member tint: the markers and tags tell members apart).
      // Every member's opaque parts first, then the blended parts far to near, so a blended
      // part (hair cards, glasses) never hides a member drawn after it.
      const glm::vec3 white(1.0f);
      looks_by_depth.clear();
      for (const auto& slot : slots) {
        if (!slot->has_front || slot->look.empty()) continue;
        const glm::vec3 at(slot->shown().placement[3]);
        looks_by_depth.push_back({glm::distance(at, eye.position), slot.get()});
      }
      std::sort(looks_by_depth.begin(), looks_by_depth.end(),
                [](const auto& a, const auto& b) { return a.first > b.first; });
      using Pass = SceneRenderer::LookPass;
      for (const Pass pass : {Pass::kOpaque, Pass::kBlended}) {
        for (const bool gpu : {false, true}) {
          if (gpu && !any_gpu) continue;
          if (gpu) {
            scene->beginSkinnedLookMeshes(eye);
          } else {
            scene->beginLookMeshes(eye);
          }
          for (const auto& [depth, slot] : looks_by_depth) {
            if (slot->shown().gpu != gpu) continue;
            if (gpu) {
              scene->drawSkinnedMeshLook(slot->gpu_mesh, slot->look, slot->shown().dq,
                                         slot->shown().placement, white, slot->shown().has_offsets,
                                         pass);
            } else {
              scene->drawMeshLook(slot->mesh, slot->look, slot->shown().placement, white, pass);
            }
          }
        }
      }
    }
    scene->beginMeshes(eye);
    if (!options.show_tags) continue;
    for (const auto& slot : slots) {
      if (!slot->has_front || (first_person && slot->shown().is_self)) continue;
      scene->drawMarker(headTop(*slot) + glm::vec3(0.0f, kMarkerLift, 0.0f), kMarkerSize,
                        memberColor(static_cast<int>(slot->id)));
    }

    // Name tags in screen space above the markers.
    for (const auto& slot : slots) {
      if (!slot->has_front || slot->shown().name.empty()) continue;
      if (first_person && slot->shown().is_self) continue;
      glm::vec3 pixel;
      if (!projectToPixel(eye, headTop(*slot) + glm::vec3(0.0f, kLabelLift, 0.0f), pixel)) continue;
      if (pixel.z < -1.0f || pixel.z > 1.0f) continue;
      // Whole pixels, so the glyphs' one-pixel strokes stay crisp.
      const glm::vec2 local(std::round(pixel.x - static_cast<float>(eye.viewport.x)),
                            std::round(static_cast<float>(eye.viewport.w) -
                                       (pixel.y - static_cast<float>(eye.viewport.y))));
      const float scale = std::clamp(static_cast<float>(eye.viewport.w) / 360.0f, 1.0f, 3.0f);
      labels->add(local, slot->shown().name, memberColor(static_cast<int>(slot->id)), scale);
    }
    labels->draw(eye.viewport);
  }
  glColorMask(GL_TRUE, GL_TRUE, GL_TRUE, GL_TRUE);

  // Resolve; show it in the window.
  target->resolve();
  if (context->isWindow()) {
    target->blitToDefault(size.x, size.y);
    context->present();
  }
  if (std::string_view error = takeGlError(); !error.empty()) {
    warning = fmt::format("frame {}: {}", frames, error);
  }
  frame_valid = true;
  ++frames;
}

// --- RoomView ---------------------------------------------------------------------------

RoomView::RoomView(std::unique_ptr<Impl> impl) : impl_(std::move(impl)) {}
RoomView::~RoomView() = default;

Result<std::unique_ptr<RoomView>> RoomView::create(const ViewOptions& options) {
  if (options.width < 1 || options.height < 1 || options.width > 16384 || options.height > 16384) {
    return fail("room view: size {}x{} is out of range (1..16384)", options.width, options.height);
  }
  ViewOptions checked = options;
  checked.worker_threads = std::clamp(options.worker_threads, 1, 64);
  checked.msaa_samples = std::min(options.msaa_samples, 16);
  auto impl = std::make_unique<Impl>(checked);
  if (checked.headless) {
    impl->backend = "headless (no GL)";
    return std::unique_ptr<RoomView>(new RoomView(std::move(impl)));
  }

  // A window when a display exists (unless told otherwise), else EGL offscreen.
  const ContextOptions context_options{options.width, options.height, options.title, options.vsync};
  std::string window_error;
  if (!options.offscreen && displayAvailable()) {
    auto window = createGlfwWindow(context_options);
    if (window) {
      impl->context = std::move(*window);
    } else {
      window_error = window.error().message;
    }
  }
  if (!impl->context) {
    auto offscreen = createEglContext(context_options);
    if (!offscreen) {
      return fail("room view: no OpenGL available: {}{}",
                  window_error.empty() ? "" : window_error + "; then ", offscreen.error().message);
    }
    impl->context = std::move(*offscreen);
  }
  impl->backend = impl->context->description();
  if (!window_error.empty()) impl->backend += " (window failed: " + window_error + ")";
  if (currentGlVersion() < 33) {
    return fail("room view: OpenGL 3.3 core or newer needed, got {}", impl->backend);
  }

  // Multisampling where it is cheap: on a GPU, not on a software rasteriser.
  if (impl->options.msaa_samples < 0) {
    const bool software = impl->backend.find("llvmpipe") != std::string::npos ||
                          impl->backend.find("softpipe") != std::string::npos ||
                          impl->backend.find("SWR") != std::string::npos;
    impl->options.msaa_samples = software ? 0 : 4;
  }
  checked.msaa_samples = impl->options.msaa_samples;
  impl->backend += impl->options.msaa_samples > 1
                       ? fmt::format(", MSAA {}x", impl->options.msaa_samples)
                       : std::string(", no MSAA");

  // Offscreen target, programs, static meshes.
  impl->target = std::make_unique<RenderTarget>();
  const glm::ivec2 size = impl->context->isWindow() ? impl->context->framebufferSize()
                                                    : glm::ivec2(options.width, options.height);
  if (Status status =
          impl->target->resize(std::max(size.x, 1), std::max(size.y, 1), checked.msaa_samples);
      !status.ok()) {
    return withContext("room view", status.error());
  }
  impl->scene = std::make_unique<SceneRenderer>();
  if (Status status = impl->scene->init(); !status.ok()) {
    return withContext("room view", status.error());
  }
  impl->labels = std::make_unique<LabelRenderer>();
  if (Status status = impl->labels->init(); !status.ok()) {
    return withContext("room view", status.error());
  }
  return std::unique_ptr<RoomView>(new RoomView(std::move(impl)));
}

bool RoomView::shouldClose() const { return impl_->context && impl_->context->shouldClose(); }

void RoomView::pollEvents() {
  if (impl_->context) impl_->context->pollEvents();
}

std::string RoomView::takeKeyPresses() { return std::exchange(impl_->keys, std::string()); }

void RoomView::render(std::span<const MemberView> members) { impl_->render(members); }

namespace {

Status saveImpl(RoomView::Impl& impl, const std::string& path, PngSpeed speed) {
  if (!impl.context) return fail("writing PNG {}: a headless view draws no pixels", path);
  if (!impl.frame_valid) return fail("writing PNG {}: no frame has been rendered yet", path);
  impl.context->makeCurrent();
  Image image;
  impl.target->readPixels(image);
  return writePng(image, path, speed);
}

}  // namespace

Status RoomView::saveScreenshot(const std::string& png_path) {
  return saveImpl(*impl_, png_path, PngSpeed::kSmallest);
}

Status RoomView::saveFrame(const std::string& png_path) {
  return saveImpl(*impl_, png_path, PngSpeed::kFastest);
}

Result<Image> RoomView::readFrame() {
  if (!impl_->context) return fail("reading the frame: a headless view draws no pixels");
  if (!impl_->frame_valid) return fail("reading the frame: no frame has been rendered yet");
  impl_->context->makeCurrent();
  Image image;
  impl_->target->readPixels(image);
  return image;
}

int RoomView::framesRendered() const { return impl_->frames; }

int RoomView::workerThreads() const { return impl_->options.worker_threads; }

void RoomView::setDeformer(std::uint32_t member_id, std::shared_ptr<PostSkinDeformer> deformer) {
  if (deformer) {
    impl_->deformers[member_id] = std::move(deformer);
  } else {
    impl_->deformers.erase(member_id);
  }
}

void RoomView::setHeadJoint(std::uint32_t member_id, int joint) {
  impl_->head_joints[member_id] = joint;
}

void RoomView::setFramed(std::uint32_t member_id, bool framed) {
  if (framed) {
    impl_->unframed.erase(member_id);
  } else if (!impl_->unframed.count(member_id)) {
    impl_->unframed.insert(member_id);  // allocates once per member, not per frame
  }
}

void RoomView::setStereo(StereoMode stereo) { impl_->options.stereo = stereo; }
void RoomView::setViewMode(ViewMode view) { impl_->options.view = view; }
StereoMode RoomView::stereo() const { return impl_->options.stereo; }
ViewMode RoomView::viewMode() const { return impl_->options.view; }

glm::ivec2 RoomView::framebufferSize() const {
  return impl_->context && impl_->context->isWindow()
             ? impl_->context->framebufferSize()
             : glm::ivec2(impl_->options.width, impl_->options.height);
}

std::span<const EyeCamera> RoomView::lastCameras() const { return impl_->cameras; }

std::span<const glm::vec3> RoomView::skinnedPositions(std::uint32_t member_id) const {
  for (const auto& slot : impl_->slots) {
    if (slot->id == member_id && slot->has_front && !slot->shown().gpu) {
      return slot->shown().positions;
    }
  }
  return {};
}

const FrameStats& RoomView::lastStats() const { return impl_->stats; }

std::string RoomView::backendDescription() const { return impl_->backend; }

const std::string& RoomView::lastWarning() const { return impl_->warning; }

}  // namespace vistel
