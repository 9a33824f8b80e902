// RoomView: draws everyone in one shared room (DESIGN.md §1, §6 "Threads").
//
// Per frame, for every member: pose the skeleton (or take the pose its deformer already
// made: PostSkinDeformer::copyPose), skin the mesh (ViewOptions::skinning: dual
// quaternions, Kavan et al. 2007, by default; or LBS, the spine lattice, rigid + slerp) in
// a worker pool into that member's double-buffered vertex arrays (sized once per avatar; no
// allocation per frame after warm-up), run the member's optional post-skin deformer (the
// deformable component's hook) — or, with gpu_skinning, leave the skinning of members that
// need no CPU vertices to the vertex shader — then upload and draw: lit skin with a
// per-member tint, a checker floor, a marker and a name tag above each head, a camera that
// frames the room or sits in the self member's head, optionally in
// stereo (side by side or red/cyan anaglyph).
//
// Threads: create(), render() and every other member function must be called from the
// thread that called create() (it owns the GL context). The worker threads only skin
// and run deformers. Skinned vertices do not depend on the number of worker threads.
//
// Display: a GLFW window when $DISPLAY (or $WAYLAND_DISPLAY) is set and
// options.offscreen is false; otherwise an EGL surfaceless context (Mesa) rendering
// into an offscreen framebuffer. GLFW is initialised only when a window is made. With
// options.headless there is no GL at all: render() poses, skins and deforms every member
// and places the cameras, but draws nothing (the CPU work of a frame, for benchmarks and
// tests on machines without GL).
#pragma once

#include <cstdint>
#include <memory>
#include <span>
#include <string>
#include <vector>

#include <glm/glm.hpp>

#include "client/render/camera.hpp"  // EyeCamera
#include "client/render/image.hpp"   // Image
#include "common/anim/posture.hpp"
#include "common/anim/skinning.hpp"
#include "common/avatar/avatar_model.hpp"
#include "common/base/result.hpp"

