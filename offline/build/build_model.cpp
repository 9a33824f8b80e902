// Offline building of the implicit model (DESIGN.md §3; primitives after Singh & Parent
// 1994, joint and bone primitives after the paper's humanoid of about 23 primitives).
#include "offline/build/build_model.hpp"

#include <algorithm>
#include <map>

#include "common/deform/inner_layers.hpp"
#include "common/deform/posed_primitives.hpp"
#include "offline/build/fit.hpp"
#include "offline/build/free_vertex_adoption.hpp"

namespace vistel {
namespace {

constexpr int kMinLimbVertices = 4;

struct Classified {
  VertexClass cls = VertexClass::kFree;
  int joint = -1;  // spec index of the joint primitive (joint vertices)
  int top1 = -1;   // spec index of the dominant limb (its own side / owner)
  int top2 = -1;   // spec index of the second limb (joint vertices: the opposite one)
};

struct Builder {
  const AvatarModel& avatar;
  const PrimitiveMapSpec& spec;
  const JointMap* map;
  BuildReport& report;

  std::vector<glm::vec3> joint_pos;    // bind-pose model position per joint
  std::vector<int> bone;               // per spec primitive: carrying joint, or -1
  std::vector<std::uint8_t> included;  // per spec primitive
  std::vector<int> group_of_joint;     // per avatar joint: owning limb (spec index) or -1
  std::map<std::pair<int, int>, int> joint_between;  // (limb, limb) -> joint spec index
  std::vector<Classified> classes;                   // per vertex
  std::vector<std::uint8_t> inner;  // per vertex: on an inner layer (eyes, teeth; free, unfitted)

  int resolve(const std::string& canonical) const {
    if (canonical.empty()) return -1;
    if (map == nullptr) return avatar.skeleton.find(canonical);
    for (std::size_t i = 0; i < map->canonical.size(); ++i) {
      if (map->canonical[i] == canonical) return avatar.skeleton.find(map->joint[i]);
    }
    return -1;
  }

  int specIndex(const std::string& name) const {
    for (std::size_t i = 0; i < spec.primitives.size(); ++i) {
      if (spec.primitives[i].name == name) return static_cast<int>(i);
    }
    return -1;
  }

  void warn(std::string text) { report.warnings.push_back(std::move(text)); }

  // Which primitives can be placed at all (their joints exist in this skeleton).
  void resolvePrimitives() {
    const std::size_t n = spec.primitives.size();
    bone.assign(n, -1);
    included.assign(n, 0);
    for (std::size_t i = 0; i < n; ++i) {
      const PrimitiveSpec& p = spec.primitives[i];
      int b = resolve(p.bone);
      if (b < 0 && p.role == PrimitiveRole::kLimb) {
        for (const std::string& j : p.joints) {
          if ((b = resolve(j)) >= 0) break;
        }
      }
      if (b < 0) {
        warn(fmt::format("primitive '{}' skipped: bone '{}' not in the skeleton", p.name, p.bone));
        continue;
      }
      if (p.role != PrimitiveRole::kLimb && resolve(p.at) < 0) {
        warn(fmt::format("primitive '{}' skipped: joint '{}' not in the skeleton", p.name, p.at));
        continue;
      }
      bone[i] = b;
      included[i] = 1;
    }
  }

