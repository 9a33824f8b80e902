// Running vistel-avatar and the Khronos glTF validator from tests.
#pragma once

#include <optional>
#include <string>
#include <string_view>

#include <nlohmann/json.hpp>

namespace vistel::test {

// The shared MakeHuman avatar, relative to the shared data folder.
inline constexpr const char* kMakeHumanGlb = "avatars/makehuman_game_engine.glb";

struct ToolRun {
  int exit_code = -1;    // the program's exit status (>= 128: killed by a signal)
  std::string out, err;  // what it printed
};

// Runs `<build>/vistel-avatar <args>` (args are passed to the shell as written), capturing
// stdout and stderr in files under `dir`.
ToolRun runTool(const std::string& args, const std::string& dir);

// A failed run: non-zero exit, not a crash, a message on stderr containing `fragment`.
void expectToolFailure(const ToolRun& run, std::string_view fragment = "");

// The validator's verdict on a .glb: its JSON line ({"errors": N, "warnings": M, ...}), or
// nothing when node/npm or the shared tools are unavailable or the validator could not be
// installed; `why` then says which.
std::optional<nlohmann::json> validateGltf(const std::string& path, std::string& why);

}  // namespace vistel::test

// Skips the test (with the reason) when the validator is unavailable; else sets `var` to
// its verdict on `path`.
#define VISTEL_VALIDATE_OR_SKIP(var, path)                              \
  std::string var##_why;                                                \
  const auto var##_opt = ::vistel::test::validateGltf(path, var##_why); \
  if (!var##_opt) GTEST_SKIP() << var##_why;                            \
  const nlohmann::json& var = *var##_opt
