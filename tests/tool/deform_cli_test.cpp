// vistel-avatar build and deform: building the implicit model of the default avatar and of
// the shared MakeHuman body (loaded back bit-identically), deforming clip frames with a
// ball into a glTF the Khronos validator accepts, --rigid-only against the deformed file,
// the forces CSV (rows, equal and opposite forces), and bad arguments.
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <map>
#include <sstream>

#include <gtest/gtest.h>
#include <glm/glm.hpp>

#include "common/avatar/avatar_io.hpp"
#include "common/base/file.hpp"
#include "common/glb/glb_container.hpp"
#include "tests/support/test_support.hpp"
#include "tests/tool/tool_runner.hpp"

namespace vistel {
namespace {

const char* kClip = "mocap/cmu/01_01.bvh";

std::vector<std::uint8_t> bytesOf(const std::string& path) {
  Result<std::vector<std::uint8_t>> bytes = readFileBytes(path, 1u << 30);
  EXPECT_TRUE(bytes.ok()) << path;
  return bytes.ok() ? *bytes : std::vector<std::uint8_t>{};
}

// The default avatar as a .vavatar (no implicit model), made by the tool once per process.
std::string defaultAvatar() {
  static const std::string path = [] {
    const std::string dir = test::scratchDir();
    const test::ToolRun run = test::runTool("default --out " + dir + "/default.vavatar", dir);
    EXPECT_EQ(run.exit_code, 0) << run.err;
    return dir + "/default.vavatar";
  }();
  return path;
}

// The vertices of animation frame f of an exported .glb: base POSITION + morph target f.
struct ExportedGlb {
  nlohmann::json doc;
  std::vector<std::uint8_t> bytes;
  std::span<const std::uint8_t> bin;

