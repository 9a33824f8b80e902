#include "offline/synthesize/avatar_synthesis.hpp"

#include <limits>
#include <memory>
#include <optional>

#include <fmt/format.h>

#include "offline/synthesize/part_field.hpp"
#include "offline/synthesize/shared_rim.hpp"
#include "offline/synthesize/skin_transfer.hpp"

namespace vistel {
namespace {

int partIndex(const PartsManifest& manifest, const std::string& segment) {
  for (std::size_t p = 0; p < manifest.parts.size(); ++p) {
    if (manifest.parts[p].segment == segment) return static_cast<int>(p);
  }
  return -1;
}

// The unused rim of `loops` whose centroid lies nearest `where`; -1 when none is left.
int nearestRim(const std::vector<BoundaryLoop>& loops, const std::vector<char>& used,
               const glm::vec3& where) {
  int best = -1;
  float best_d = std::numeric_limits<float>::max();
  for (std::size_t l = 0; l < loops.size(); ++l) {
    if (used[l] != 0) continue;
    const float d = glm::distance(loops[l].centroid, where);
    if (d < best_d) {
      best_d = d;
      best = static_cast<int>(l);
    }
  }
  return best;
}

// Taubin's lambda/mu smoothing (Taubin 1995) of the new vertices (from `first_new` on),
// the parts' vertices held: evens out the rings and chords without shrinking the region.
void fairRegions(std::vector<glm::vec3>& positions, const std::vector<std::uint32_t>& indices,
                 std::uint32_t first_new, int rounds) {
  const std::size_t nv = positions.size();
  if (rounds <= 0 || first_new >= nv) return;
  std::vector<std::vector<std::uint32_t>> next(nv - first_new);
  for (std::size_t t = 0; t + 2 < indices.size(); t += 3) {
    for (int e = 0; e < 3; ++e) {
      const std::uint32_t a = indices[t + e], b = indices[t + (e + 1) % 3];
      if (a >= first_new) next[a - first_new].push_back(b);
      if (b >= first_new) next[b - first_new].push_back(a);
    }
  }
  std::vector<glm::vec3> moved(nv - first_new);
  for (int r = 0; r < 2 * rounds; ++r) {
    const float factor = r % 2 == 0 ? 0.5f : -0.53f;
    for (std::size_t v = 0; v < moved.size(); ++v) {
      const glm::vec3& p = positions[first_new + v];
      glm::vec3 mean(0.0f);
      for (const std::uint32_t w : next[v]) mean += positions[w];
      moved[v] = next[v].empty() ? p : p + factor * (mean / static_cast<float>(next[v].size()) - p);
    }
    std::copy(moved.begin(), moved.end(), positions.begin() + first_new);
  }
}

}  // namespace

Result<std::vector<PartMesh>> readParts(const PartsManifest& manifest) {
  std::vector<PartMesh> parts;
  for (const ManifestPart& p : manifest.parts) {
    Result<PartMesh> part = readPartMesh(p.file);
    if (!part) return part.error();
    parts.push_back(std::move(*part));
  }
  return parts;
}

Result<AvatarModel> synthesizeAvatar(const PartsManifest& manifest,
                                     std::span<const PartMesh> parts_in, const AvatarModel& source,
                                     const SynthesisOptions& options, SynthesisReport* report) {
  if (parts_in.size() != manifest.parts.size()) {
    return fail("{} part meshes for {} parts", parts_in.size(), manifest.parts.size());
  }
  // The parts with the spikes along their rims trimmed.
  std::vector<PartMesh> parts(parts_in.begin(), parts_in.end());
  int spikes = 0;
  for (PartMesh& p : parts) spikes += trimRimSpikes(p, options.spike_rounds);
  if (source.skeleton.jointCount() == 0) return fail("the skeleton source has no joints");
  const bool with_skin = !source.skin.indices.empty() &&
                         validateSkinMesh(source.skin, source.skeleton.jointCount()).ok();
  SynthesisReport local;
  SynthesisReport& rep = report != nullptr ? *report : local;
  rep = {};
  rep.trimmed_spikes = spikes;

  // Each part's bone, its place in the output, its rims and its field.
  std::vector<std::uint16_t> bone(parts.size(), 0);
  std::vector<std::uint32_t> first(parts.size(), 0);
  std::vector<std::vector<BoundaryLoop>> rims(parts.size());
  std::vector<std::vector<char>> used(parts.size());
  std::vector<std::unique_ptr<PartField>> fields;
  std::uint32_t nv = 0;
  for (std::size_t p = 0; p < parts.size(); ++p) {
    const int j = source.skeleton.find(manifest.parts[p].bone);
    if (j < 0) {
      return fail("part '{}': the skeleton source has no joint '{}'", manifest.parts[p].segment,
                  manifest.parts[p].bone);
    }
    bone[p] = static_cast<std::uint16_t>(j);
    first[p] = nv;
    nv += static_cast<std::uint32_t>(parts[p].mesh.positions.size());
    rep.part_triangles += static_cast<int>(parts[p].mesh.indices.size() / 3);
    rims[p] = boundaryLoops(parts[p]);
    used[p].assign(rims[p].size(), 0);
    rep.rims += static_cast<int>(rims[p].size());
    fields.push_back(std::make_unique<PartField>(parts[p]));
  }
  rep.part_vertices = static_cast<int>(nv);

  // The parts' own vertices and triangles.
  AvatarModel out;
  out.name = source.name;
  out.skeleton = source.skeleton;
  SkinMesh& skin = out.skin;
  std::vector<glm::vec2> uvs;
  bool with_uvs = true;
  for (std::size_t p = 0; p < parts.size(); ++p) {
    const PartMesh& part = parts[p];
    skin.positions.insert(skin.positions.end(), part.mesh.positions.begin(),
                          part.mesh.positions.end());
    for (const std::uint32_t i : part.mesh.indices) skin.indices.push_back(first[p] + i);
    with_uvs = with_uvs && !part.uvs.empty();
    if (with_uvs) uvs.insert(uvs.end(), part.uvs.begin(), part.uvs.end());
  }

  // The parts' vertices' weights: the source skin's where they lie, else their bone's.
  std::vector<Influences> weights(nv);
  {
    std::optional<SkinTransfer> transfer;
    if (with_skin) transfer.emplace(source.skin);
    for (std::size_t p = 0; p < parts.size(); ++p) {
      for (std::size_t v = 0; v < parts[p].mesh.positions.size(); ++v) {
        Influences& w = weights[first[p] + v];
        if (transfer) w = transfer->at(parts[p].mesh.positions[v]);
        if (w.empty()) w = {{bone[p], 1.0f}};
      }
    }
  }

  // Each joint's child rim: the child part's unused rim nearest the joint.
  const std::size_t nj = manifest.joints.size();
  std::vector<SeamReport> seams(nj);
  std::vector<int> child_rim(nj, -1), parent_rim(nj, -1);
  for (std::size_t j = 0; j < nj; ++j) {
    const ManifestJoint& joint = manifest.joints[j];
    seams[j].joint = joint.name;
    seams[j].parent = joint.parent_segment;
    seams[j].child = joint.child_segment;
    const auto pc = static_cast<std::size_t>(partIndex(manifest, joint.child_segment));
    child_rim[j] = nearestRim(rims[pc], used[pc], joint.position);
    if (child_rim[j] < 0) {
      seams[j].why = fmt::format("no rim left on '{}'", joint.child_segment);
      continue;
    }
    used[pc][static_cast<std::size_t>(child_rim[j])] = 1;
  }
  // Its parent rim: the parent part's rim (not a child rim) lying nearest the child rim.
  for (std::size_t j = 0; j < nj; ++j) {
    if (child_rim[j] < 0) continue;
    const auto pp =
        static_cast<std::size_t>(partIndex(manifest, manifest.joints[j].parent_segment));
    const auto pc = static_cast<std::size_t>(partIndex(manifest, manifest.joints[j].child_segment));
    const BoundaryLoop& cl = rims[pc][static_cast<std::size_t>(child_rim[j])];
    float best = std::numeric_limits<float>::max();
    for (std::size_t l = 0; l < rims[pp].size(); ++l) {
      if (used[pp][l] == 1) continue;  // another joint's child rim
      float sum = 0.0f;
      for (const std::uint32_t cv : cl.vertices) {
        float nearest = std::numeric_limits<float>::max();
        for (const std::uint32_t pv : rims[pp][l].vertices) {
          nearest = std::min(
              nearest, glm::distance(parts[pc].mesh.positions[cv], parts[pp].mesh.positions[pv]));
        }
        sum += nearest;
      }
      const float mean = sum / static_cast<float>(cl.vertices.size());
      if (mean < best) {
        best = mean;
        parent_rim[j] = static_cast<int>(l);
      }
    }
    if (parent_rim[j] < 0) seams[j].why = fmt::format("no rim on '{}'", seams[j].parent);
  }

  // Attributes of a new vertex: blended from output vertices already placed.
  const auto appendBlend = [&](const glm::vec3& p, std::uint32_t a0, std::uint32_t b0, float t0,
                               std::uint32_t a1, std::uint32_t b1, float t1, float s) {
    skin.positions.push_back(p);
    weights.push_back(blendInfluences(blendInfluences(weights[a0], weights[b0], t0),
                                      blendInfluences(weights[a1], weights[b1], t1), s));
    if (with_uvs) {
      uvs.push_back(glm::mix(glm::mix(uvs[a0], uvs[b0], t0), glm::mix(uvs[a1], uvs[b1], t1), s));
    }
  };
  const auto curveOf = [&](std::size_t p, const BoundaryLoop& loop) {
    RimCurve c;
    for (const std::uint32_t v : loop.vertices) {
      c.index.push_back(first[p] + v);
      c.position.push_back(parts[p].mesh.positions[v]);
      c.normal.push_back(parts[p].normals[v]);
    }
    return c;
  };

  // Rim by rim of the parents: split when shared, then each child's region lofted.
  for (std::size_t j0 = 0; j0 < nj; ++j0) {
    if (parent_rim[j0] < 0 || seams[j0].lofted || !seams[j0].why.empty()) continue;
    const auto pp =
        static_cast<std::size_t>(partIndex(manifest, manifest.joints[j0].parent_segment));
    std::vector<std::size_t> group;
    for (std::size_t j = j0; j < nj; ++j) {
      if (parent_rim[j] == parent_rim[j0] && seams[j].why.empty() &&
          manifest.joints[j].parent_segment == manifest.joints[j0].parent_segment) {
        group.push_back(j);
      }
    }
    const BoundaryLoop& ploop = rims[pp][static_cast<std::size_t>(parent_rim[j0])];
    used[pp][static_cast<std::size_t>(parent_rim[j0])] = 1;
    const RimCurve whole = curveOf(pp, ploop);
    std::vector<RimCurve> child_curves;
    std::vector<const PartField*> child_fields;
    std::vector<std::size_t> child_parts;
    for (const std::size_t j : group) {
      const auto pc =
          static_cast<std::size_t>(partIndex(manifest, manifest.joints[j].child_segment));
      child_parts.push_back(pc);
      child_curves.push_back(curveOf(pc, rims[pc][static_cast<std::size_t>(child_rim[j])]));
      child_fields.push_back(fields[pc].get());
    }
    std::vector<RimCurve> pieces;
    if (group.size() == 1) {
      pieces.push_back(whole);
    } else {
      std::vector<const RimCurve*> child_ptrs;
      for (const RimCurve& c : child_curves) child_ptrs.push_back(&c);
      const float spacing =
          whole.position.empty() ? 0.01f : ploop.length / static_cast<float>(ploop.vertices.size());
      const SharedRimSplit split =
          splitSharedRim(whole, child_ptrs, child_fields,
                         static_cast<std::uint32_t>(skin.positions.size()), spacing);
      for (const ChordVertex& cv : split.chords) {
        appendBlend(cv.position, cv.from, cv.to, cv.t, cv.from, cv.to, cv.t, 0.0f);
      }
      rep.region_vertices += static_cast<int>(split.chords.size());
      pieces = split.pieces;
    }
    for (std::size_t g = 0; g < group.size(); ++g) {
      SeamReport& seam = seams[group[g]];
      const RimCurve& piece = pieces[g];
      const RimCurve& cc = child_curves[g];
      if (piece.index.size() < 3) {
        seam.why = fmt::format("the rim of '{}' it shares left it no piece", seam.parent);
        continue;
      }
      const LoftSide parent{&piece, fields[pp].get()};
      const LoftSide child{&cc, child_fields[g]};
      const auto first_new = static_cast<std::uint32_t>(skin.positions.size());
      const SeamLoft loft = loftSeam(parent, child, first_new, options.loft);
      for (std::size_t v = 0; v < loft.positions.size(); ++v) {
        const float s = loft.s[v];
        const RimPoint& a = loft.parent_at[v];
        const RimPoint& b = loft.child_at[v];
        appendBlend(loft.positions[v], piece.index[a.a], piece.index[a.b], a.t, cc.index[b.a],
                    cc.index[b.b], b.t, s * s * (3.0f - 2.0f * s));
      }
      const auto first_triangle = static_cast<std::uint32_t>(skin.indices.size() / 3);
      skin.indices.insert(skin.indices.end(), loft.indices.begin(), loft.indices.end());
      seam.lofted = true;
      seam.shared_rim = group.size() > 1;
      seam.parent_rim = static_cast<int>(piece.index.size());
      seam.child_rim = static_cast<int>(cc.index.size());
      seam.rings = loft.rings;
      seam.ring_size = loft.ring_size;
      seam.length_m = loft.length;
      seam.max_projection_m = loft.max_projection;
      for (std::uint32_t t = 0; t < loft.indices.size() / 3; ++t) {
        seam.region_triangles.push_back(first_triangle + t);
      }
      rep.region_vertices += static_cast<int>(loft.positions.size());
      rep.region_triangles += static_cast<int>(loft.indices.size() / 3);
    }
  }
  rep.seams = std::move(seams);
  fairRegions(skin.positions, skin.indices, nv, options.fairing_rounds);
  for (const std::vector<char>& u : used) {
    for (const char c : u) rep.rims_left_open += c == 0 ? 1 : 0;
  }

  // Vertices no triangle uses any more (spikes trimmed off the rims) are dropped.
  {
    std::vector<std::uint32_t> remap(skin.positions.size(), UINT32_MAX);
    for (const std::uint32_t i : skin.indices) remap[i] = 0;
    std::uint32_t kept = 0;
    int kept_parts = 0;
    for (std::size_t v = 0; v < remap.size(); ++v) {
      if (remap[v] == UINT32_MAX) continue;
      remap[v] = kept;
      skin.positions[kept] = skin.positions[v];
      weights[kept] = std::move(weights[v]);
      if (with_uvs) uvs[kept] = uvs[v];
      kept_parts += v < nv ? 1 : 0;
      ++kept;
    }
    skin.positions.resize(kept);
    weights.resize(kept);
    if (with_uvs) uvs.resize(kept);
    for (std::uint32_t& i : skin.indices) i = remap[i];
    rep.part_vertices = kept_parts;
  }

  // Simplified where flat: collapses that remove region vertices (and, when asked, part
  // vertices away from the rims), the survivors' attributes as they are.
  rep.undecimated_vertices = static_cast<int>(skin.positions.size());
  rep.undecimated_triangles = static_cast<int>(skin.indices.size() / 3);
  if (options.decimation.max_error_m > 0.0f) {
    const auto part_vertices = static_cast<std::uint32_t>(rep.part_vertices);
    const auto part_indices = static_cast<std::size_t>(3 * rep.part_triangles);
    std::vector<std::uint8_t> removable(skin.positions.size(), 0);
    for (std::size_t v = part_vertices; v < removable.size(); ++v) removable[v] = 1;
    if (options.decimate_parts) {
      std::vector<char> on_region(skin.positions.size(), 0);
      for (std::size_t i = part_indices; i < skin.indices.size(); ++i)
        on_region[skin.indices[i]] = 1;
      for (std::uint32_t v = 0; v < part_vertices; ++v) removable[v] = on_region[v] == 0 ? 1 : 0;
    }
    Result<DecimatedMesh> d =
        decimateMesh(skin.positions, skin.indices, removable, options.decimation);
    if (!d) return fail("decimating the skin: {}", d.error().message);
    std::vector<glm::vec3> positions(d->kept.size());
    std::vector<Influences> kept_weights(d->kept.size());
    std::vector<glm::vec2> kept_uvs(with_uvs ? d->kept.size() : 0);
    int kept_parts = 0;
    for (std::size_t v = 0; v < d->kept.size(); ++v) {
      const std::uint32_t old = d->kept[v];
      positions[v] = skin.positions[old];
      kept_weights[v] = std::move(weights[old]);
      if (with_uvs) kept_uvs[v] = uvs[old];
      kept_parts += old < part_vertices ? 1 : 0;
    }
    // Each seam's region triangles renumbered (those collapsed away dropped).
    std::vector<std::uint32_t> now(skin.indices.size() / 3, UINT32_MAX);
    int kept_part_triangles = 0;
    for (std::size_t t = 0; t < d->origin.size(); ++t) {
      now[d->origin[t]] = static_cast<std::uint32_t>(t);
      kept_part_triangles += 3 * d->origin[t] < part_indices ? 1 : 0;
    }
    for (SeamReport& seam : rep.seams) {
      std::vector<std::uint32_t> region;
      for (const std::uint32_t t : seam.region_triangles) {
        if (now[t] != UINT32_MAX) region.push_back(now[t]);
      }
      seam.region_triangles = std::move(region);
    }
    skin.positions = std::move(positions);
    skin.indices = std::move(d->indices);
    weights = std::move(kept_weights);
    if (with_uvs) uvs = std::move(kept_uvs);
    rep.part_vertices = kept_parts;
    rep.part_triangles = kept_part_triangles;
    rep.region_vertices = static_cast<int>(skin.positions.size()) - kept_parts;
    rep.region_triangles = static_cast<int>(skin.indices.size() / 3) - kept_part_triangles;
    rep.collapses = d->collapses;
  }

  // The skin: weights in the source's slots, normals, and the look.
  const std::size_t total = skin.positions.size();
  skin.influences = with_skin ? source.skin.influences : 4;
  const auto k = static_cast<std::size_t>(skin.influences);
  skin.joints.assign(total * k, 0);
  skin.weights.assign(total * k, 0.0f);
  for (std::size_t v = 0; v < total; ++v) {
    storeInfluences(weights[v], 0, std::span(skin.joints).subspan(v * k, k),
                    std::span(skin.weights).subspan(v * k, k));
  }
  skin.normals.assign(total, glm::vec3(0.0f));
  computeVertexNormals(skin.positions, skin.indices, skin.normals);
  if (with_uvs) {
    out.look.uvs = std::move(uvs);
    out.look.materials = source.look.materials;
    out.look.textures = source.look.textures;
  }
  if (Status st = validateAvatar(out); !st)
    return fail("the synthesized avatar: {}", st.error().message);
  return out;
}

}  // namespace vistel
