#include "tests/tool/tool_runner.hpp"

#include <sys/wait.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>

#include <gtest/gtest.h>

#include "tests/support/test_support.hpp"

namespace vistel::test {
namespace {

std::string slurp(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

int exitCode(int status) {
  if (status == -1) return -1;
  if (WIFEXITED(status)) return WEXITSTATUS(status);
  return 128 + WTERMSIG(status);
}

}  // namespace

ToolRun runTool(const std::string& args, const std::string& dir) {
  const std::string out = dir + "/tool.out", err = dir + "/tool.err";
  const std::string command = binaryDir() + "/vistel-avatar " + args + " > " + out + " 2> " + err;
  ToolRun run;
  run.exit_code = exitCode(std::system(command.c_str()));
  run.out = slurp(out);
  run.err = slurp(err);
  return run;
}

std::optional<nlohmann::json> validateGltf(const std::string& path, std::string& why) {
  const std::string tool = sharedDataPath("../tools/gltf-validate");
  if (!std::filesystem::exists(tool)) {
    why = "glTF validator not found: " + tool + " (shared/ is absent)";
    return std::nullopt;
  }
  if (std::system("command -v node > /dev/null 2>&1 && command -v npm > /dev/null 2>&1") != 0) {
    why = "node/npm are not installed: cannot run the Khronos glTF validator";
    return std::nullopt;
  }
  const std::string out = path + ".validation.json";
  const int code = exitCode(std::system((tool + " " + path + " > " + out + " 2>&1").c_str()));
  const std::string text = slurp(out);
  nlohmann::json verdict = nlohmann::json::parse(text, nullptr, false);
  if (verdict.is_discarded() || !verdict.is_object() || !verdict.contains("errors")) {
    why = "the glTF validator did not run (npm install failed?); exit " + std::to_string(code) +
          ", output: " + text.substr(0, 300);
    return std::nullopt;
  }
  return verdict;
}

void expectToolFailure(const ToolRun& run, std::string_view fragment) {
  EXPECT_NE(run.exit_code, 0) << run.out;
  EXPECT_GT(run.exit_code, 0);
  EXPECT_LT(run.exit_code, 128) << "crashed: " << run.err;
  EXPECT_FALSE(run.err.empty());
  EXPECT_NE(run.err.find(fragment), std::string::npos)
      << "expected '" << fragment << "' in: " << run.err;
}

}  // namespace vistel::test
