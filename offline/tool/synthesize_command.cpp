// vistel-avatar synthesize PARTS.toml -o OUT.glb [--source AVATAR]: one avatar from
// separately digitized parts (offline/synthesize): the parts named in PARTS.toml (the
// format vistel-avatar cut writes, offline/parts/parts_manifest.hpp) joined at each
// joint by a lofted blend region and simplified where flat (--decimate-mm), on the
// skeleton of the manifest's source avatar (or --source), with its skin weights
// transferred; written as a skinned .glb that vistel-avatar build accepts.
#include <algorithm>
#include <filesystem>
#include <memory>

#include <fmt/format.h>

#include "common/glb/gltf_export.hpp"
#include "offline/synthesize/avatar_synthesis.hpp"
#include "offline/tool/tool_commands.hpp"

namespace vistel {
namespace {

struct SynthesizeOptions {
  std::string manifest;
  std::string out;
  std::string source;
  float ring_spacing = 0.0f;
  float decimate_mm = 0.5f;
  bool decimate_parts = false;
};

Status runSynthesize(const SynthesizeOptions& opt) {
  std::string ext = std::filesystem::path(opt.out).extension().string();
  std::transform(ext.begin(), ext.end(), ext.begin(),
                 [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  if (ext != ".glb") return fail("{}: -o must end in .glb", opt.out);
  Result<PartsManifest> manifest = readPartsManifest(opt.manifest);
  if (!manifest) return manifest.error();
  const std::string source = opt.source.empty() ? manifest->source : opt.source;
  if (source.empty()) return fail("{}: names no source avatar; give --source", opt.manifest);
  Result<AvatarModel> skeleton_source = loadAvatarFile(source);
  if (!skeleton_source) return skeleton_source.error();
  Result<std::vector<PartMesh>> parts = readParts(*manifest);
  if (!parts) return withContext(opt.manifest, parts.error());
  SynthesisOptions options;
  options.loft.ring_spacing_m = opt.ring_spacing;
  options.decimation.max_error_m = 1e-3f * opt.decimate_mm;
  options.decimate_parts = opt.decimate_parts;
  SynthesisReport report;
  Result<AvatarModel> avatar =
      synthesizeAvatar(*manifest, *parts, *skeleton_source, options, &report);
  if (!avatar) return withContext(opt.manifest, avatar.error());
  if (Status st = writeGlb(opt.out, restAvatarScene(*avatar)); !st) return st;

  fmt::print(
      "synthesized {} from {} parts ({} vertices, {} triangles; {} spikes trimmed off "
      "the rims) and {} regions ({} vertices, {} triangles): {}\n",
      opt.manifest, parts->size(), report.part_vertices, report.part_triangles,
      report.trimmed_spikes, report.seams.size(), report.region_vertices, report.region_triangles,
      opt.out);
  if (report.collapses > 0) {
    fmt::print("decimated within {} mm: {} -> {} vertices, {} -> {} triangles\n", opt.decimate_mm,
               report.undecimated_vertices, report.part_vertices + report.region_vertices,
               report.undecimated_triangles, report.part_triangles + report.region_triangles);
  }
  for (const SeamReport& s : report.seams) {
    if (!s.lofted) {
      fmt::print("  {:<11} {} - {}: not joined ({})\n", s.joint, s.parent, s.child, s.why);
      continue;
    }
    fmt::print("  {:<11} rims {:>3} / {:>3}{}, {} rings of {}, {:.1f} mm long\n", s.joint,
               s.parent_rim, s.child_rim, s.shared_rim ? " (shared rim split)" : "", s.rings,
               s.ring_size, 1e3 * s.length_m);
  }
  if (report.rims_left_open > 0) {
    fmt::print("warning: {} of {} rims were not paired with a joint: the skin has holes\n",
               report.rims_left_open, report.rims);
  }
  return {};
}

}  // namespace

void registerSynthesizeCommand(CLI::App& app) {
  auto opt = std::make_shared<SynthesizeOptions>();
  CLI::App* cmd = app.add_subcommand(
      "synthesize",
      "Join separately digitized parts (a PARTS.toml as cut writes it) into one skinned avatar: "
      "each joint's blend region lofted between the two parts' rims and stitched to them");
  cmd->add_option("parts", opt->manifest, "the PARTS.toml")->required();
  cmd->add_option("-o,--out", opt->out, "output avatar, .glb")->required();
  cmd->add_option("--source", opt->source,
                  "skeleton source avatar (default: the manifest's source)");
  cmd->add_option("--ring-spacing", opt->ring_spacing,
                  "distance between the region's rings, metres (default: the rims' edge length)")
      ->check(CLI::Range(0.0f, 0.1f));
  cmd->add_option("--decimate-mm", opt->decimate_mm,
                  "simplify the skin where flat, moving it at most this far, millimetres; 0: "
                  "not at all (default 0.5: a tenth of the 5 mm allowed in the blend regions, "
                  "half the 1 mm allowed elsewhere)")
      ->check(CLI::Range(0.0f, 10.0f));
  cmd->add_flag("--decimate-parts", opt->decimate_parts,
                "simplify the parts too, away from their rims (default: only the blend regions; "
                "the parts' own vertices are kept)");
  setCommandAction(cmd, [opt]() { return runSynthesize(*opt); });
}

}  // namespace vistel
