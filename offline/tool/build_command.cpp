// vistel-avatar build IN -o OUT.vavatar [--primitives MAP] [--config DIR]: imports an avatar
// (.glb, .gltf or .vavatar), fits its implicit model (DESIGN.md §3: primitives chosen by the
// map, vertex classes, combination graph, calibration) and writes a .vavatar that is then
// loaded back, validated and compared byte for byte with what was written.
//
// Progress goes to stderr: a bar redrawn in place (stage, percent, elapsed time) when stderr
// is a terminal, one plain line per stage otherwise (logs, tests).
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <condition_variable>
#include <cstdio>
#include <filesystem>
#include <memory>
#include <mutex>
#include <string>
#include <thread>

#include <fmt/format.h>

#include "common/avatar/avatar_io.hpp"
#include "common/base/file.hpp"
#include "common/motion/auto_joint_map.hpp"
#include "common/motion/joint_map.hpp"
#include "offline/build/build_model.hpp"
#include "offline/build/server_limits.hpp"
#include "offline/gltf/gltf_look.hpp"
#include "offline/tool/tool_commands.hpp"

namespace vistel {
namespace {

using Clock = std::chrono::steady_clock;

// Stage and percent on stderr. On a terminal a ticker thread redraws the bar every 100 ms
// so the elapsed time moves during long stages; elsewhere each new stage is one line.
class Progress {
 public:
  explicit Progress(std::string label)
      : label_(std::move(label)), tty_(isatty(STDERR_FILENO) == 1), start_(Clock::now()) {
    if (tty_) ticker_ = std::thread([this] { tick(); });
  }
  ~Progress() { finish(); }
  Progress(const Progress&) = delete;
  Progress& operator=(const Progress&) = delete;

  // fraction: 0..1 of the whole job; stage: what runs now.
  void update(float fraction, std::string_view stage) {
    std::lock_guard lock(mutex_);
    fraction_ = std::clamp(fraction, 0.0f, 1.0f);
    if (stage != stage_) {
      stage_ = std::string(stage);
      if (!tty_) std::fprintf(stderr, "%s: %3d%% %s\n", label_.c_str(), percent(), stage_.c_str());
    }
    if (tty_) draw();
  }

  // Ends the bar (its line stays, completed) and stops the ticker.
  void finish() {
    {
      std::lock_guard lock(mutex_);
      if (done_) return;
      done_ = true;
      if (tty_) {
        draw();
        std::fputc('\n', stderr);
      }
    }
    wake_.notify_all();
    if (ticker_.joinable()) ticker_.join();
  }

 private:
  int percent() const { return static_cast<int>(fraction_ * 100.0f + 0.5f); }

  // One line, redrawn in place: "label [#####.....]  50%  stage  1.2 s".
  void draw() {
    constexpr int kWidth = 30;
    const int filled = static_cast<int>(fraction_ * kWidth + 0.5f);
    const double seconds = std::chrono::duration<double>(Clock::now() - start_).count();
    std::fprintf(stderr, "\r%s [%s%s] %3d%%  %-24s %6.1f s\x1b[K", label_.c_str(),
                 std::string(static_cast<std::size_t>(filled), '#').c_str(),
                 std::string(static_cast<std::size_t>(kWidth - filled), '.').c_str(), percent(),
                 stage_.c_str(), seconds);
    std::fflush(stderr);
  }

  void tick() {
    std::unique_lock lock(mutex_);
    while (!done_) {
      wake_.wait_for(lock, std::chrono::milliseconds(100));
      if (!done_) draw();
    }
  }

