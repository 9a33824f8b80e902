// One avatar from separately digitized parts (vistel-avatar synthesize; issue 24, the
// paper's Section 2). For each joint of the manifest, the parent part's rim and the child
// part's rim nearest the joint are lofted into each other across the blend region
// (seam_loft.hpp: rings on Hermite curves leaving each part along its surface, zipped onto
// both rims; a parent rim around several children is split first, shared_rim.hpp), and
// the regions' new vertices are evened out by Taubin smoothing, so that the parts and the
// regions make one closed 2-manifold skin when every rim is paired. Then the skin is
// simplified where flat (skin_decimation.hpp, SynthesisOptions::decimation): halfedge
// collapses remove region vertices (and, with decimate_parts, part vertices off the rims)
// within the error bound, closed, manifold and oriented as it was. The part vertices that
// stay are where they were; the skeleton is the source's.
//
// Attributes: a part vertex takes the source skin's weights at its nearest surface point
// (the weights the source has there), or weight 1 on its part's bone when the source has
// no skin; a region vertex blends the weights of the two rim points it runs between by
// smoothstep(s). Texture coordinates are blended the same way when every part has them
// (the source's materials and textures are kept then).
//
// Space: the source's model space, rest posture, metres. Bad input (a part's bone or a
// joint's segment unknown, a source without a skeleton) is an Error naming it; a rim that
// cannot be paired is reported (SynthesisReport) and leaves a hole. Cost: O(parts' size)
// plus O(ring vertices x log) field queries: well under a second for a 13k-vertex body.
#pragma once

#include <span>
#include <string>
#include <vector>

#include "common/avatar/avatar_model.hpp"
#include "common/base/result.hpp"
#include "offline/parts/parts_manifest.hpp"
#include "offline/synthesize/part_mesh.hpp"
#include "offline/synthesize/seam_loft.hpp"
#include "offline/synthesize/skin_decimation.hpp"

namespace vistel {

struct SynthesisOptions {
  LoftOptions loft;
  int spike_rounds = 2;     // rounds of trimRimSpikes on each part before lofting
  int fairing_rounds = 20;  // Taubin smoothing rounds over the regions' new vertices
  // The result simplified where flat (skin_decimation.hpp): the regions' vertices, and
  // with `decimate_parts` the parts' vertices off their rims too. max_error_m 0: none.
  DecimationOptions decimation;
  bool decimate_parts = false;
};

struct SeamReport {
  std::string joint;
  std::string parent, child;  // segments
  bool lofted = false;
  bool shared_rim = false;            // the parent's rim was shared with other joints and split
  std::string why;                    // when not lofted
  int parent_rim = 0, child_rim = 0;  // rim vertices
  int rings = 0, ring_size = 0;
  float length_m = 0.0f;                        // mean rim-to-rim distance
  float max_projection_m = 0.0f;                // largest move onto the blended field
  std::vector<std::uint32_t> region_triangles;  // output triangle indices of the region
};

struct SynthesisReport {
  std::vector<SeamReport> seams;
  int part_vertices = 0, part_triangles = 0;  // kept in the result
  int region_vertices = 0, region_triangles = 0;
  int rims = 0;            // over all parts
  int rims_left_open = 0;  // not lofted: holes in the result
  int trimmed_spikes = 0;  // part triangles dropped along the rims (trimRimSpikes)
  // Decimation: the counts above are the result's; these the skin's before it.
  int undecimated_vertices = 0, undecimated_triangles = 0;
  int collapses = 0;
};

// Reads the manifest's part files (in its order).
Result<std::vector<PartMesh>> readParts(const PartsManifest& manifest);

// The synthesized avatar: named after the source, its skeleton, the parts' vertices (in
// manifest order, as read, less those only trimmed spikes used) then the regions'
// vertices; triangles likewise (parts' first). `parts` in manifest order.
Result<AvatarModel> synthesizeAvatar(const PartsManifest& manifest, std::span<const PartMesh> parts,
                                     const AvatarModel& source, const SynthesisOptions& options,
                                     SynthesisReport* report = nullptr);

}  // namespace vistel
