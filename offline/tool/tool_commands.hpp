// The subcommands of vistel-avatar and what they share. Each subcommand lives in its own
// <name>_command.cpp with a register function declared here and called from main.cpp.
#pragma once

#include <functional>
#include <string>
#include <string_view>
#include <vector>

#include <CLI/CLI.hpp>

#include "common/avatar/avatar_model.hpp"
#include "common/base/result.hpp"

namespace vistel {

// vistel-avatar info FILE [--json]
void registerInfoCommand(CLI::App& app);
// vistel-avatar pose FILE (--bvh CLIP --frame K | --rest) [--skinning lbs|dqs|ffd|slerp]
//   --out OUT.glb
void registerPoseCommand(CLI::App& app);
// vistel-avatar default --out OUT.glb|OUT.vavatar [--primitives MAP] [--config DIR]
void registerDefaultCommand(CLI::App& app);
void registerGesturesCommand(CLI::App& app);
void registerSolveCommand(CLI::App& app);
// vistel-avatar build IN -o OUT.vavatar [--primitives MAP] [--config DIR]
void registerBuildCommand(CLI::App& app);
// vistel-avatar deform AVATAR (--bvh CLIP [--frames A:B] | --rest) [--ball X,Y,Z,R[,VX,VY,VZ]]
//   [--rigid-only] [--skinning lbs|dqs|ffd|slerp] --out OUT.glb [--forces-csv F]
void registerDeformCommand(CLI::App& app);
// vistel-avatar compare A B [--json] [--weld M] [--samples N]
void registerCompareCommand(CLI::App& app);
// vistel-avatar cut AVATAR [--band M] -o DIR [--format obj|ply] [--config DIR]
void registerCutCommand(CLI::App& app);
// vistel-avatar synthesize PARTS.toml -o OUT.glb [--source AVATAR] [--ring-spacing M]
void registerSynthesizeCommand(CLI::App& app);

// Fits `avatar`'s implicit model (build_command.cpp; shared with deform): the joint map that
// fits its skeleton from <config>/skeletons, the primitive map from `primitives`. progress
// (may be empty) gets the fraction done and the stage. adopt_free_vertices: give the free
// vertices primitives of their own (BuildOptions). The avatar is validated after.
struct BuildReport;
Status buildAvatarImplicit(AvatarModel& avatar, const std::string& primitives,
                           const std::string& config,
                           std::function<void(float, std::string_view)> progress,
                           BuildReport* report = nullptr, bool adopt_free_vertices = true);

// Runs `body` as the subcommand's action: an Error (or an escaped exception) is printed
// to stderr as "vistel-avatar <command>: error: <message>" and makes the program exit with
// status 1 (through CLI::RuntimeError, which main() turns into the exit status).
void setCommandAction(CLI::App* command, std::function<Status()> body);

// Loads an avatar from a .glb/.gltf (glTF import) or .vavatar file, chosen by the file's
// first bytes (the extension when they do not tell). Import warnings are appended to
// `warnings` when it is given.
Result<AvatarModel> loadAvatarFile(const std::string& path,
                                   std::vector<std::string>* warnings = nullptr);

}  // namespace vistel