  std::string label_;
  bool tty_;
  Clock::time_point start_;
  std::mutex mutex_;
  std::condition_variable wake_;
  float fraction_ = 0.0f;
  std::string stage_;
  bool done_ = false;
  std::thread ticker_;
};

struct BuildCommandOptions {
  std::string in;
  std::string out;
  std::string primitives = "config/avatars/humanoid.toml";
  std::string config = "config";
  bool keep_free = false;  // --keep-free: no primitives for the free vertices
};

Status runBuild(const BuildCommandOptions& opt) {
  std::string ext = std::filesystem::path(opt.out).extension().string();
  std::transform(ext.begin(), ext.end(), ext.begin(),
                 [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  if (ext != ".vavatar") return fail("{}: the output must be a .vavatar file", opt.out);
  const Clock::time_point start = Clock::now();

  // Import.
  Progress progress("build");
  progress.update(0.0f, "importing");
  std::vector<std::string> warnings;
  Result<AvatarModel> avatar = loadAvatarFile(opt.in, &warnings);
  if (!avatar) return avatar.error();
  const bool rebuilt = avatar->implicit.has_value();

  // Fit (10% .. 85% of the bar).
  BuildReport report;
  Status built = buildAvatarImplicit(
      *avatar, opt.primitives, opt.config,
      [&progress](float f, std::string_view stage) {
        if (stage != "done") progress.update(0.1f + 0.75f * f, stage);
      },
      &report, !opt.keep_free);
  if (!built) return built;

  // Textures downscaled when the avatar would exceed the server's avatar size limit.
  const std::size_t limit = serverMaxAvatarBytes(opt.config, &warnings);
  Result<int> downscaled = fitAvatarTextures(*avatar, limit, warnings);
  if (!downscaled) return downscaled.error();

  // Save, load back, compare.
  progress.update(0.85f, "saving");
  const std::vector<std::uint8_t> bytes = encodeAvatar(*avatar);
  if (Status st = writeFileBytes(opt.out, bytes); !st) return st;
  progress.update(0.95f, "verifying");
  Result<AvatarModel> loaded = loadAvatar(opt.out);
  if (!loaded) return withContext("reading back what was written", loaded.error());
  if (encodeAvatar(*loaded) != bytes) {
    return fail("{}: the file read back differs from the model written", opt.out);
  }
  progress.update(1.0f, "done");
  progress.finish();

  // Summary.
  for (const std::string& w : warnings) fmt::print(stderr, "warning: {}\n", w);
  for (const std::string& w : report.warnings) fmt::print(stderr, "warning: {}\n", w);
  if (bytes.size() > limit) {
    fmt::print(stderr, "warning: {} is {} bytes, beyond the server's avatar limit of {} bytes\n",
               opt.out, bytes.size(), limit);
  }
  const CalibrationReport& c = report.calibration;
  const double seconds = std::chrono::duration<double>(Clock::now() - start).count();
  fmt::print(
      "wrote {}: {} vertices, {} joints, {} primitives ({} from the map, {} adopting {} free "
      "vertices); vertices: {} limb, {} joint, {} free ({} demoted), {} rest-contact pairs; {} "
      "bytes (format {}), verified on reload; {:.1f} s{}\n",
      opt.out, avatar->skin.vertexCount(), avatar->skeleton.jointCount(), report.primitives.size(),
      report.primitives.size() - static_cast<std::size_t>(report.adopted_primitives),
      report.adopted_primitives, report.adopted_vertices, c.limb, c.joint, c.free, c.demoted,
      c.rest_pairs, bytes.size(), kAvatarFormatVersion, seconds,
      rebuilt ? " (the input's implicit model was replaced)" : "");
  if (!avatar->look.empty()) {
    fmt::print("look: {} materials, {} textures ({} bytes), {}\n", avatar->look.materials.size(),
               avatar->look.textures.size(), avatar->look.textureBytes(),
               avatar->look.uvs.empty() ? "no texture coordinates" : "texture coordinates");
  }
  std::fflush(stdout);
  return {};
}

}  // namespace

Status buildAvatarImplicit(AvatarModel& avatar, const std::string& primitives,
                           const std::string& config,
                           std::function<void(float, std::string_view)> progress,
                           BuildReport* report, bool adopt_free_vertices) {
  // The joint map (the avatar's names -> canonical ones) and the primitive map.
  Result<std::vector<JointMap>> maps = loadJointMaps(config);
  if (!maps) return maps.error();
  // A config/skeletons map that fits, else one inferred from names and topology.
  Result<JointMapChoice> map = chooseJointMap(*maps, avatar.skeleton);
  if (!map) {
    return withContext(fmt::format("avatar '{}': no joint map in {}/skeletons fits its skeleton "
                                   "and none can be inferred",
                                   avatar.name, config),
                       map.error());
  }
  Result<PrimitiveMapSpec> spec = loadPrimitiveMap(primitives);
  if (!spec) return spec.error();
  BuildOptions options;
  options.progress = std::move(progress);
  options.adopt_free_vertices = adopt_free_vertices;
  Result<ImplicitModel> model = buildImplicitModel(avatar, *spec, &map->map, options, report);
  if (!model)
    return withContext(fmt::format("fitting {} to '{}'", primitives, avatar.name), model.error());
  avatar.implicit = std::move(*model);
  if (Status valid = validateAvatar(avatar); !valid) {
    return withContext("the built model does not validate", valid.error());
  }
  return {};
}

void registerBuildCommand(CLI::App& app) {
  auto opt = std::make_shared<BuildCommandOptions>();
  CLI::App* cmd = app.add_subcommand(
      "build",
      "Fit the implicit model (primitives, combination graph, calibration) to a rigged "
      "humanoid and write a .vavatar file");
  cmd->add_option("in", opt->in, "avatar file (.glb, .gltf or .vavatar)")->required();
  cmd->add_option("-o,--out", opt->out, "output .vavatar file")->required();
  cmd->add_option("--primitives", opt->primitives, "primitive map (TOML)")->capture_default_str();
  cmd->add_option("--config", opt->config, "config folder with skeletons/*.toml joint maps")
      ->capture_default_str();
  cmd->add_flag("--keep-free", opt->keep_free,
                "leave the vertices no mapped primitive models free (rigid to soft partners) "
                "instead of giving them primitives of their own (fingers, toes, chest, crown)");
  setCommandAction(cmd, [opt]() { return runBuild(*opt); });
}

}  // namespace vistel
