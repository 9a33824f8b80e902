// OwnForces: where vistel-client sends its own avatar's contact force per body part each
// frame (issue 25 item 10) — the --stats-json summary, the --forces-out CSV stream
// (client/deform/force_log.hpp) and a force-feedback device named by the sensors config's
// [force_feedback] section (common/sensors/io/force_feedback.hpp).
//
// Each rendered frame, after RoomDeformer::finish(), frame() computes the forces of the self
// member's body (client/deform/part_forces.hpp; model space, newtons) and hands them on. A
// frame in which the own body was not deformed (no deformable component, the body not drawn
// yet, a rigid level of detail) counts as no contact. Render thread only.
#pragma once

#include <cstdint>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "client/deform/force_log.hpp"
#include "client/deform/part_forces.hpp"
#include "client/deform/room_deformer.hpp"
#include "common/avatar/avatar_model.hpp"
#include "common/base/result.hpp"
#include "common/sensors/io/force_feedback.hpp"
#include "common/sensors/sensor_config.hpp"

namespace vistel {

struct OwnForcesOptions {
  std::string csv_path;                 // --forces-out (empty: none)
  std::string force_feedback_config;    // a sensors config; its [force_feedback] (empty: none)
  double frame_rate_hz = 60.0;          // the device gets at most this many reports per second
  bool require_force_feedback = false;  // warn when the config has no [force_feedback]
};

class OwnForces {
 public:
  // Fails when the own avatar has no body parts (no implicit model), the CSV cannot be
  // written or the config does not parse. A force-feedback device that cannot be opened, a
  // config without [force_feedback], and channels naming parts the avatar lacks are
  // warnings (warnings()), not failures: the client runs on without them.
  static Result<std::unique_ptr<OwnForces>> create(const AvatarModel& own,
                                                   const OwnForcesOptions& options);
  // As create(), with a given device (tests; null: none) for the config's channels.
  static Result<std::unique_ptr<OwnForces>> create(const AvatarModel& own,
                                                   const OwnForcesOptions& options,
                                                   std::unique_ptr<HidOutputDevice> device);

  // One frame: the forces of `self_view`'s body in `deformer` (null, or nullopt: none) at
  // time `now` (seconds). Problems (a write failing) are returned once; the frame goes on.
  Status frame(double now, const RoomDeformer* deformer, std::optional<std::uint32_t> self_view);
  // Flushes the CSV and releases the device (an all-zero report). Idempotent.
  Status close();

  const std::vector<std::string>& warnings() const { return warnings_; }
  std::span<const PartForce> lastForces() const { return forces_; }
  const PartForceLayout& layout() const { return layout_; }
  // The --stats-json member ("own_forces": {...}).
  std::string json() const { return log_.json(); }
  // One line for the exit report.
  std::string summary() const;

 private:
  OwnForces(PartForceLayout layout);

  PartForceLayout layout_;
  std::vector<PartForce> forces_;         // (npart) this frame's
  std::vector<glm::vec3> force_vectors_;  // (npart) the same, for the device
  ForceLog log_;
  std::unique_ptr<ForceFeedbackWriter> device_;
  std::vector<std::string> warnings_;
};

}  // namespace vistel