namespace vistel {

enum class StereoMode { kOff, kSideBySide, kAnaglyph };
enum class ViewMode { kRoom, kFirstPerson };

// What a post-skin deformer sees for one member, on a worker thread, after rigid
// skinning. Spaces: model space of the avatar (metres, +Y up); `placement` takes model
// space to room space.
struct SkinFrame {
  const AvatarModel& avatar;
  const Posture& posture;
  std::span<const glm::mat4> joint_model;  // posed joint transforms, model space (njoint)
  std::span<const glm::mat4> skin;         // skinning matrices, bind -> posed (njoint)
  glm::mat4 placement;                     // model -> room
  std::span<glm::vec3> positions;          // rigidly skinned positions (nvert); edit in place
  std::span<glm::vec3> normals;            // unit normals (nvert); edit in place
};

// Fixed model-space offsets a deformer adds to a member's rigid skinning (see
// PostSkinDeformer::offsetsOnly).
struct SkinOffsets {
  std::span<const glm::vec3> positions;  // added to the skinned positions (nvert)
  std::span<const glm::vec3> normals;    // added to the skinned normals, then normalised (nvert)
  std::uint64_t generation = 0;          // changes whenever the contents change (never 0)
};

// The hook for the deformable component: runs after skinning on each member that has
// one. One instance per member (it may keep per-member state such as elastic memory);
// deform() for different members may run concurrently on different worker threads,
// never twice at once for one member. It must not touch GL and should not allocate
// per frame.
class PostSkinDeformer {
 public:
  virtual ~PostSkinDeformer() = default;
  virtual void deform(const SkinFrame& frame) = 0;
  // Optional, on the view's thread before the member is skinned: when the deformer has
  // already posed this very posture this frame (DeformScene::prepare poses every body for
  // Step 1), it copies the posed joint transforms and skinning matrices (model space,
  // njoint each) into the spans and returns true, and the view does not pose the member
  // again. The default returns false (the view poses).
  virtual bool copyPose(const Posture& /*posture*/, std::span<glm::mat4> /*joint_model*/,
                        std::span<glm::mat4> /*skin*/) {
    return false;
  }
  // Optional, on the view's thread before the member is skinned: false when deform()
  // would leave this frame's vertices as they are (e.g. a body the level of detail draws
  // rigid), so that a view with gpu_skinning may skin the member in the vertex shader and
  // not call deform() this frame. The default: true.
  virtual bool needsVertices() { return true; }
  // Optional, on the view's thread before the member is skinned (after needsVertices()
  // said true): true when this frame deform() would only add fixed offsets to the rigid
  // skinning (a body between two deformations); `out` then holds them, valid until the
  // next render(). A view with gpu_skinning then adds them in the vertex shader, uploading
  // them only when their generation changes, and does not call deform(). Default: false.
  virtual bool offsetsOnly(SkinOffsets& /*out*/) { return false; }
};

// One member as the view draws it. Exactly these six fields, so that positional
// aggregate initialisation stays warning-free (-Wmissing-field-initializers); per-member
// extras are set on the view (setDeformer, setHeadJoint, setFramed).
struct MemberView {
  std::uint32_t id = 0;                       // stable member id (caches are keyed by it)
  std::string name;                           // drawn in the name tag (empty: no tag)
  std::shared_ptr<const AvatarModel> avatar;  // shared read-only; null = not drawn
  Posture posture;                            // on the avatar's skeleton; one that does not
                                              // fit it (rotation count, non-finite) is
                                              // drawn at rest and counted in FrameStats
  glm::mat4 placement{1.0f};                  // model -> room transform (rigid)
  bool is_self = false;                       // the first-person camera uses this member
};

struct ViewOptions {
  int width = 1280;  // offscreen: the framebuffer size; window: the initial size (pixels)
  int height = 720;
  bool offscreen = false;  // force EGL offscreen even when a display exists
  StereoMode stereo = StereoMode::kOff;
  ViewMode view = ViewMode::kRoom;
  int worker_threads = 2;  // threads that skin, counting the calling thread (1 = all on it)
  std::string title = "vistel";
  // Additions:
  int msaa_samples = -1;           // -1 = auto: 4 on a GPU, none on a software rasteriser (Mesa
                                   // llvmpipe, where 4x multiplies the draw time by 3-6); 0 or 1 =
                                   // none; else clamped to what the driver allows
  float eye_separation = 0.064f;   // stereo interocular distance, metres
  float vertical_fov_deg = 50.0f;  // camera field of view (vertical, degrees)
  bool vsync = true;               // window only
  bool show_tags = true;           // markers and name tags above heads
  bool shadows = true;             // planar shadows of the avatars on the floor (key light)
  bool headless = false;           // no GL: render() skins, deforms and places cameras only
  // Rigid skinning in the vertex shader for members that need no CPU vertices this frame
  // (no deformer, or one whose needsVertices() is false, or whose offsetsOnly() gives the
  // offsets to add in the shader) and whose avatar fits the GPU path
  // (at most 4 influences, kMaxGpuSkinJoints joints): the CPU then only poses them, their
  // skinnedPositions() are empty, and their bounds (camera framing) come from the posed
  // joints. Headless, such members are not skinned at all (a GPU client's CPU work).
  bool gpu_skinning = false;
  // The rigid component (common/anim/skinning_rig.hpp), built per avatar when it first
  // appears (kSpineFfd takes the member's head joint, see setHeadJoint, and falls back to
  // DQS with a lastWarning() where the skeleton has no spine). The vertex shader does DQS
  // only: with any other method members are skinned on the CPU whatever gpu_skinning says.
  SkinningMethod skinning = SkinningMethod::kDualQuaternion;
};

// Timings and counts of the last frame (milliseconds of wall time on the calling thread).
struct FrameStats {
  int members_drawn = 0;
  int vertices_skinned = 0;
  int postures_at_rest = 0;     // members whose posture did not fit their skeleton
  double skin_ms = 0.0;         // pose + skin + deform (worker pool, waited for)
  double draw_ms = 0.0;         // upload + draw calls + resolve (+ present in a window)
  int poses_copied = 0;         // members whose pose came from their deformer (copyPose)
  int members_gpu_skinned = 0;  // members skinned in the vertex shader (gpu_skinning)
  int gpu_offsets = 0;          // of which with a deformer's offsets (offsetsOnly)
  int gpu_offset_uploads = 0;   // offsets uploaded (changed since the member's last upload)
};

class RoomView {
 public:
  // Opens the window or the offscreen context and compiles the shaders. Fails with an
  // Error (never a crash) when neither a display nor EGL works, or GL is below 3.3 core.
  static Result<std::unique_ptr<RoomView>> create(const ViewOptions& options);
  ~RoomView();
  RoomView(const RoomView&) = delete;
  RoomView& operator=(const RoomView&) = delete;

