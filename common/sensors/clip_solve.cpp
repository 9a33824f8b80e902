#include "common/sensors/clip_solve.hpp"

#include <cmath>

#include "common/motion/auto_joint_map.hpp"

namespace vistel {

Result<ClipBody> makeClipBody(MotionClip clip, std::span<const JointMap> maps) {
  ClipBody body;
  body.skeleton = clipSkeleton(clip);
  Result<JointMapChoice> map = chooseJointMap(maps, body.skeleton);  // config map, else inferred
  if (!map)
    return withContext(fmt::format("{}: no joint map fits the clip", clip.source), map.error());
  Result<JointRoles> roles = resolveJointRoles(body.skeleton, &map->map);
  if (!roles) return withContext(clip.source, roles.error());
  body.roles = *roles;
  body.map_name = map->map.name;
  body.clip = std::move(clip);
  return body;
}

Result<ClipBody> loadClipBody(const std::string& bvh_path, const std::string& config_dir) {
  Result<MotionClip> clip = loadBvh(bvh_path);
  if (!clip) return clip.error();
  Result<std::vector<JointMap>> maps = loadJointMaps(config_dir);
  if (!maps) return maps.error();
  return makeClipBody(std::move(*clip), *maps);
}

PostureSampler clipSampler(const MotionClip& clip) {
  return [&clip](double t, Posture& out) { samplePostureAt(clip, t, out); };
}

std::vector<Posture> clipPostures(const MotionClip& clip) {
  std::vector<Posture> out(static_cast<std::size_t>(clip.frame_count));
  for (int k = 0; k < clip.frame_count; ++k)
    samplePosture(clip, k, out[static_cast<std::size_t>(k)]);
  return out;
}

Result<SimulatedClip> simulateClip(const ClipBody& body, const ClipSolveOptions& options) {
  if (body.clip.frame_count <= 0) return fail("{}: the clip has no frames", body.clip.source);
  if (!(options.calibration_s > 0.0) || options.calibration_s > options.hold_s + 1e-9) {
    return fail("calibration window {} s must be positive and within the hold ({} s)",
                options.calibration_s, options.hold_s);
  }
  SimOptions sim_options = options.sim;
  sim_options.hold_s = options.hold_s;
  const double last = (body.clip.frame_count - 1) * body.clip.frame_time;
  Result<std::unique_ptr<RigSimulator>> sim =
      RigSimulator::create(body.skeleton, body.roles, clipSampler(body.clip), last, sim_options);
  if (!sim) return sim.error();
  SimulatedClip out;
  out.calibration_posture = (*sim)->calibrationPosture();
  SensorFrame frame;
  int next = 0;
  const double tick = (*sim)->tickInterval();
  while ((*sim)->poll(0.0, frame).isFrame()) {
    const double body_t = frame.time - options.hold_s;
    if (body_t < -0.5 * tick) {
      // Standing still: the calibration window is the end of the hold.
      if (frame.time >= options.hold_s - options.calibration_s - 1e-9)
        out.calibration.push_back(frame);
      continue;
    }
    out.frames.push_back(frame);
    // This tick stands for every clip frame whose time it has reached.
    int emitted = -1;
    while (next < body.clip.frame_count && next * body.clip.frame_time <= body_t + 0.5 * tick) {
      emitted = next++;
    }
    out.clip_frame.push_back(emitted);
  }
  // Clip frames past the last tick (rounding) take the last tick.
  if (next < body.clip.frame_count && !out.clip_frame.empty())
    out.clip_frame.back() = body.clip.frame_count - 1;
  if (out.calibration.empty()) return fail("no sensor frames in the calibration window");
  return out;
}

Result<ClipSolveResult> solveClip(const ClipBody& body, const ClipSolveOptions& options) {
  Result<SimulatedClip> sim = simulateClip(body, options);
  if (!sim) return sim.error();
  Result<BodyCalibration> cal =
      calibrateBody(body.skeleton, body.roles, sim->calibration_posture, sim->calibration, {});
  if (!cal) return cal.error();
  Result<PostureSolver> solver =
      PostureSolver::create(body.skeleton, body.roles, *cal, options.solver);
  if (!solver) return solver.error();
  ClipSolveResult out;
  out.calibration = std::move(*cal);
  out.postures.resize(static_cast<std::size_t>(body.clip.frame_count));
  Posture posture;
  // The solver runs while the participant holds still for calibration (as it does live), so
  // its filters have settled when the clip starts moving.
  for (const SensorFrame& frame : sim->calibration) solver->solve(frame, posture);
  int filled = 0;
  for (std::size_t i = 0; i < sim->frames.size(); ++i) {
    solver->solve(sim->frames[i], posture);
    ++out.solver_calls;
    // A tick may complete several clip frames (a clip faster than the rig): all get it.
    const int k = sim->clip_frame[i];
    while (k >= 0 && filled <= k) out.postures[static_cast<std::size_t>(filled++)] = posture;
  }
  while (filled < body.clip.frame_count) out.postures[static_cast<std::size_t>(filled++)] = posture;
  return out;
}

}  // namespace vistel