  // Drops joint and bone primitives whose partners are gone; rebuilds the lookups.
  void settleDependencies() {
    for (std::size_t i = 0; i < spec.primitives.size(); ++i) {
      const PrimitiveSpec& p = spec.primitives[i];
      if (included[i] == 0) continue;
      if (p.role == PrimitiveRole::kJoint) {
        const int a = specIndex(p.between[0]);
        const int b = specIndex(p.between[1]);
        if (included[static_cast<std::size_t>(a)] == 0 ||
            included[static_cast<std::size_t>(b)] == 0) {
          included[i] = 0;
          warn(fmt::format("joint primitive '{}' skipped: a limb it joins is missing", p.name));
        }
      }
    }
    for (std::size_t i = 0; i < spec.primitives.size(); ++i) {
      const PrimitiveSpec& p = spec.primitives[i];
      if (included[i] != 0 && p.role == PrimitiveRole::kBone &&
          included[static_cast<std::size_t>(specIndex(p.blend))] == 0) {
        included[i] = 0;
        warn(fmt::format("bone primitive '{}' skipped: joint '{}' is missing", p.name, p.blend));
      }
    }
    group_of_joint.assign(static_cast<std::size_t>(avatar.skeleton.jointCount()), -1);
    joint_between.clear();
    for (std::size_t i = 0; i < spec.primitives.size(); ++i) {
      const PrimitiveSpec& p = spec.primitives[i];
      if (included[i] == 0) continue;
      if (p.role == PrimitiveRole::kLimb) {
        for (const std::string& j : p.joints) {
          const int ji = resolve(j);
          if (ji < 0) continue;
          int& g = group_of_joint[static_cast<std::size_t>(ji)];
          if (g < 0) g = static_cast<int>(i);
        }
        // The carrying bone always belongs to its primitive's group.
        int& g = group_of_joint[static_cast<std::size_t>(bone[i])];
        if (g < 0) g = static_cast<int>(i);
      } else if (p.role == PrimitiveRole::kJoint) {
        const int a = specIndex(p.between[0]);
        const int b = specIndex(p.between[1]);
        joint_between[{std::min(a, b), std::max(a, b)}] = static_cast<int>(i);
      }
    }
  }

  // Vertex classes from skin weights (DESIGN.md §3 "Vertex classes").
  void classify() {
    const SkinMesh& m = avatar.skin;
    const auto k = static_cast<std::size_t>(m.influences);
    classes.assign(m.positions.size(), Classified{});
    for (std::size_t v = 0; v < m.positions.size(); ++v) {
      // Inner layers are carried by their skinning alone: no primitive is fitted to them.
      if (!inner.empty() && inner[v] != 0) continue;
      // Skin weight per limb group.
      std::pair<int, float> groups[kMaxInfluences];
      int ng = 0;
      for (std::size_t s = 0; s < k; ++s) {
        const float w = m.weights[v * k + s];
        if (!(w > 0.0f)) continue;
        const int g = group_of_joint[m.joints[v * k + s]];
        if (g < 0) continue;
        int at = 0;
        while (at < ng && groups[at].first != g) ++at;
        if (at == ng) groups[ng++] = {g, 0.0f};
        groups[at].second += w;
      }
      // Heaviest first (insertion sort of at most kMaxInfluences entries).
      for (int i = 1; i < ng; ++i) {
        for (int j = i; j > 0; --j) {
          const auto& x = groups[j];
          const auto& y = groups[j - 1];
          if (!(x.second > y.second || (x.second == y.second && x.first < y.first))) break;
          std::swap(groups[j], groups[j - 1]);
        }
      }
      Classified& c = classes[v];
      if (ng == 0) continue;  // free, owner chosen later
      c.top1 = groups[0].first;
      if (ng > 1 && groups[1].second >= spec.joint_weight) {
        const int a = std::min(groups[0].first, groups[1].first);
        const int b = std::max(groups[0].first, groups[1].first);
        const auto it = joint_between.find({a, b});
        if (it != joint_between.end()) {
          c.cls = VertexClass::kJoint;
          c.joint = it->second;
          c.top2 = groups[1].first;
          continue;
        }
      }
      // Limb when the primitive's own bone carries enough of the vertex, else free.
      float own = 0.0f;
      for (std::size_t s = 0; s < k; ++s) {
        if (m.joints[v * k + s] == bone[static_cast<std::size_t>(c.top1)])
          own += m.weights[v * k + s];
      }
      c.cls = own >= spec.limb_weight ? VertexClass::kLimb : VertexClass::kFree;
    }
  }

