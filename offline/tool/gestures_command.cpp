// vistel-avatar gestures --out-dir DIR: the project's bundled keyframed gesture clips
// (wave, point, clap, idle) as BVH files, for bots and the demo.
#include <filesystem>
#include <memory>

#include <fmt/format.h>

#include "offline/gestures/gestures.hpp"
#include "offline/tool/tool_commands.hpp"

namespace vistel {

void registerGesturesCommand(CLI::App& app) {
  auto out_dir = std::make_shared<std::string>();
  CLI::App* cmd = app.add_subcommand(
      "gestures", "Write the bundled gesture clips (wave, point, clap, idle) as BVH files");
  cmd->add_option("--out-dir", *out_dir, "folder to write <name>.bvh into (created if missing)")
      ->required();
  setCommandAction(cmd, [out_dir]() -> Status {
    std::error_code ec;
    std::filesystem::create_directories(*out_dir, ec);
    if (ec) return fail("{}: cannot create folder: {}", *out_dir, ec.message());
    if (Status s = writeBundledGestures(*out_dir); !s) return s;
    fmt::print("wrote the bundled gestures into {}\n", *out_dir);
    return {};
  });
}

}  // namespace vistel
