#include "offline/build/primitive_map.hpp"

#include <cmath>
#include <set>

#include <toml++/toml.h>

#include "common/base/embedded.hpp"

namespace vistel {
namespace {

std::string where(std::string_view source, const toml::source_region& r) {
  return fmt::format("{}:{}", source, r.begin.line);
}

Result<float> number(const toml::node& n, std::string_view at, std::string_view key) {
  const std::optional<double> v = n.value<double>();
  if (!v || !std::isfinite(*v)) return fail("{}: '{}' must be a finite number", at, key);
  return static_cast<float>(*v);
}

Result<std::string> text(const toml::node& n, std::string_view at, std::string_view key) {
  const std::optional<std::string> v = n.value<std::string>();
  if (!v || v->empty()) return fail("{}: '{}' must be a non-empty string", at, key);
  return *v;
}

Result<glm::vec3> vector3(const toml::node& n, std::string_view at, std::string_view key) {
  const toml::array* a = n.as_array();
  if (a == nullptr || a->size() != 3) return fail("{}: '{}' must be [x, y, z]", at, key);
  glm::vec3 out;
  for (std::size_t i = 0; i < 3; ++i) {
    const std::optional<double> v = (*a)[i].value<double>();
    if (!v || !std::isfinite(*v)) return fail("{}: '{}' must hold numbers", at, key);
    out[static_cast<int>(i)] = static_cast<float>(*v);
  }
  if (!(glm::length(out) > 0.0f)) return fail("{}: '{}' must not be zero", at, key);
  return glm::normalize(out);
}

Result<std::vector<std::string>> strings(const toml::node& n, std::string_view at,
                                         std::string_view key) {
  const toml::array* a = n.as_array();
  if (a == nullptr) return fail("{}: '{}' must be an array of strings", at, key);
  std::vector<std::string> out;
  for (const toml::node& item : *a) {
    const std::optional<std::string> v = item.value<std::string>();
    if (!v || v->empty()) return fail("{}: '{}' must hold non-empty strings", at, key);
    out.push_back(*v);
  }
  return out;
}

// A material key, if `key` is one; returns true when it consumed the key.
Result<bool> materialKey(Material& m, std::string_view key, const toml::node& n,
                         std::string_view at) {
  if (key == "density") {
    auto s = text(n, at, key);
    if (!s) return s.error();
    if (*s == "wyvill") {
      m.density.kind = DensityKind::kWyvill;
    } else if (*s == "piecewise") {
      m.density.kind = DensityKind::kPiecewise;
    } else {
      return fail("{}: density '{}' is not wyvill or piecewise", at, *s);
    }
  } else if (key == "knee" || key == "slope" || key == "time_constant") {
    auto v = number(n, at, key);
    if (!v) return v.error();
    (key == "knee" ? m.density.knee : key == "slope" ? m.density.slope : m.time_constant) = *v;
  } else if (key == "stiffness") {
    if (n.value<std::string>() == std::optional<std::string>("rigid")) {
      m.stiffness = kRigidStiffness;
    } else {
      auto v = number(n, at, key);
      if (!v) return v.error();
      if (!(*v > 0.0f)) return fail("{}: stiffness must be > 0 or \"rigid\"", at);
      m.stiffness = *v;
    }
  } else if (key == "elasticity") {
    auto s = text(n, at, key);
    if (!s) return s.error();
    if (*s == "elastic") {
      m.elasticity = Elasticity::kElastic;
    } else if (*s == "plastic") {
      m.elasticity = Elasticity::kPlastic;
    } else if (*s == "viscoelastic") {
      m.elasticity = Elasticity::kViscoelastic;
    } else {
      return fail("{}: elasticity '{}' is not elastic, plastic or viscoelastic", at, *s);
    }
  } else {
    return false;
  }
  if (!validDensity(m.density)) return fail("{}: density knee/slope out of range", at);
  if (!(m.time_constant > 0.0f)) return fail("{}: time_constant must be > 0", at);
  return true;
}

Result<PrimitiveSpec> parsePrimitive(const toml::table& t, const PrimitiveMapSpec& map,
                                     std::string_view source, const std::string& at_table) {
  PrimitiveSpec p;
  p.material = map.material;
  p.line = static_cast<int>(t.source().begin.line);
  bool has_shape = false;
  for (auto&& [key, node] : t) {
    const std::string_view k = key.str();
    const std::string at = where(source, key.source());
    Result<bool> mat = materialKey(p.material, k, node, at);
    if (!mat) return mat.error();
    if (*mat) continue;
    if (k == "name" || k == "bone" || k == "from" || k == "to" || k == "at" || k == "blend") {
      auto s = text(node, at, k);
      if (!s) return s.error();
      (k == "name"   ? p.name
       : k == "bone" ? p.bone
       : k == "from" ? p.from
       : k == "to"   ? p.to
       : k == "at"   ? p.at
                     : p.blend) = *s;
    } else if (k == "role") {
      auto s = text(node, at, k);
      if (!s) return s.error();
      if (*s == "limb") {
        p.role = PrimitiveRole::kLimb;
      } else if (*s == "joint") {
        p.role = PrimitiveRole::kJoint;
      } else if (*s == "bone") {
        p.role = PrimitiveRole::kBone;
      } else {
        return fail("{}: role '{}' is not limb, joint or bone", at, *s);
      }
    } else if (k == "shape") {
      auto s = text(node, at, k);
      if (!s) return s.error();
      has_shape = true;
      if (*s == "sphere") {
        p.shape = ShapeKind::kSphere;
      } else if (*s == "sphylinder" || *s == "capsule") {
        p.shape = ShapeKind::kSphylinder;
      } else if (*s == "cone_sphere") {
        p.shape = ShapeKind::kConeSphere;
      } else if (*s == "offset_polygon") {
        p.shape = ShapeKind::kOffsetPolygon;
      } else {
        return fail("{}: shape '{}' is not sphere, sphylinder, cone_sphere or offset_polygon", at,
                    *s);
      }
    } else if (k == "joints") {
      auto s = strings(node, at, k);
      if (!s) return s.error();
      p.joints = *s;
    } else if (k == "between") {
      auto s = strings(node, at, k);
      if (!s) return s.error();
      if (s->size() != 2) return fail("{}: 'between' must name two limb primitives", at);
      p.between = {(*s)[0], (*s)[1]};
    } else if (k == "offset" || k == "normal") {
      auto v = vector3(node, at, k);
      if (!v) return v.error();
      (k == "offset" ? p.offset : p.normal) = *v;
    } else if (k == "depth" || k == "reach") {
      auto v = number(node, at, k);
      if (!v) return v.error();
      if (!(*v > 0.0f) || *v > 10.0f) return fail("{}: '{}' out of range", at, k);
      (k == "depth" ? p.depth : p.reach) = *v;
    } else if (k == "collides") {
      const std::optional<bool> b = node.value<bool>();
      if (!b) return fail("{}: 'collides' must be true or false", at);
      p.collides = *b;
    } else {
      return fail("{}: unknown primitive key '{}'", at, k);
    }
  }
  if (p.name.empty()) return fail("{}: primitive without a name", at_table);
  if (!has_shape) return fail("{}: primitive '{}' without a shape", at_table, p.name);
  if (p.bone.empty()) return fail("{}: primitive '{}' without a bone", at_table, p.name);
  if (p.role == PrimitiveRole::kBone && !t.contains("collides")) p.collides = false;
  if (p.role == PrimitiveRole::kLimb && p.joints.empty()) p.joints = {p.bone};
  if (p.role != PrimitiveRole::kLimb && p.at.empty()) {
    return fail("{}: {} primitive '{}' needs 'at' (its centre joint)", at_table,
                p.role == PrimitiveRole::kJoint ? "joint" : "bone", p.name);
  }
  if (p.role != PrimitiveRole::kLimb && p.shape != ShapeKind::kSphere) {
    return fail("{}: joint and bone primitive '{}' must be spheres", at_table, p.name);
  }
  if (p.role == PrimitiveRole::kJoint && p.between[0].empty()) {
    return fail("{}: joint primitive '{}' needs 'between' (two limbs)", at_table, p.name);
  }
  if (p.role == PrimitiveRole::kBone && (p.blend.empty() || !p.offset)) {
    return fail("{}: bone primitive '{}' needs 'blend' and 'offset'", at_table, p.name);
  }
  if ((p.from.empty()) != (p.to.empty())) {
    return fail("{}: primitive '{}' needs both 'from' and 'to', or neither", at_table, p.name);
  }
  return p;
}

}  // namespace

const PrimitiveSpec* PrimitiveMapSpec::find(std::string_view name) const {
  for (const PrimitiveSpec& p : primitives) {
    if (p.name == name) return &p;
  }
  return nullptr;
}

Result<PrimitiveMapSpec> parsePrimitiveMap(std::string_view toml_text, std::string_view source) {
  toml::table table;
  try {
    table = toml::parse(toml_text, source);
  } catch (const toml::parse_error& e) {
    return fail("{}:{}: {}", source, e.source().begin.line, e.description());
  }
  PrimitiveMapSpec map;
  map.source = std::string(source);
  // Top-level scalars and tables other than the primitives first (materials are defaults).
  for (auto&& [key, node] : table) {
    const std::string_view k = key.str();
    const std::string at = where(source, key.source());
    if (k == "primitive" || k == "no_collide") continue;
    if (k == "iso" || k == "joint_weight" || k == "limb_weight" || k == "max_surface_ratio") {
      auto v = number(node, at, k);
      if (!v) return v.error();
      (k == "iso"            ? map.iso
       : k == "joint_weight" ? map.joint_weight
       : k == "limb_weight"  ? map.limb_weight
                             : map.max_surface_ratio) = *v;
    } else if (k == "diff_exponent") {
      const std::optional<std::int64_t> v = node.value<std::int64_t>();
      if (!v || *v < 1 || *v > 8) return fail("{}: diff_exponent must be an integer 1..8", at);
      map.diff_exponent = static_cast<int>(*v);
    } else if (k == "propagation" || k == "material") {
      const toml::table* t = node.as_table();
      if (t == nullptr) return fail("{}: '{}' must be a table", at, k);
      for (auto&& [sub, sub_node] : *t) {
        const std::string sub_at = where(source, sub.source());
        if (k == "material") {
          Result<bool> used = materialKey(map.material, sub.str(), sub_node, sub_at);
          if (!used) return used.error();
          if (!*used) return fail("{}: unknown material key '{}'", sub_at, sub.str());
        } else if (sub.str() == "amplitude" || sub.str() == "width") {
          auto v = number(sub_node, sub_at, sub.str());
          if (!v) return v.error();
          (sub.str() == "amplitude" ? map.propagation_amplitude : map.propagation_width) = *v;
        } else {
          return fail("{}: unknown propagation key '{}'", sub_at, sub.str());
        }
      }
    } else {
      return fail("{}: unknown key '{}'", at, k);
    }
  }
  if (!(map.iso > 0.0f && map.iso < 1.0f)) return fail("{}: iso must be in (0, 1)", source);
  if (!(map.joint_weight > 0.0f && map.joint_weight < 0.5f)) {
    return fail("{}: joint_weight must be in (0, 0.5)", source);
  }
  if (!(map.limb_weight > 0.0f && map.limb_weight <= 1.0f)) {
    return fail("{}: limb_weight must be in (0, 1]", source);
  }
  if (!(map.max_surface_ratio > 0.1f && map.max_surface_ratio < 0.95f)) {
    return fail("{}: max_surface_ratio must be in (0.1, 0.95)", source);
  }
  if (!(map.propagation_amplitude >= 0.0f) || !(map.propagation_width > 0.0f) ||
      !(map.propagation_width < map.iso)) {
    return fail("{}: propagation amplitude must be >= 0 and 0 < width < iso", source);
  }
  // The primitives.
  if (const toml::node* prims = table.get("primitive")) {
    const toml::array* list = prims->as_array();
    if (list == nullptr) return fail("{}: 'primitive' must be an array of tables", source);
    for (const toml::node& item : *list) {
      const toml::table* t = item.as_table();
      const std::string at = where(source, item.source());
      if (t == nullptr) return fail("{}: each [[primitive]] must be a table", at);
      auto p = parsePrimitive(*t, map, source, at);
      if (!p) return p.error();
      if (map.find(p->name) != nullptr) return fail("{}: duplicate primitive '{}'", at, p->name);
      map.primitives.push_back(std::move(*p));
    }
  }
  if (map.primitives.empty()) return fail("{}: no [[primitive]] defined", source);
  if (const toml::node* nc = table.get("no_collide")) {
    const toml::array* list = nc->as_array();
    const std::string at = where(source, nc->source());
    if (list == nullptr) return fail("{}: 'no_collide' must be an array of [name, name]", at);
    for (const toml::node& item : *list) {
      auto pair = strings(item, at, "no_collide");
      if (!pair || pair->size() != 2)
        return fail("{}: 'no_collide' entries must be [name, name]", at);
      map.no_collide.push_back({(*pair)[0], (*pair)[1]});
    }
  }
  // References.
  const auto role_of = [&](const std::string& name) -> std::optional<PrimitiveRole> {
    const PrimitiveSpec* p = map.find(name);
    return p != nullptr ? std::optional<PrimitiveRole>(p->role) : std::nullopt;
  };
  for (const PrimitiveSpec& p : map.primitives) {
    const std::string at = fmt::format("{}:{}", source, p.line);
    if (p.role == PrimitiveRole::kJoint) {
      for (const std::string& limb : p.between) {
        if (role_of(limb) != PrimitiveRole::kLimb) {
          return fail("{}: joint '{}': '{}' is not a limb primitive", at, p.name, limb);
        }
      }
      if (p.between[0] == p.between[1])
        return fail("{}: joint '{}' joins a limb to itself", at, p.name);
    }
    if (p.role == PrimitiveRole::kBone && role_of(p.blend) != PrimitiveRole::kJoint) {
      return fail("{}: bone '{}': blend '{}' is not a joint primitive", at, p.name, p.blend);
    }
  }
  for (const auto& pair : map.no_collide) {
    for (const std::string& name : pair) {
      if (!role_of(name)) return fail("{}: no_collide names unknown primitive '{}'", source, name);
    }
  }
  return map;
}

Result<PrimitiveMapSpec> loadPrimitiveMap(const std::string& path) {
  Result<std::string> text = readConfigText(path);
  if (!text) return text.error();
  return parsePrimitiveMap(*text, path);
}

}  // namespace vistel