  // Classifies until every included limb has enough vertices and every joint some.
  bool settle() {
    for (int round = 0; round < 64; ++round) {
      settleDependencies();
      classify();
      std::vector<int> count(spec.primitives.size(), 0);
      for (const Classified& c : classes) {
        if (c.top1 >= 0) ++count[static_cast<std::size_t>(c.top1)];
        if (c.cls == VertexClass::kJoint) ++count[static_cast<std::size_t>(c.joint)];
      }
      bool changed = false;
      for (std::size_t i = 0; i < spec.primitives.size(); ++i) {
        const PrimitiveRole role = spec.primitives[i].role;
        if (included[i] == 0 || role == PrimitiveRole::kBone) continue;
        if (count[i] < (role == PrimitiveRole::kLimb ? kMinLimbVertices : 1)) {
          included[i] = 0;
          changed = true;
          warn(fmt::format("primitive '{}' skipped: only {} skin vertices", spec.primitives[i].name,
                           count[i]));
        }
      }
      if (!changed) return true;
    }
    return false;
  }
};

}  // namespace

Result<ImplicitModel> buildImplicitModel(const AvatarModel& avatar, const PrimitiveMapSpec& spec,
                                         const JointMap* map, const BuildOptions& opt,
                                         BuildReport* report_out) {
  BuildReport local_report;
  BuildReport& report = report_out != nullptr ? *report_out : local_report;
  report = BuildReport{};
  const auto progress = [&](float f, std::string_view stage) {
    if (opt.progress) opt.progress(f, stage);
  };
  if (Status st = validateAvatar(avatar); !st)
    return withContext("building implicit model", st.error());

  Builder b{avatar, spec, map, report, {}, {}, {}, {}, {}, {}, {}};
  const Skeleton& sk = avatar.skeleton;
  const SkinMesh& mesh = avatar.skin;
  progress(0.0f, "classifying vertices");
  b.joint_pos.resize(static_cast<std::size_t>(sk.jointCount()));
  for (int j = 0; j < sk.jointCount(); ++j) {
    b.joint_pos[static_cast<std::size_t>(j)] =
        glm::vec3(glm::inverse(sk.inverse_bind[static_cast<std::size_t>(j)])[3]);
  }
  // Inner layers (eyes, teeth, tongue) lie inside the skin: fitted to them, the head's
  // primitive would lie inside its skin. They are carried by their skinning alone
  // (inner_layers.hpp), marked so before calibration.
  if (Result<InnerLayers> layers = findInnerLayers(mesh.positions, mesh.indices); !layers) {
    return withContext("building implicit model", layers.error());
  } else if (layers->inner_vertices > 0) {
    b.inner = std::move(layers->inner);
  }
  b.resolvePrimitives();
  if (!b.settle()) return fail("building implicit model: vertex classes do not settle");

  // Model order: the spec's order among the included primitives.
  std::vector<int> model_index(spec.primitives.size(), -1);
  std::vector<int> spec_of;
  for (std::size_t i = 0; i < spec.primitives.size(); ++i) {
    if (b.included[i] == 0) continue;
    model_index[i] = static_cast<int>(spec_of.size());
    spec_of.push_back(static_cast<int>(i));
  }
  if (spec_of.empty()) return fail("building implicit model: no primitive could be placed");
  if (spec_of.size() > static_cast<std::size_t>(kMaxPrimitives)) {
    return fail("building implicit model: {} primitives (at most {})", spec_of.size(),
                kMaxPrimitives);
  }
  const auto mi = [&](int spec_index) {
    return static_cast<std::int16_t>(model_index[static_cast<std::size_t>(spec_index)]);
  };

  ImplicitModel model;
  PrimitiveSet& set = model.primitives;
  set.iso = spec.iso;
  set.diff_exponent = spec.diff_exponent;
  set.propagation_amplitude = spec.propagation_amplitude;
  set.propagation_width = spec.propagation_width;
  set.items.resize(spec_of.size());

  // Fit limbs, then joints (on their joint vertices), then bones.
  progress(0.2f, "fitting primitives");
  std::vector<glm::vec3> pts;
  const auto place = [&](std::size_t k, const ShapeFit& fit) {
    const PrimitiveSpec& ps = spec.primitives[static_cast<std::size_t>(spec_of[k])];
    Primitive& p = set.items[k];
    p.name = ps.name;
    p.role = ps.role;
    p.bone = b.bone[static_cast<std::size_t>(spec_of[k])];
    p.shape = fit.shape;
    p.r_in = fit.r_in;
    p.r_out = fit.r_out;
    p.density = ps.material.density;
    p.stiffness = ps.material.stiffness;
    p.elasticity = ps.material.elasticity;
    p.time_constant = ps.material.time_constant;
    p.collides = ps.collides && ps.role != PrimitiveRole::kBone;
    p.weight = shapeWeight(p.density, set.iso, p.r_in, p.r_out);
  };
  const auto joint_at = [&](const std::string& name) -> std::optional<glm::vec3> {
    const int j = b.resolve(name);
    if (j < 0) return std::nullopt;
    return b.joint_pos[static_cast<std::size_t>(j)];
  };
  for (std::size_t k = 0; k < spec_of.size(); ++k) {
    const int si = spec_of[k];
    const PrimitiveSpec& ps = spec.primitives[static_cast<std::size_t>(si)];
    if (ps.role != PrimitiveRole::kLimb) continue;
    pts.clear();
    for (std::size_t v = 0; v < b.classes.size(); ++v) {
      if (b.classes[v].top1 == si) pts.push_back(mesh.positions[v]);
    }
    std::optional<glm::vec3> a = joint_at(ps.from);
    std::optional<glm::vec3> e = joint_at(ps.to);
    if (!ps.from.empty() && (!a || !e)) {
      b.warn(
          fmt::format("primitive '{}': segment joints missing, fitted by principal axis", ps.name));
    }
    if (a && e && glm::length(*a - *e) < 1e-5f) a = e = std::nullopt;
    const float ratio = spec.max_surface_ratio;
    switch (ps.shape) {
      case ShapeKind::kSphere:
        place(k, fitSphere(pts, ps.at.empty() ? std::nullopt : joint_at(ps.at), ratio));
        break;
      case ShapeKind::kSphylinder:
        place(k, fitSphylinder(pts, a, e, ratio));
        break;
      case ShapeKind::kConeSphere:
        place(k, fitConeSphere(pts, a, e, ratio));
        break;
      case ShapeKind::kOffsetPolygon:
        place(k, fitOffsetPolygon(pts, ps.normal, ratio));
        break;
    }
  }
  for (std::size_t k = 0; k < spec_of.size(); ++k) {
    const int si = spec_of[k];
    const PrimitiveSpec& ps = spec.primitives[static_cast<std::size_t>(si)];
    if (ps.role != PrimitiveRole::kJoint) continue;
    pts.clear();
    for (std::size_t v = 0; v < b.classes.size(); ++v) {
      if (b.classes[v].cls == VertexClass::kJoint && b.classes[v].joint == si) {
        pts.push_back(mesh.positions[v]);
      }
    }
    place(k, fitSphere(pts, joint_at(ps.at), spec.max_surface_ratio));
  }
  for (std::size_t k = 0; k < spec_of.size(); ++k) {
    const int si = spec_of[k];
    const PrimitiveSpec& ps = spec.primitives[static_cast<std::size_t>(si)];
    if (ps.role != PrimitiveRole::kBone) continue;
    // Centre: `offset` from the joint by depth x the joint primitive's radius; bound: a
    // little past the nearest skin vertex of the joint's region, so it blends in only
    // where the skin comes near.
    const int js = b.specIndex(ps.blend);
    const Primitive& joint = set.items[static_cast<std::size_t>(mi(js))];
    const glm::vec3 centre = *joint_at(ps.at) + (ps.depth * joint.r_in) * *ps.offset;
    const PrimitiveSpec& jspec = spec.primitives[static_cast<std::size_t>(js)];
    const int la = b.specIndex(jspec.between[0]);
    const int lb = b.specIndex(jspec.between[1]);
    float nearest = INFINITY;
    for (std::size_t v = 0; v < b.classes.size(); ++v) {
      const Classified& c = b.classes[v];
      if (c.top1 == la || c.top1 == lb || c.joint == js) {
        nearest = std::min(nearest, glm::length(mesh.positions[v] - centre));
      }
    }
    ShapeFit fit;
    fit.shape.kind = ShapeKind::kSphere;
    fit.shape.a = fit.shape.b = centre;
    prepareShape(fit.shape);
    fit.r_out = std::max(ps.reach * nearest, 1e-3f);
    fit.r_in = 0.5f * fit.r_out;
    place(k, fit);
  }

  // Per-vertex classes and defining primitives.
  progress(0.4f, "vertex classes");
  Calibration& cal = model.calibration;
  const std::size_t nv = mesh.positions.size();
  cal.vertex_class.resize(nv);
  cal.prims.assign(nv, {kNoPrimitive, kNoPrimitive, kNoPrimitive, kNoPrimitive});
  PosedPrimitives rest;
  rest.items.resize(set.items.size());
  for (std::size_t k = 0; k < set.items.size(); ++k)
    rest.items[k] = posePrimitive(set.items[k], glm::mat4(1.0f));
  for (std::size_t v = 0; v < nv; ++v) {
    const Classified& c = b.classes[v];
    cal.vertex_class[v] = c.cls;
    if (c.cls == VertexClass::kJoint) {
      cal.prims[v] = {mi(c.joint), mi(c.top1), mi(c.top2), kNoPrimitive};
    } else if (c.top1 >= 0) {
      cal.prims[v][0] = mi(c.top1);
    } else {
      // No limb group: owned by the limb primitive it is deepest in (for collisions).
      float best = INFINITY;
      for (std::size_t k = 0; k < set.items.size(); ++k) {
        if (set.items[k].role != PrimitiveRole::kLimb) continue;
        const float d =
            skeletonDistance(rest.items[k].shape, mesh.positions[v]) * rest.items[k].inv_r_out;
        if (d < best) {
          best = d;
          cal.prims[v][0] = static_cast<std::int16_t>(k);
        }
      }
    }
  }
  // Limb vertices skinned entirely by their primitive's bone never change shape on their own.
  cal.rigid.assign(nv, 0);
  {
    const auto k = static_cast<std::size_t>(mesh.influences);
    for (std::size_t v = 0; v < nv; ++v) {
      if (cal.vertex_class[v] != VertexClass::kLimb) continue;
      const int bone = set.items[static_cast<std::size_t>(cal.prims[v][0])].bone;
      float own = 0.0f;
      for (std::size_t s = 0; s < k; ++s) {
        if (mesh.joints[v * k + s] == bone) own += mesh.weights[v * k + s];
      }
      cal.rigid[v] = own >= 1.0f - 1e-6f ? 1 : 0;
    }
  }
  // Bone primitives join the joint vertices of their joint, and the limb vertices of the
  // two limbs inside their bound.
  for (std::size_t k = 0; k < set.items.size(); ++k) {
    const PrimitiveSpec& ps = spec.primitives[static_cast<std::size_t>(spec_of[k])];
    if (ps.role != PrimitiveRole::kBone) continue;
    const int js = b.specIndex(ps.blend);
    const PrimitiveSpec& jspec = spec.primitives[static_cast<std::size_t>(js)];
    const std::int16_t la = mi(b.specIndex(jspec.between[0]));
    const std::int16_t lb = mi(b.specIndex(jspec.between[1]));
    for (std::size_t v = 0; v < nv; ++v) {
      auto& pr = cal.prims[v];
      if (pr[3] != kNoPrimitive) continue;
      const bool joint_vertex = cal.vertex_class[v] == VertexClass::kJoint && pr[0] == mi(js);
      const bool limb_vertex = cal.vertex_class[v] == VertexClass::kLimb &&
                               (pr[0] == la || pr[0] == lb) &&
                               primitiveField(rest.items[k], mesh.positions[v]) > 0.0f;
      if (joint_vertex || limb_vertex) {
        pr[3] = static_cast<std::int16_t>(k);
        cal.rigid[v] = 0;
      }
    }
  }
  // How much of each vertex's skin the bones its own field models carry (the own field's
  // fade, DeformOptions::own_fade_low): its own primitives' bones, and a limb's partner
  // across a joint primitive (whose DIFF models the blend between the two).
  cal.own_weight.assign(nv, 1.0f);
  {
    std::vector<std::array<std::int16_t, 2>> joined;  // limb pairs a joint primitive blends
    for (std::size_t p = 0; p < set.items.size(); ++p) {
      const PrimitiveSpec& ps = spec.primitives[static_cast<std::size_t>(spec_of[p])];
      if (ps.role != PrimitiveRole::kJoint) continue;
      joined.push_back({mi(b.specIndex(ps.between[0])), mi(b.specIndex(ps.between[1]))});
    }
    const auto bone_of = [&](std::int16_t p) {
      return set.items[static_cast<std::size_t>(p)].bone;
    };
    const auto k = static_cast<std::size_t>(mesh.influences);
    std::vector<int> modelled;
    for (std::size_t v = 0; v < nv; ++v) {
      if (cal.vertex_class[v] == VertexClass::kFree) continue;
      const auto& pr = cal.prims[v];
      modelled.clear();
      for (const std::int16_t p : pr) {
        if (p >= 0) modelled.push_back(bone_of(p));
      }
      for (const auto& [la, lb] : joined) {
        if (pr[0] == la && lb >= 0) modelled.push_back(bone_of(lb));
        if (pr[0] == lb && la >= 0) modelled.push_back(bone_of(la));
      }
      float own = 0.0f;
      for (std::size_t s = 0; s < k; ++s) {
        if (std::find(modelled.begin(), modelled.end(), mesh.joints[v * k + s]) != modelled.end())
          own += mesh.weights[v * k + s];
      }
      cal.own_weight[v] = std::clamp(own, 0.0f, 1.0f);
    }
  }

  // Combination graph: joints blend their two limbs; everything else that collides does,
  // except a joint with its own limbs and the map's no_collide pairs.
  progress(0.5f, "combination graph");
  CombinationGraph& graph = model.graph;
  for (std::size_t k = 0; k < set.items.size(); ++k) {
    const PrimitiveSpec& ps = spec.primitives[static_cast<std::size_t>(spec_of[k])];
    if (ps.role != PrimitiveRole::kJoint) continue;
    graph.blends.push_back({static_cast<std::uint16_t>(mi(b.specIndex(ps.between[0]))),
                            static_cast<std::uint16_t>(mi(b.specIndex(ps.between[1]))),
                            static_cast<std::uint16_t>(k)});
  }
  const auto joins = [&](std::size_t j, std::size_t limb) {
    const PrimitiveSpec& ps = spec.primitives[static_cast<std::size_t>(spec_of[j])];
    if (ps.role != PrimitiveRole::kJoint) return false;
    return mi(b.specIndex(ps.between[0])) == static_cast<int>(limb) ||
           mi(b.specIndex(ps.between[1])) == static_cast<int>(limb);
  };
  for (std::size_t i = 0; i < set.items.size(); ++i) {
    for (std::size_t j = i + 1; j < set.items.size(); ++j) {
      if (!set.items[i].collides || !set.items[j].collides) continue;
      if (joins(i, j) || joins(j, i)) continue;
      bool excluded = false;
      for (const auto& nc : spec.no_collide) {
        if ((nc[0] == set.items[i].name && nc[1] == set.items[j].name) ||
            (nc[1] == set.items[i].name && nc[0] == set.items[j].name)) {
          excluded = true;
        }
      }
      if (!excluded) {
        graph.collide_pairs.push_back(
            {static_cast<std::uint16_t>(i), static_cast<std::uint16_t>(j)});
      }
    }
  }
  finalizeGraph(graph, static_cast<int>(set.items.size()));

  // Calibration and relaxation weights.
  progress(0.6f, "relaxation weights");
  computeRelaxationWeights(mesh.positions, mesh.normals, mesh.indices, cal);
  if (!b.inner.empty()) {
    if (Result<int> carried = carryInnerLayersRigidly(b.inner, cal); !carried) {
      return withContext("building implicit model", carried.error());
    }
  }
  progress(0.8f, "calibration");
  Result<CalibrationReport> calib =
      calibrateModel(model, mesh.positions, mesh.normals, opt.calibration);
  if (!calib) return withContext("building implicit model", calib.error());
  report.calibration = *calib;
  if (opt.adopt_free_vertices) {
    progress(0.9f, "adopting free vertices");
    Result<AdoptionReport> adopted = adoptFreeVertices(model, sk, mesh, {}, opt.calibration);
    if (!adopted) return withContext("building implicit model", adopted.error());
    report.adopted_primitives = adopted->primitives;
    report.adopted_vertices = adopted->adopted;
    if (adopted->primitives > 0) report.calibration = adopted->calibration;
  }
  for (const Primitive& p : set.items) report.primitives.push_back(p.name);
  if (Status st = validateImplicitModel(model, sk.jointCount(), static_cast<int>(nv)); !st) {
    return withContext("building implicit model", st.error());
  }
  progress(1.0f, "done");
  return model;
}

}  // namespace vistel
