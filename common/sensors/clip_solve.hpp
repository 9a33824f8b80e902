// Solving a mocap clip through the simulated rig: the clip's own skeleton is the
// participant's body; the four trackers (and the gloves) are simulated from it; the solver
// calibrates on the first frames (the body holds the clip's first pose for hold_s) and
// solves every tick; the posture at each clip frame is kept. What `vistel-avatar solve` and
// bench_posture run.
#pragma once

#include <string>
#include <vector>

#include "common/anim/posture.hpp"
#include "common/anim/skeleton.hpp"
#include "common/base/result.hpp"
#include "common/motion/bvh.hpp"
#include "common/motion/joint_map.hpp"
#include "common/sensors/body_roles.hpp"
#include "common/sensors/calibration.hpp"
#include "common/sensors/posture_metrics.hpp"
#include "common/sensors/posture_solver.hpp"
#include "common/sensors/rig_simulator.hpp"

namespace vistel {

// A clip with its skeleton (metres) and the roles of its joints.
struct ClipBody {
  MotionClip clip;
  Skeleton skeleton;
  JointRoles roles{};
  std::string map_name;  // the joint map that fitted
};

// Loads a BVH and finds its joint map among config_dir/skeletons (or the embedded maps).
Result<ClipBody> loadClipBody(const std::string& bvh_path,
                              const std::string& config_dir = "config");
Result<ClipBody> makeClipBody(MotionClip clip, std::span<const JointMap> maps);

// A sampler of the clip's body at time t (clamped to the clip).
PostureSampler clipSampler(const MotionClip& clip);

struct ClipSolveOptions {
  SimOptions sim;  // noise, latency, rate, mounts, seed; hold_s is set from below
  SolverOptions solver;
  double hold_s = 0.5;         // the body stands in its first pose this long
  double calibration_s = 0.4;  // ... and calibration averages the frames of this window
};

// The simulated frames of a clip: those of the calibration window, then every tick while the
// body moves, with the clip frame (or -1) each tick completes.
struct SimulatedClip {
  std::vector<SensorFrame> calibration;
  std::vector<SensorFrame> frames;
  std::vector<int> clip_frame;  // (frames.size()) clip frame index emitted at this tick, or -1
  Posture calibration_posture;
};
Result<SimulatedClip> simulateClip(const ClipBody& body, const ClipSolveOptions& options);

struct ClipSolveResult {
  std::vector<Posture> postures;  // one per clip frame
  BodyCalibration calibration;
  std::size_t solver_calls = 0;
};
Result<ClipSolveResult> solveClip(const ClipBody& body, const ClipSolveOptions& options);

// The clip's own postures, one per frame (the ground truth).
std::vector<Posture> clipPostures(const MotionClip& clip);

}  // namespace vistel
