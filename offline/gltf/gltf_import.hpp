// Avatar import from rigged glTF 2.0 files (.glb, or .gltf with external or embedded
// buffers), through tinygltf (parsing) and OpenMesh (topology, normals).
//
// The result is in model space: the glTF scene's world space (metres, +Y up), with every
// scene-root or up-axis conversion node above the skeleton or the mesh (a Z-up -> Y-up
// rotation, a 0.01 scale) baked into the vertices and joints. The rest posture is the
// bind posture: vertices are where the skin's inverse bind matrices put them, joints
// where the bind matrices say (when the nodes' rest transforms disagree, the bind wins and
// a warning says so). Joint frames are rigid (scale is baked into positions, not kept in
// joints), ordered parents first with a single root at 0.
#pragma once

#include <cstdint>
#include <optional>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "common/avatar/avatar_model.hpp"
#include "common/base/result.hpp"
#include "common/motion/joint_map.hpp"

namespace vistel {

// config/server.toml's [limits] max_avatar_bytes as shipped (one avatar file).
inline constexpr std::size_t kDefaultMaxAvatarBytes = 16u << 20;
// Room left for the deformable component that `vistel-avatar build` adds after the import
// (measured: about 180 bytes per skin vertex for the default primitive map; `build` then
// fits the textures again to the exact size).
inline constexpr std::size_t implicitModelAllowance(std::size_t vertices) {
  return (64u << 10) + 256u * vertices;
}

struct GltfImportOptions {
  // A joint's rest transform agrees with its inverse bind matrix when
  // |world * ibm - bind| <= bind_tolerance * (1 + |bind|) entrywise.
  double bind_tolerance = 1e-4;
  // Recompute vertex normals (area-weighted) even when the file has them.
  bool recompute_normals = false;
  // Files larger than this are refused (bytes).
  std::size_t max_file_bytes = std::size_t{1} << 30;
  // The encoded avatar (.vavatar) must fit this many bytes: textures are downscaled (by
  // halves, largest first, with a warning) until the imported avatar plus
  // implicitModelAllowance(vertices) fits (or, when that leaves less than half the limit,
  // the whole limit). Default: the server's [limits] max_avatar_bytes
  // (config/server.toml). 0: no limit.
  std::size_t max_avatar_bytes = kDefaultMaxAvatarBytes;
  // Import texture coordinates, materials and textures (false: geometry only).
  bool import_look = true;
  // VRM files (the VRMC_vrm 1.0 or VRM 0.x extension): rename the humanoid bones' joints to
  // vistel's canonical names (joint_map.hpp), so that every joint mapping later finds them
  // by name; the extension's map is in GltfImportReport::humanoid either way.
  bool vrm_canonical_names = true;
};

// What the import found and did besides the model; every entry of `warnings` is one line.
struct GltfImportReport {
  std::vector<std::string> warnings;
  std::string mesh_node;                // name (or "node N") of the skinned mesh node used
  int skin = -1;                        // index of the skin used
  int primitives = 0;                   // primitives merged into the skin mesh
  int boundary_edges = 0;               // from OpenMesh
  int non_manifold_vertices = 0;        // from OpenMesh
  int rejected_triangles = 0;           // triangles OpenMesh refused (kept in the output)
  int unweighted_vertices = 0;          // vertices with zero total weight, bound to one joint
  bool normals_computed = false;        // the file had no (usable) normals
  bool rest_from_inverse_bind = false;  // node rest transforms disagreed with the IBMs
  bool synthetic_root = false;          // the skin had several roots; a root was added
  int materials = 0;                    // materials kept in the look
  int textures = 0;                     // textures kept in the look
  int textures_downscaled = 0;          // textures made smaller to fit max_avatar_bytes
  // VRM: the humanoid bone map read from the extension (canonical name <- joint name as
  // imported; empty map when the file is not a VRM), and the extension's version.
  std::optional<JointMap> humanoid;
  std::string vrm_version;  // "1.0" (VRMC_vrm) or "0.x" (VRM), empty: no VRM
};

// Imports the first skin used by a mesh node (in the default scene's order, else node
// order): all primitives of mesh nodes using that skin are merged into one mesh (mode
// TRIANGLES; vertices as in the file, so the count equals the file's), with up to
// kMaxInfluences influences per vertex from JOINTS_n/WEIGHTS_n (normalised; a vertex with
// zero total weight is bound to the mesh node's joint or the nearest joint, with a
// warning). avatar.name is the file's stem.
// The look (options.import_look): TEXCOORD_0 per vertex, one submesh per primitive run
// with its material (base colour factor and texture, normal map, alpha mode, double
// sidedness), the PNG/JPEG images those use kept encoded (buffer views, data URIs and
// external files next to the file; others dropped with a warning), downscaled to fit
// options.max_avatar_bytes (gltf_look.hpp). VRM (.vrm) files: see vrm_canonical_names.
// Errors name the file and the element ("avatar.glb: accessor 7: count 10 exceeds buffer
// view 3 ..."); malformed input never crashes. report (optional) receives warnings and
// counts. Cost: O(file size + vertices + joints^2).
Result<AvatarModel> importGltfAvatar(const std::string& path, const GltfImportOptions& options = {},
                                     GltfImportReport* report = nullptr);

// As importGltfAvatar from the bytes of a .glb or .gltf (JSON) file; source_name is used in
// messages and as the avatar's name; external buffers are looked up in base_dir.
Result<AvatarModel> importGltfAvatarFromMemory(std::span<const std::uint8_t> bytes,
                                               std::string_view source_name,
                                               const std::string& base_dir = "",
                                               const GltfImportOptions& options = {},
                                               GltfImportReport* report = nullptr);

}  // namespace vistel
