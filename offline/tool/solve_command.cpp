// vistel-avatar solve --bvh CLIP --out SOLVED.bvh [--noise default|none] [--seated|--standing]
// [--feet] [--seed N]: the clip's own skeleton as the participant's body wears the four
// simulated trackers (six with --feet: one on each foot too, 240 Hz shared) and gloves with
// neutral fingers; calibration on the first pose, the posture
// solver on every tick; the solved motion written with the clip's hierarchy and frame rate,
// so it can be compared with the clip joint by joint. Prints the scores it measured.
#include <memory>
#include <string>

#include <fmt/format.h>

#include "common/base/file.hpp"
#include "common/motion/bvh.hpp"
#include "common/sensors/clip_solve.hpp"
#include "common/sensors/posture_metrics.hpp"
#include "offline/tool/tool_commands.hpp"

namespace vistel {
namespace {

struct SolveCommandOptions {
  std::string bvh;
  std::string out;
  std::string noise = "default";
  bool seated = false;
  bool standing = false;
  bool feet = false;
  std::uint64_t seed = 1;
  std::string config = "config";
};

Status runSolve(const SolveCommandOptions& opt) {
  Result<ClipBody> body = loadClipBody(opt.bvh, opt.config);
  if (!body) return body.error();
  ClipSolveOptions options;
  options.sim.seed = opt.seed;
  if (opt.noise == "none") {
    options.sim.position_noise_m = 0.0f;
    options.sim.orientation_noise_deg = 0.0f;
  }
  options.solver.stance = opt.seated ? Stance::kSeated : Stance::kStanding;
  if (opt.feet) {
    // Six stations sharing the tracker: 240 Hz keeps the four at 30 Hz each (bench_posture's
    // /sensors:6 rows).
    options.sim.foot_trackers = true;
    options.sim.rate_hz = 240.0;
  }
  Result<ClipSolveResult> solved = solveClip(*body, options);
  if (!solved) return withContext(opt.bvh, solved.error());

  const MotionClip& clip = body->clip;
  const MotionClip out =
      clipFromPostures(body->skeleton, solved->postures, clip.frame_time, clip.unit_scale, opt.out);
  if (Status s = writeFileText(opt.out, writeBvh(out)); !s) return s;

  const PostureMetrics m = measurePostures(body->skeleton, body->roles, clipPostures(clip),
                                           solved->postures, clip.frame_time);
  fmt::print("wrote {}: {} frames at {:.0f} fps, {} joints (joint map {}), noise {}, {}\n", opt.out,
             clip.frame_count, 1.0 / clip.frame_time, body->skeleton.jointCount(), body->map_name,
             opt.noise, opt.seated ? "seated" : "standing");
  fmt::print(
      "against the clip: MPJPE upper body {:.2f} cm, legs {:.2f} cm, all joints {:.2f} cm; MPJRE "
      "{:.2f} deg; jerk solved {:.1f} vs clip {:.1f} m/s^3\n",
      m.mpjpe_upper_m * 100.0, m.mpjpe_legs_m * 100.0, m.mpjpe_all_m * 100.0, m.mpjre_all_deg,
      m.jerk_solved, m.jerk_truth);
  std::fflush(stdout);
  return {};
}

}  // namespace

void registerSolveCommand(CLI::App& app) {
  auto opt = std::make_shared<SolveCommandOptions>();
  CLI::App* cmd =
      app.add_subcommand("solve",
                         "Simulate the four trackers (six with --feet) on a BVH clip's own body, "
                         "calibrate, solve every frame and "
                         "write the solved motion (same hierarchy and frame rate) as BVH");
  cmd->add_option("--bvh", opt->bvh, "BVH motion clip (the participant's body and motion)")
      ->required();
  cmd->add_option("--out", opt->out, "output .bvh file")->required();
  cmd->add_option("--noise", opt->noise, "tracker noise: default (FASTRAK-like) or none")
      ->check(CLI::IsMember({"default", "none"}))
      ->capture_default_str();
  CLI::Option* seated = cmd->add_flag("--seated", opt->seated, "legs by the seated heuristic");
  cmd->add_flag("--feet", opt->feet, "a tracker on each foot too (six sensors)");
  CLI::Option* standing =
      cmd->add_flag("--standing", opt->standing, "legs by the standing heuristic (default)");
  seated->excludes(standing);
  cmd->add_option("--seed", opt->seed, "noise seed")->capture_default_str();
  cmd->add_option("--config", opt->config, "config folder with skeletons/*.toml joint maps")
      ->capture_default_str();
  setCommandAction(cmd, [opt]() { return runSolve(*opt); });
}

}  // namespace vistel