  // Window closed by the user (or Escape). Always false offscreen and headless.
  bool shouldClose() const;
  // Handles window events (resize, mouse orbit/zoom, keys: V view mode, B stereo
  // cycle, Escape). No-op offscreen.
  void pollEvents();
  // The window's other printable keys pressed since the last call, oldest first, as GLFW
  // names them ('A'..'Z' upper case, '0'..'9'); seen by render(), so a press shows up
  // after the next frame. Always empty offscreen.
  std::string takeKeyPresses();

  // Skins and draws one frame of these members (their order does not matter; ids must
  // be unique — a repeated id is drawn once). Members absent from a later call have
  // their buffers freed. In a window the frame is presented (swap buffers).
  void render(std::span<const MemberView> members);

  // Writes the last rendered frame as PNG (width x height of the framebuffer, rows from
  // the top). saveScreenshot uses the best compression, saveFrame the fastest (for
  // frame sequences). Errors name the path. Before the first render() or headless: an
  // error.
  Status saveScreenshot(const std::string& png_path);
  Status saveFrame(const std::string& png_path);
  // The last rendered frame's pixels.
  Result<Image> readFrame();

  int framesRendered() const;
  // Threads that skin, the calling thread included (ViewOptions::worker_threads, clamped).
  int workerThreads() const;

  // The post-skin deformer of a member id (null removes it). Kept by id until replaced,
  // also across the member leaving and coming back.
  void setDeformer(std::uint32_t member_id, std::shared_ptr<PostSkinDeformer> deformer);
  // The head joint of a member's avatar when the caller knows it; -1 (the default) =
  // find it: the canonical "head" of the joint map (config/skeletons) that fits the
  // skeleton, else a joint named "head" in any case, else a name containing "head", else
  // the topmost joint at rest. Out-of-range indices fall back to the search.
  void setHeadJoint(std::uint32_t member_id, int joint);
  // Whether the room camera keeps this member in the picture (default: yes). Props are
  // drawn but not framed, so a ball that bounces away does not zoom the room out; when
  // nothing framed is drawn, everything is.
  void setFramed(std::uint32_t member_id, bool framed);

  // Changing modes between frames (the window's keys do the same).
  void setStereo(StereoMode stereo);
  void setViewMode(ViewMode view);
  StereoMode stereo() const;
  ViewMode viewMode() const;

  // Framebuffer size in pixels (follows the window's size).
  glm::ivec2 framebufferSize() const;
  // The last frame's eye cameras: one (kOff) or two (left, right).
  std::span<const EyeCamera> lastCameras() const;
  // The last frame's skinned (and deformed) vertices of a member, model space; empty if
  // the member was not drawn or was skinned on the GPU. Valid until the next render().
  std::span<const glm::vec3> skinnedPositions(std::uint32_t member_id) const;
  const FrameStats& lastStats() const;
  // "EGL surfaceless ..." or "GLFW window", and the GL version and renderer strings
  // ("headless (no GL)" without GL).
  std::string backendDescription() const;
  // The latest problem met while drawing (an avatar that failed validation and is not
  // drawn, a framebuffer that could not be made), or empty.
  const std::string& lastWarning() const;

  struct Impl;

 private:
  explicit RoomView(std::unique_ptr<Impl> impl);
  std::unique_ptr<Impl> impl_;
};

}  // namespace vistel
