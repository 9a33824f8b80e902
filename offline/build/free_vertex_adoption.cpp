#include "offline/build/free_vertex_adoption.hpp"

#include <algorithm>
#include <map>
#include <string>
#include <vector>

#include "common/deform/inner_layers.hpp"
#include "offline/build/fit.hpp"

namespace vistel {
namespace {

// A limb capsule on the points' principal segment (a sphere for a compact cloud), r_in their
// mean skeleton distance, r_out at least `reach` times the largest and r_in / max_ratio.
ShapeFit fitAdopted(std::span<const glm::vec3> pts, float reach, float max_ratio) {
  glm::vec3 a, b;
  principalSegment(pts, a, b);
  ShapeFit fit = a == b ? fitSphere(pts, a, max_ratio) : fitSphylinder(pts, a, b, max_ratio);
  float biggest = 0.0f;
  for (const glm::vec3& p : pts) biggest = std::max(biggest, skeletonDistance(fit.shape, p));
  fit.r_in = std::max(fit.r_in, 1e-3f);
  fit.r_out = std::max({fit.r_out, reach * biggest, fit.r_in / max_ratio});
  return fit;
}

}  // namespace

Result<AdoptionReport> adoptFreeVertices(ImplicitModel& model, const Skeleton& skeleton,
                                         const SkinMesh& skin, const AdoptionOptions& opt,
                                         const FieldCalibrationOptions& calibration) {
  Calibration& c = model.calibration;
  PrimitiveSet& set = model.primitives;
  const std::size_t nv = skin.positions.size();
  const auto k = static_cast<std::size_t>(skin.influences);
  if (c.vertex_class.size() != nv || c.prims.size() != nv || skin.joints.size() != nv * k ||
      skin.weights.size() != nv * k || skin.normals.size() != nv) {
    return fail("adopting free vertices: skin of {} vertices, calibration of {}", nv,
                c.vertex_class.size());
  }
  const std::size_t np0 = set.items.size();
  if (model.graph.primitive_count != static_cast<int>(np0)) {
    return fail("adopting free vertices: graph not finalized for {} primitives", np0);
  }
  const int nj = skeleton.jointCount();
  // Per free vertex: the joint carrying most of its skin weight.
  std::vector<int> heaviest(nv, -1);
  for (std::size_t v = 0; v < nv; ++v) {
    // Inner layers (eyes, teeth) stay carried by their skinning alone.
    if (c.vertex_class[v] != VertexClass::kFree || innerVertex(c, v)) continue;
    float best = 0.0f;
    for (std::size_t s = 0; s < k; ++s) {
      const float w = skin.weights[v * k + s];
      const int j = skin.joints[v * k + s];
      if (w > best && j < nj) {
        best = w;
        heaviest[v] = j;
      }
    }
  }
  AdoptionReport report;
  const float iso = set.iso;
  // By heaviest joint: a primitive of their own. A vertex whose former owner is carried by
  // that same joint (a crown vertex beyond the head's support, demoted at calibration) stays
  // in the owner's fit as well, so the owner's skin does not move.
  std::map<int, std::vector<std::uint32_t>> groups;
  for (std::size_t v = 0; v < nv; ++v) {
    if (heaviest[v] >= 0) groups[heaviest[v]].push_back(static_cast<std::uint32_t>(v));
  }
  std::vector<std::int16_t> also_fits(nv, kNoPrimitive);
  // The map's primitives whose skin weight grids stay (fitted again they would come out the
  // same): all but the former owners of adopted vertices, whose fitted vertices change (a
  // free vertex is fitted only when demoted, which is not known here).
  std::vector<std::uint8_t> keep_grids(np0, 1);
  std::vector<int> owner_of;  // per new primitive: the primitive its vertices had as owner
  std::vector<glm::vec3> pts;
  for (const auto& [joint, members] : groups) {
    if (static_cast<int>(members.size()) < std::max(opt.min_vertices, 4)) continue;
    if (set.items.size() >= static_cast<std::size_t>(kMaxPrimitives)) {
      return fail("adopting free vertices: more than {} primitives", kMaxPrimitives);
    }
    // The former owner: the commonest p0 among them.
    std::map<int, int> votes;
    for (const std::uint32_t v : members) {
      if (c.prims[v][0] >= 0) ++votes[c.prims[v][0]];
    }
    int owner = -1, most = 0;
    for (const auto& [p, count] : votes) {
      if (count > most) {
        most = count;
        owner = p;
      }
    }
    pts.clear();
    for (const std::uint32_t v : members) pts.push_back(skin.positions[v]);
    Primitive q;
    // "<owner>/<joint>": the body part it belongs to, then its joint (see primitivePart).
    std::string name = skeleton.names[static_cast<std::size_t>(joint)];
    if (owner >= 0) name = set.items[static_cast<std::size_t>(owner)].name + "/" + name;
    while (std::any_of(set.items.begin(), set.items.end(),
                       [&name](const Primitive& p) { return p.name == name; })) {
      name += "+";
    }
    q.name = name;
    q.role = PrimitiveRole::kLimb;
    q.bone = joint;
    const ShapeFit fit = fitAdopted(pts, opt.reach, opt.max_surface_ratio);
    q.shape = fit.shape;
    q.r_in = fit.r_in;
    q.r_out = fit.r_out;
    if (owner >= 0) {
      const Primitive& o = set.items[static_cast<std::size_t>(owner)];
      q.density = o.density;
      q.stiffness = o.stiffness;
      q.elasticity = o.elasticity;
      q.time_constant = o.time_constant;
      q.collides = o.collides;
    }
    q.weight = shapeWeight(q.density, iso, q.r_in, q.r_out);
    const auto qi = static_cast<std::int16_t>(set.items.size());
    set.items.push_back(std::move(q));
    owner_of.push_back(owner);
    for (const std::uint32_t v : members) {
      const std::int16_t was = c.prims[v][0];
      if (was >= 0 && set.items[static_cast<std::size_t>(was)].bone == joint) also_fits[v] = was;
      if (was >= 0) keep_grids[static_cast<std::size_t>(was)] = 0;
      c.vertex_class[v] = VertexClass::kLimb;
      c.prims[v] = {qi, kNoPrimitive, kNoPrimitive, kNoPrimitive};
    }
    ++report.primitives;
    report.adopted += static_cast<int>(members.size());
  }
  if (report.primitives == 0) {  // nothing adopted: the model stays as it was
    report.calibration.limb = report.calibration.joint = report.calibration.free = 0;
    for (const VertexClass cls : c.vertex_class) {
      if (cls == VertexClass::kLimb) ++report.calibration.limb;
      if (cls == VertexClass::kJoint) ++report.calibration.joint;
      if (cls == VertexClass::kFree) ++report.calibration.free;
    }
    return report;
  }
  // Collisions within the body: a new primitive inherits its former owner's, except with the
  // owner and the other new primitives (within its own body an adopted primitive is no one's
  // partner: its vertices take a partner's whole contact, as they did free; see
  // DeformScratch::adopted).
  CombinationGraph& g = model.graph;
  const std::size_t np = set.items.size();
  for (std::size_t a = np0; a < np; ++a) {
    const int oa = owner_of[a - np0];
    if (oa < 0 || !set.items[a].collides) continue;
    for (std::size_t i = 0; i < np0; ++i) {
      if (!set.items[i].collides) continue;
      const int oi = static_cast<int>(i);
      if (oi == oa) continue;
      // Nor with the owner's neighbours across a joint (the upper arm for the chest, the
      // forearm for a finger): the owner meets those through the joint's blend.
      if (!g.collides(oa, oi) || g.neighbours(oa, oi)) continue;
      g.collide_pairs.push_back(
          {static_cast<std::uint16_t>(std::min(a, i)), static_cast<std::uint16_t>(std::max(a, i))});
    }
  }
  finalizeGraph(g, static_cast<int>(np));
  // Rigid flags and the own field's share for the vertices that got a field.
  if (c.rigid.size() != nv) c.rigid.assign(nv, 0);
  if (c.own_weight.size() != nv) c.own_weight.assign(nv, 1.0f);
  for (std::size_t v = 0; v < nv; ++v) {
    if (heaviest[v] < 0 || c.vertex_class[v] == VertexClass::kFree) continue;
    const int bone = set.items[static_cast<std::size_t>(c.prims[v][0])].bone;
    float own = 0.0f;
    for (std::size_t s = 0; s < k; ++s) {
      if (skin.joints[v * k + s] == bone) own += skin.weights[v * k + s];
    }
    // Untouched, it keeps its skinned position (as it did free): the field is for contact.
    c.rigid[v] = own >= 1.0f - 1e-6f ? kRigidLimb : kRigidUntouched;
    c.own_weight[v] = std::clamp(own, 0.0f, 1.0f);
  }
  Result<CalibrationReport> cal =
      calibrateModel(model, skin.positions, skin.normals, calibration, also_fits, keep_grids);
  if (!cal) return withContext("adopting free vertices", cal.error());
  report.calibration = *cal;
  return report;
}

}  // namespace vistel
