// vistel-avatar: inspect, pose, build and export avatars (offline).
//
// Subcommands are registered from their own files (see tool_commands.hpp); adding one is
// a new <name>_command.cpp and one line below.
#include <exception>
#include <iostream>

#include <CLI/CLI.hpp>

#include "common/wire/packets.hpp"
#include "offline/tool/tool_commands.hpp"
#include "vistel_version.hpp"

int main(int argc, char** argv) {
  CLI::App app{"vistel-avatar: inspect, pose, build and export vistel avatars"};
  // Avatars travel to the server and peers: the version names the datagram wire it matches.
  app.set_version_flag("--version", "vistel-avatar " + std::string(vistel::kVistelVersion) +
                                        " (datagram wire " +
                                        std::to_string(vistel::wire::kWireVersion) + ")");
  app.require_subcommand(1);
  vistel::registerInfoCommand(app);
  vistel::registerPoseCommand(app);
  vistel::registerDefaultCommand(app);
  vistel::registerGesturesCommand(app);
  vistel::registerSolveCommand(app);
  vistel::registerBuildCommand(app);
  vistel::registerDeformCommand(app);
  vistel::registerCompareCommand(app);
  vistel::registerCutCommand(app);
  vistel::registerSynthesizeCommand(app);
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    return app.exit(e);
  } catch (const std::exception& e) {
    std::cerr << "vistel-avatar: error: " << e.what() << std::endl;
    return 1;
  }
  return 0;
}