  std::vector<glm::vec3> accessor(int index) const {
    const nlohmann::json& a = doc["accessors"][static_cast<std::size_t>(index)];
    const nlohmann::json& v = doc["bufferViews"][a["bufferView"].get<std::size_t>()];
    const std::size_t offset =
        v.value("byteOffset", std::size_t{0}) + a.value("byteOffset", std::size_t{0});
    std::vector<glm::vec3> out(a["count"].get<std::size_t>());
    EXPECT_LE(offset + out.size() * sizeof(glm::vec3), bin.size());
    if (offset + out.size() * sizeof(glm::vec3) <= bin.size()) {
      std::memcpy(out.data(), bin.data() + offset, out.size() * sizeof(glm::vec3));
    }
    return out;
  }
  std::size_t frameCount() const {
    const nlohmann::json& p = doc["meshes"][0]["primitives"][0];
    return p.contains("targets") ? p["targets"].size() : 1;
  }
  std::vector<glm::vec3> frame(std::size_t f) const {
    const nlohmann::json& p = doc["meshes"][0]["primitives"][0];
    std::vector<glm::vec3> base = accessor(p["attributes"]["POSITION"].get<int>());
    if (!p.contains("targets")) return base;
    const std::vector<glm::vec3> delta = accessor(p["targets"][f]["POSITION"].get<int>());
    for (std::size_t i = 0; i < base.size(); ++i) base[i] += delta[i];
    return base;
  }
};

ExportedGlb readExportedGlb(const std::string& path) {
  ExportedGlb g;
  g.bytes = bytesOf(path);
  Result<GlbChunks> chunks = parseGlbContainer(g.bytes, path);
  EXPECT_TRUE(chunks.ok()) << (chunks.ok() ? "" : chunks.error().message);
  if (!chunks.ok()) return g;
  g.doc = nlohmann::json::parse(chunks->json.begin(), chunks->json.end());
  g.bin = chunks->bin;
  return g;
}

struct CsvRow {
  int frame = 0;
  double time = 0.0;
  std::string body;
  double area = 0.0;
  glm::dvec3 force{0.0};
  double magnitude = 0.0;
  std::string partner;
  std::string dynamics;  // the ball dynamics' force (N), empty without --ball-physics
};

std::vector<CsvRow> readCsv(const std::string& path, std::string& header) {
  std::ifstream in(path);
  std::getline(in, header);
  std::vector<CsvRow> rows;
  std::string line;
  while (std::getline(in, line)) {
    std::vector<std::string> f;
    std::stringstream s(line);
    std::string item;
    while (std::getline(s, item, ',')) f.push_back(item);
    if (!line.empty() && line.back() == ',') f.emplace_back();
    EXPECT_EQ(f.size(), 10u) << line;
    if (f.size() != 10) continue;
    CsvRow r;
    r.frame = std::stoi(f[0]);
    r.time = std::stod(f[1]);
    r.body = f[2];
    r.area = std::stod(f[3]);
    r.force = glm::dvec3(std::stod(f[4]), std::stod(f[5]), std::stod(f[6]));
    r.magnitude = std::stod(f[7]);
    r.partner = f[8];
    r.dynamics = f[9];
    rows.push_back(r);
  }
  return rows;
}

TEST(DeformCli, BuildTheDefaultAvatarAndLoadItBackBitIdentical) {
  const std::string dir = test::scratchDir();
  const std::string out = dir + "/built.vavatar";
  test::ToolRun run = test::runTool("build " + defaultAvatar() + " -o " + out, dir);
  ASSERT_EQ(run.exit_code, 0) << run.err;
  // Not a terminal: one plain progress line per stage.
  EXPECT_NE(run.err.find("build:   0% importing"), std::string::npos) << run.err;
  EXPECT_NE(run.err.find("calibration"), std::string::npos) << run.err;
  EXPECT_NE(run.err.find("build: 100% done"), std::string::npos) << run.err;
  EXPECT_EQ(run.err.find('\r'), std::string::npos);
  EXPECT_NE(run.out.find("verified on reload"), std::string::npos) << run.out;

  Result<AvatarModel> loaded = loadAvatar(out);
  ASSERT_TRUE(loaded.ok()) << loaded.error().message;
  ASSERT_TRUE(loaded->implicit.has_value());
  EXPECT_GE(loaded->implicit->primitives.items.size(), 20u);
  EXPECT_EQ(loaded->implicit->calibration.vertexCount(), loaded->skin.vertexCount());
  EXPECT_EQ(encodeAvatar(*loaded), bytesOf(out));

  // Deterministic: building again (also from the built file) gives the same bytes.
  run = test::runTool("build " + out + " --out " + dir + "/again.vavatar", dir);
  ASSERT_EQ(run.exit_code, 0) << run.err;
  EXPECT_NE(run.out.find("replaced"), std::string::npos) << run.out;
  EXPECT_EQ(bytesOf(dir + "/again.vavatar"), bytesOf(out));

  // The free vertices get primitives of their own unless --keep-free says not to.
  EXPECT_EQ(run.out.find(" 0 adopting"), std::string::npos) << run.out;
  run = test::runTool("build " + out + " --keep-free -o " + dir + "/free.vavatar", dir);
  ASSERT_EQ(run.exit_code, 0) << run.err;
  EXPECT_NE(run.out.find(" 0 adopting 0 free vertices"), std::string::npos) << run.out;
  Result<AvatarModel> kept_free = loadAvatar(dir + "/free.vavatar");
  ASSERT_TRUE(kept_free.ok()) << kept_free.error().message;
  EXPECT_LT(kept_free->implicit->primitives.items.size(),
            loaded->implicit->primitives.items.size());

  // A damaged file is refused on load with a clear error.
  std::vector<std::uint8_t> bytes = bytesOf(out);
  bytes[bytes.size() / 2] ^= 0x5a;
  ASSERT_TRUE(writeFileBytes(dir + "/damaged.vavatar", bytes).ok());
  run = test::runTool("info " + dir + "/damaged.vavatar", dir);
  test::expectToolFailure(run, "damaged.vavatar");
}

TEST(DeformCli, BuildTheSharedGlb) {
  VISTEL_REQUIRE_SHARED(glb, test::kMakeHumanGlb);
  const std::string dir = test::scratchDir();
  const std::string out = dir + "/mh.vavatar";
  const test::ToolRun run = test::runTool(
      "build " + glb + " -o " + out + " --primitives config/avatars/humanoid.toml", dir);
  ASSERT_EQ(run.exit_code, 0) << run.err;
  EXPECT_NE(run.out.find("13380 vertices"), std::string::npos) << run.out;
  Result<AvatarModel> loaded = loadAvatar(out);
  ASSERT_TRUE(loaded.ok()) << loaded.error().message;
  ASSERT_TRUE(loaded->implicit.has_value());
  EXPECT_EQ(loaded->skin.vertexCount(), 13380);
  EXPECT_EQ(encodeAvatar(*loaded), bytesOf(out));
}

TEST(DeformCli, DeformClipFramesWithABall) {
  VISTEL_REQUIRE_SHARED(glb, test::kMakeHumanGlb);
  VISTEL_REQUIRE_SHARED(clip, kClip);
  const std::string dir = test::scratchDir();
  const std::string avatar = dir + "/mh.vavatar";
  test::ToolRun run = test::runTool("build " + glb + " -o " + avatar, dir);
  ASSERT_EQ(run.exit_code, 0) << run.err;

  // A ball 10 cm in radius held against the belly (hips-relative), moving slowly in.
  const std::string common = avatar + " --bvh " + clip +
                             " --frames 100:124 --every 4 --ball 0,0.15,0.17,0.1,0,0,-0.2 "
                             "--ball-origin hips";
  run = test::runTool(
      "deform " + common + " --out " + dir + "/deformed.glb --forces-csv " + dir + "/forces.csv",
      dir);
  ASSERT_EQ(run.exit_code, 0) << run.err;
  EXPECT_NE(run.out.find("steps 2-3"), std::string::npos) << run.out;
  run = test::runTool("deform " + common + " --rigid-only --out " + dir + "/rigid.glb", dir);
  ASSERT_EQ(run.exit_code, 0) << run.err;

  // The CSV: one row per body per frame, forces equal and opposite.
  std::string header;
  const std::vector<CsvRow> rows = readCsv(dir + "/forces.csv", header);
  EXPECT_EQ(header,
            "frame,time_s,body,contact_area_m2,force_x_n,force_y_n,force_z_n,force_n,partner,"
            "dynamics_force_n");
  ASSERT_EQ(rows.size(), 12u);
  int contact_frames = 0;
  std::size_t contact_index = 0;
  for (std::size_t k = 0; k < 6; ++k) {
    const CsvRow& body = rows[2 * k];
    const CsvRow& ball = rows[2 * k + 1];
    EXPECT_EQ(body.frame, 100 + 4 * static_cast<int>(k));
    EXPECT_EQ(ball.frame, body.frame);
    EXPECT_NEAR(body.time, body.frame / 120.0, 1e-5);
    EXPECT_EQ(body.body, "makehuman_game_engine");
    EXPECT_EQ(ball.body, "ball");
    EXPECT_EQ(body.dynamics, "") << "no ball dynamics without --ball-physics";
    const double scale = std::max(1.0, body.magnitude);
    EXPECT_NEAR(body.force.x + ball.force.x, 0.0, 1e-6 * scale);
    EXPECT_NEAR(body.force.y + ball.force.y, 0.0, 1e-6 * scale);
    EXPECT_NEAR(body.force.z + ball.force.z, 0.0, 1e-6 * scale);
    EXPECT_NEAR(body.magnitude, glm::length(body.force), 1e-6 * scale);
    if (ball.area > 0.0 && ball.magnitude > 0.0) {
      if (contact_frames++ == 0) contact_index = k;
      EXPECT_EQ(ball.partner, "makehuman_game_engine");
      EXPECT_GT(ball.force.z, 0.0) << "the belly pushes the ball forward";
    }
  }
  ASSERT_GE(contact_frames, 3);

  // Both files hold the same frames; they differ where the ball touches.
  const ExportedGlb deformed = readExportedGlb(dir + "/deformed.glb");
  const ExportedGlb rigid = readExportedGlb(dir + "/rigid.glb");
  ASSERT_EQ(deformed.frameCount(), 6u);
  ASSERT_EQ(rigid.frameCount(), 6u);
  const std::vector<glm::vec3> d = deformed.frame(contact_index);
  const std::vector<glm::vec3> r = rigid.frame(contact_index);
  ASSERT_EQ(d.size(), r.size());
  ASSERT_EQ(d.size(), 13380u + 642u);
  float moved = 0.0f;
  for (std::size_t v = 0; v < 13380; ++v) moved = std::max(moved, glm::length(d[v] - r[v]));
  EXPECT_GT(moved, 5e-3f);
  // The ball (rigid) is in the same place in both.
  float ball_moved = 0.0f;
  for (std::size_t v = 13380; v < d.size(); ++v) {
    ball_moved = std::max(ball_moved, glm::length(d[v] - r[v]));
  }
  EXPECT_LT(ball_moved, 1e-5f);

  // The Khronos validator accepts both.
  VISTEL_VALIDATE_OR_SKIP(verdict, dir + "/deformed.glb");
  EXPECT_EQ(verdict["errors"], 0) << verdict.dump();
  VISTEL_VALIDATE_OR_SKIP(verdict_rigid, dir + "/rigid.glb");
  EXPECT_EQ(verdict_rigid["errors"], 0) << verdict_rigid.dump();
}

TEST(DeformCli, DeformAnAvatarWithoutAModelBuildsItOnTheFly) {
  const std::string dir = test::scratchDir();
  // A .glb carries the skinned mesh only.
  const test::ToolRun made = test::runTool("default --out " + dir + "/plain.glb", dir);
  ASSERT_EQ(made.exit_code, 0) << made.err;
  const test::ToolRun run = test::runTool(
      "deform " + dir + "/plain.glb --rest --frames 0:3 --ball 0,1.2,0.25,0.08 --out " + dir +
          "/rest.glb" + " --forces-csv " + dir + "/rest.csv",
      dir);
  ASSERT_EQ(run.exit_code, 0) << run.err;
  EXPECT_NE(run.err.find("has no implicit model: building one"), std::string::npos) << run.err;
  EXPECT_NE(run.out.find("3 frames"), std::string::npos) << run.out;
  std::string header;
  EXPECT_EQ(readCsv(dir + "/rest.csv", header).size(), 6u);
  EXPECT_EQ(readExportedGlb(dir + "/rest.glb").frameCount(), 3u);
}

TEST(DeformCli, BadArgumentsFailCleanly) {
  const std::string dir = test::scratchDir();
  const std::string a = defaultAvatar();
  const std::string out = " --out " + dir + "/x.glb";
  test::expectToolFailure(test::runTool("deform " + a + out, dir), "--bvh");
  test::expectToolFailure(test::runTool("deform " + a + " --rest --frames 5:2" + out, dir),
                          "--frames 5:2");
  test::expectToolFailure(test::runTool("deform " + a + " --rest --frames x:3" + out, dir), "A:B");
  test::expectToolFailure(test::runTool("deform " + a + " --rest --frames 0:99999" + out, dir),
                          "at most 4096");
  test::expectToolFailure(test::runTool("deform " + a + " --rest --ball 1,2,3" + out, dir),
                          "3 numbers");
  test::expectToolFailure(test::runTool("deform " + a + " --rest --ball 1,2,3,-1" + out, dir),
                          "radius");
  test::expectToolFailure(test::runTool("deform " + a + " --rest --ball 1,2,nan,0.1" + out, dir),
                          "not a finite number");
  test::expectToolFailure(test::runTool("deform " + a + " --rest --ball 1,2,3,0.1,4" + out, dir),
                          "5 numbers");
  test::expectToolFailure(test::runTool("deform " + a + " --rest --ball-physics" + out, dir),
                          "needs --ball");
  test::expectToolFailure(
      test::runTool("deform " + a + " --rest --ball-stiffness soft --ball 0,0,0,0.1" + out, dir),
      "--ball-stiffness");
  test::expectToolFailure(test::runTool("deform " + dir + "/missing.vavatar --rest" + out, dir),
                          "missing.vavatar: no such file");
  test::expectToolFailure(
      test::runTool("deform " + a + " --bvh " + dir + "/missing.bvh" + out, dir), "missing.bvh");
  test::expectToolFailure(
      test::runTool("deform " + a + " --rest --out " + dir + "/no/such/dir/x.glb", dir), "x.glb");
  test::expectToolFailure(test::runTool("build " + a + " -o " + dir + "/x.glb", dir), ".vavatar");
  test::expectToolFailure(
      test::runTool("build " + dir + "/missing.glb -o " + dir + "/x.vavatar", dir), "no such file");
  test::expectToolFailure(
      test::runTool(
          "build " + a + " -o " + dir + "/x.vavatar --primitives " + dir + "/missing.toml", dir),
      "missing.toml");
  if (std::filesystem::exists(test::sharedDataPath(kClip))) {
    test::expectToolFailure(test::runTool("deform " + a + " --bvh " + test::sharedDataPath(kClip) +
                                              " --frames 0:100000" + out,
                                          dir),
                            "has frames 0..");
  }
  EXPECT_FALSE(std::filesystem::exists(dir + "/x.glb"));
  EXPECT_FALSE(std::filesystem::exists(dir + "/x.vavatar"));
}

}  // namespace
}  // namespace vistel

