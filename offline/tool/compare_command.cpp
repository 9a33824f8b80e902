// vistel-avatar compare A B [--json] [--weld M] [--samples N]: how far two surfaces lie
// from each other (symmetric Hausdorff and mean surface distance) and, for each, whether it
// is closed, a 2-manifold and consistently oriented, and how many of its triangle pairs
// intersect (issue 24's measures of a synthesized avatar against the original).
//
// A and B: avatars (.glb, .gltf, .vavatar: their skin in the rest posture) or meshes
// (.obj, .ply, .off, .stl, through OpenMesh). Vertices closer than --weld metres are joined
// first, so a skin split at texture seams is judged as one surface.
#include <filesystem>
#include <iostream>
#include <memory>

#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include "common/deform/mesh_quality.hpp"
#include "offline/compare/mesh_topology.hpp"
#include "offline/compare/surface_distance.hpp"
#include "offline/tool/tool_commands.hpp"

namespace vistel {
namespace {

struct CompareOptions {
  std::string a;
  std::string b;
  bool json = false;
  float weld = 1e-6f;
  int samples = 4;
};

bool isMeshFile(const std::string& path) {
  std::string ext = std::filesystem::path(path).extension().string();
  for (char& c : ext) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return ext == ".obj" || ext == ".ply" || ext == ".off" || ext == ".stl";
}

Result<TriangleSoup> loadSurface(const std::string& path) {
  if (isMeshFile(path)) return readMeshFile(path);
  Result<AvatarModel> avatar = loadAvatarFile(path);
  if (!avatar) return avatar.error();
  TriangleSoup soup;
  soup.positions = avatar->skin.positions;
  soup.indices = avatar->skin.indices;
  return soup;
}

struct SurfaceReport {
  TriangleSoup soup;  // welded
  MeshTopology topology;
  int self_intersections = 0;
};

Result<SurfaceReport> examine(const std::string& path, float weld) {
  Result<TriangleSoup> loaded = loadSurface(path);
  if (!loaded) return loaded.error();
  if (loaded->indices.empty()) return fail("{}: no triangles", path);
  SurfaceReport r;
  r.soup = weldVertices(*loaded, weld);
  r.topology = analyzeTopology(r.soup);
  r.self_intersections = countSelfIntersections(r.soup.positions, r.soup.indices);
  return r;
}

nlohmann::json toJson(const std::string& path, const SurfaceReport& r) {
  const MeshTopology& t = r.topology;
  return {{"file", path},
          {"vertices", t.vertices},
          {"triangles", t.triangles},
          {"closed", t.closed()},
          {"manifold", t.manifold()},
          {"oriented", t.oriented()},
          {"boundary_edges", t.boundary_edges},
          {"nonmanifold_edges", t.nonmanifold_edges},
          {"nonmanifold_vertices", t.nonmanifold_vertices},
          {"misoriented_edges", t.misoriented_edges},
          {"degenerate_triangles", t.degenerate_triangles},
          {"components", t.components},
          {"self_intersecting_pairs", r.self_intersections}};
}

void printSurface(const char* label, const std::string& path, const SurfaceReport& r) {
  const MeshTopology& t = r.topology;
  fmt::print("{}: {}\n", label, path);
  fmt::print("  {} vertices, {} triangles, {} piece(s)\n", t.vertices, t.triangles, t.components);
  fmt::print("  closed: {} ({} boundary edges)\n", t.closed() ? "yes" : "no", t.boundary_edges);
  fmt::print("  2-manifold: {} ({} non-manifold edges, {} non-manifold vertices)\n",
             t.manifold() ? "yes" : "no", t.nonmanifold_edges, t.nonmanifold_vertices);
  fmt::print("  oriented: {} ({} edges used twice in one direction)\n", t.oriented() ? "yes" : "no",
             t.misoriented_edges);
  fmt::print("  degenerate triangles: {}\n", t.degenerate_triangles);
  fmt::print("  self-intersecting triangle pairs: {}\n", r.self_intersections);
}

Status runCompare(const CompareOptions& opt) {
  Result<SurfaceReport> a = examine(opt.a, opt.weld);
  if (!a) return a.error();
  Result<SurfaceReport> b = examine(opt.b, opt.weld);
  if (!b) return b.error();
  const SurfaceDistance d = surfaceDistance(a->soup, b->soup, opt.samples);
  const auto point = [](const glm::vec3& p) { return nlohmann::json{p.x, p.y, p.z}; };
  if (opt.json) {
    nlohmann::json out = {{"a", toJson(opt.a, *a)},
                          {"b", toJson(opt.b, *b)},
                          {"distance",
                           {{"hausdorff_m", d.hausdorff()},
                            {"mean_m", d.mean()},
                            {"a_to_b",
                             {{"max_m", d.a_to_b.max},
                              {"mean_m", d.a_to_b.mean},
                              {"worst", point(d.a_to_b.worst)},
                              {"samples", d.a_to_b.samples}}},
                            {"b_to_a",
                             {{"max_m", d.b_to_a.max},
                              {"mean_m", d.b_to_a.mean},
                              {"worst", point(d.b_to_a.worst)},
                              {"samples", d.b_to_a.samples}}}}}};
    std::cout << out.dump() << std::endl;
    return {};
  }
  printSurface("A", opt.a, *a);
  printSurface("B", opt.b, *b);
  fmt::print("distance:\n");
  fmt::print("  symmetric Hausdorff: {:.6f} m\n", d.hausdorff());
  fmt::print("  mean surface distance: {:.6f} m\n", d.mean());
  fmt::print("  A to B: max {:.6f} m at ({:.4f}, {:.4f}, {:.4f}), mean {:.6f} m ({} samples)\n",
             d.a_to_b.max, d.a_to_b.worst.x, d.a_to_b.worst.y, d.a_to_b.worst.z, d.a_to_b.mean,
             d.a_to_b.samples);
  fmt::print("  B to A: max {:.6f} m at ({:.4f}, {:.4f}, {:.4f}), mean {:.6f} m ({} samples)\n",
             d.b_to_a.max, d.b_to_a.worst.x, d.b_to_a.worst.y, d.b_to_a.worst.z, d.b_to_a.mean,
             d.b_to_a.samples);
  return {};
}

}  // namespace

void registerCompareCommand(CLI::App& app) {
  auto opt = std::make_shared<CompareOptions>();
  CLI::App* cmd = app.add_subcommand(
      "compare",
      "Compare two surfaces: symmetric Hausdorff and mean surface distance (metres), and for "
      "each whether it is closed, a 2-manifold and consistently oriented, and its "
      "self-intersecting triangle pairs. Avatars (.glb, .gltf, .vavatar) give their rest skin; "
      "meshes (.obj, .ply, .off, .stl) are read with OpenMesh");
  cmd->add_option("a", opt->a, "first avatar or mesh file")->required();
  cmd->add_option("b", opt->b, "second avatar or mesh file")->required();
  cmd->add_flag("--json", opt->json, "print one JSON object instead of text");
  cmd->add_option("--weld", opt->weld,
                  "join vertices closer than this (metres) before judging topology "
                  "(default 1e-6: a skin split at texture seams is one surface)")
      ->check(CLI::Range(0.0f, 0.01f));
  cmd->add_option("--samples", opt->samples,
                  "subdivisions n of each triangle's sample pattern, (n + 1)(n + 2) / 2 samples "
                  "(default 4)")
      ->check(CLI::Range(1, 32));
  setCommandAction(cmd, [opt]() { return runCompare(*opt); });
}

}  // namespace vistel
