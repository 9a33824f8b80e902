#include "client/deform/part_forces.hpp"

#include <algorithm>

namespace vistel {

Result<PartForceLayout> makePartForceLayout(const AvatarModel& avatar) {
  if (!avatar.implicit) return fail("avatar '{}': no implicit model (no body parts)", avatar.name);
  const ImplicitModel& model = *avatar.implicit;
  const auto nvert = avatar.skin.positions.size();
  const auto nprim = model.primitives.items.size();
  if (model.calibration.prims.size() != nvert) {
    return fail("avatar '{}': calibration of {} vertices for a skin of {}", avatar.name,
                model.calibration.prims.size(), nvert);
  }
  PartForceLayout layout;
  // Parts: the body parts the primitives belong to (primitivePart: a finger or toe the
  // builder adopted is part of its hand or foot), in model order; each vertex's owner's part.
  std::vector<std::int16_t> part_of(nprim, -1);
  for (std::size_t i = 0; i < nprim; ++i) {
    const std::string_view part = primitivePart(model.primitives.items[i].name);
    const auto found = std::find(layout.names.begin(), layout.names.end(), part);
    part_of[i] = static_cast<std::int16_t>(found - layout.names.begin());
    if (found == layout.names.end()) layout.names.emplace_back(part);
  }
  layout.vertex_part.resize(nvert);
  for (std::size_t v = 0; v < nvert; ++v) {
    const std::int16_t p = model.calibration.prims[v][0];
    layout.vertex_part[v] =
        p >= 0 && static_cast<std::size_t>(p) < nprim ? part_of[static_cast<std::size_t>(p)] : -1;
  }
  // Vertex -> incident faces (counting, then filling).
  const std::vector<std::uint32_t>& idx = avatar.skin.indices;
  if (idx.size() % 3 != 0) return fail("avatar '{}': {} indices", avatar.name, idx.size());
  for (std::uint32_t i : idx) {
    if (i >= nvert) return fail("avatar '{}': index {} beyond {} vertices", avatar.name, i, nvert);
  }
  layout.indices = idx;
  layout.vf_offsets.assign(nvert + 1, 0);
  for (std::uint32_t i : idx) ++layout.vf_offsets[i + 1];
  for (std::size_t v = 0; v < nvert; ++v) layout.vf_offsets[v + 1] += layout.vf_offsets[v];
  layout.vf_faces.resize(idx.size());
  std::vector<std::uint32_t> fill(layout.vf_offsets.begin(), layout.vf_offsets.end() - 1);
  for (std::size_t k = 0; k < idx.size(); ++k) {
    layout.vf_faces[fill[idx[k]]++] = static_cast<std::uint32_t>(k / 3);
  }
  return layout;
}

int findPart(const PartForceLayout& layout, std::string_view name) {
  const auto found = std::find(layout.names.begin(), layout.names.end(), name);
  return found == layout.names.end() ? -1 : static_cast<int>(found - layout.names.begin());
}

void computePartForces(const PartForceLayout& layout, const PartForceInput& input,
                       std::span<PartForce> out) {
  std::fill(out.begin(), out.end(), PartForce{});
  const std::size_t nvert = layout.vertex_part.size();
  if (input.positions.size() != nvert || input.normals.size() != nvert ||
      input.pressure.size() != nvert || input.contact_body.size() != nvert) {
    return;
  }
  // Every vertex touching another body adds its force (model space) to its part.
  for (std::size_t v = 0; v < nvert; ++v) {
    const int partner = input.contact_body[v];
    const float p = input.pressure[v];
    if (partner < 0 || partner == input.self_body || !(p > 0.0f)) continue;
    const int part = layout.vertex_part[v];
    if (part < 0 || static_cast<std::size_t>(part) >= out.size()) continue;
    // One third of the incident faces' areas.
    double area = 0.0;
    for (std::uint32_t k = layout.vf_offsets[v]; k < layout.vf_offsets[v + 1]; ++k) {
      const std::size_t f = 3u * layout.vf_faces[k];
      const glm::dvec3 a(input.positions[layout.indices[f]]);
      const glm::dvec3 b(input.positions[layout.indices[f + 1]]);
      const glm::dvec3 c(input.positions[layout.indices[f + 2]]);
      area += 0.5 * glm::length(glm::cross(b - a, c - a));
    }
    area /= 3.0;
    const glm::dvec3 f_world = -(static_cast<double>(p) * area) * glm::dvec3(input.normals[v]);
    PartForce& pf = out[static_cast<std::size_t>(part)];
    pf.force += glm::vec3(glm::dmat3(input.world_to_model) * f_world);
    pf.area += static_cast<float>(area);
    ++pf.vertices;
  }
}

}  // namespace vistel