namespace vistel {
namespace {

// A per-frame export is estimated before any frame is computed: beyond --max-size it is
// refused with the estimate and the ways out; --allow-large writes it anyway.
TEST(DeformCli, AnOversizedExportIsRefusedBeforeItIsComputed) {
  const std::string dir = test::scratchDir();
  const std::string a = defaultAvatar() + " --rest --frames 0:40";
  test::ToolRun run = test::runTool("deform " + a + " --max-size 1 --out " + dir + "/big.glb", dir);
  EXPECT_NE(run.exit_code, 0);
  EXPECT_NE(run.err.find("over --max-size 1 MiB"), std::string::npos) << run.err;
  EXPECT_NE(run.err.find("--every N"), std::string::npos) << run.err;
  EXPECT_FALSE(std::filesystem::exists(dir + "/big.glb"));
  run = test::runTool("deform " + a + " --max-size 1 --allow-large --out " + dir + "/big.glb", dir);
  ASSERT_EQ(run.exit_code, 0) << run.err;
  EXPECT_NE(run.err.find("40 frames of"), std::string::npos) << run.err;
  const double mib = static_cast<double>(std::filesystem::file_size(dir + "/big.glb")) / 1048576.0;
  EXPECT_GT(mib, 1.0);
  // The estimate it printed is the file's size to within 2%.
  const std::size_t about = run.err.find("about ");
  ASSERT_NE(about, std::string::npos) << run.err;
  const double estimate = std::strtod(run.err.c_str() + about + 6, nullptr);
  EXPECT_NEAR(estimate, mib, 0.02 * mib) << run.err;
}

}  // namespace
}  // namespace vistel
