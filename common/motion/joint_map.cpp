// Joint-name maps from TOML (toml++), loading from config/ or the embedded copies, and
// choosing the map that fits a skeleton.
#include "common/motion/joint_map.hpp"

#include <algorithm>
#include <array>
#include <filesystem>
#include <unordered_map>

#include <fmt/ranges.h>
#include <toml++/toml.h>

#include "common/base/embedded.hpp"
#include "common/base/file.hpp"

namespace vistel {
namespace {

constexpr std::array<std::string_view, 52> kCanonical = {
    "hips",       "spine",     "chest",     "upper_chest", "neck",       "head",       "l_clavicle",
    "l_upperarm", "l_forearm", "l_hand",    "l_thumb1",    "l_thumb2",   "l_thumb3",   "l_index1",
    "l_index2",   "l_index3",  "l_middle1", "l_middle2",   "l_middle3",  "l_ring1",    "l_ring2",
    "l_ring3",    "l_pinky1",  "l_pinky2",  "l_pinky3",    "r_clavicle", "r_upperarm", "r_forearm",
    "r_hand",     "r_thumb1",  "r_thumb2",  "r_thumb3",    "r_index1",   "r_index2",   "r_index3",
    "r_middle1",  "r_middle2", "r_middle3", "r_ring1",     "r_ring2",    "r_ring3",    "r_pinky1",
    "r_pinky2",   "r_pinky3",  "l_thigh",   "l_shin",      "l_foot",     "l_toes",     "r_thigh",
    "r_shin",     "r_foot",    "r_toes"};

// Parents by name, resolved to indices once.
std::array<int, 52> makeParents() {
  std::array<int, 52> parents{};
  const auto index = [](std::string_view name) {
    return static_cast<int>(std::find(kCanonical.begin(), kCanonical.end(), name) -
                            kCanonical.begin());
  };
  for (std::size_t i = 0; i < kCanonical.size(); ++i) {
    const std::string_view name = kCanonical[i];
    const std::string side(name.substr(0, 2));  // "l_" or "r_" for limbs
    std::string parent;
    if (name == "hips") {
      parents[i] = -1;
      continue;
    } else if (name == "spine") {
      parent = "hips";
    } else if (name == "chest") {
      parent = "spine";
    } else if (name == "upper_chest") {
      parent = "chest";
    } else if (name == "neck") {
      parent = "upper_chest";
    } else if (name == "head") {
      parent = "neck";
    } else if (name.ends_with("clavicle")) {
      parent = "upper_chest";
    } else if (name.ends_with("upperarm")) {
      parent = side + "clavicle";
    } else if (name.ends_with("forearm")) {
      parent = side + "upperarm";
    } else if (name.ends_with("hand")) {
      parent = side + "forearm";
    } else if (name.ends_with("thigh")) {
      parent = "hips";
    } else if (name.ends_with("shin")) {
      parent = side + "thigh";
    } else if (name.ends_with("foot")) {
      parent = side + "shin";
    } else if (name.ends_with("toes")) {
      parent = side + "foot";
    } else if (name.ends_with('1')) {
      parent = side + "hand";  // first phalanx of a finger
    } else {
      // Later phalanx: the previous one of the same finger.
      parent = std::string(name);
      parent.back() = static_cast<char>(parent.back() - 1);
    }
    parents[i] = index(parent);
  }
  return parents;
}

std::string fileStem(std::string_view source) {
  return std::filesystem::path(std::string(source)).stem().string();
}

std::string where(std::string_view source, const toml::source_region& region) {
  return fmt::format("{}:{}", source, region.begin.line);
}

}  // namespace

std::span<const std::string_view> canonicalJoints() { return kCanonical; }

std::span<const int> canonicalParents() {
  static const std::array<int, 52> kParents = makeParents();
  return kParents;
}

int canonicalIndex(std::string_view name) {
  const auto it = std::find(kCanonical.begin(), kCanonical.end(), name);
  return it == kCanonical.end() ? -1 : static_cast<int>(it - kCanonical.begin());
}

std::string_view JointMap::jointFor(std::string_view canonical_name) const {
  for (std::size_t i = 0; i < canonical.size(); ++i) {
    if (canonical[i] == canonical_name) return joint[i];
  }
  return {};
}

Result<JointMap> parseJointMap(std::string_view toml_text, std::string_view source_name) {
  // toml++ reports syntax errors by exception; they stop here.
  toml::table table;
  try {
    table = toml::parse(toml_text, source_name);
  } catch (const toml::parse_error& e) {
    return fail("{}:{}: {}", source_name, e.source().begin.line, e.description());
  }

  JointMap map;
  map.source = std::string(source_name);
  map.name = fileStem(source_name);
  std::vector<std::string> by_canonical(kCanonical.size());
  bool has_required = false;
  for (auto&& [key, node] : table) {
    const std::string_view k = key.str();
    const std::string at = where(source_name, key.source());
    if (k == "name" || k == "description") {
      const std::optional<std::string> value = node.value<std::string>();
      if (!value || value->empty()) return fail("{}: '{}' must be a non-empty string", at, k);
      if (k == "name") map.name = *value;
    } else if (k == "required") {
      const toml::array* list = node.as_array();
      if (list == nullptr) return fail("{}: 'required' must be an array of canonical names", at);
      has_required = true;
      for (const toml::node& item : *list) {
        const std::optional<std::string> value = item.value<std::string>();
        if (!value || canonicalIndex(*value) < 0) {
          return fail("{}: 'required' holds something that is not a canonical joint name", at);
        }
        map.required.push_back(*value);
      }
    } else if (k == "joints") {
      const toml::table* joints = node.as_table();
      if (joints == nullptr) return fail("{}: 'joints' must be a table", at);
      std::unordered_map<std::string, std::string> used;  // skeleton name -> canonical
      for (auto&& [jkey, jnode] : *joints) {
        const std::string canonical(jkey.str());
        const std::string jat = where(source_name, jkey.source());
        const int index = canonicalIndex(canonical);
        if (index < 0) {
          return fail("{}: [joints].{}: not a canonical joint name (see canonicalJoints())", jat,
                      canonical);
        }
        const std::optional<std::string> value = jnode.value<std::string>();
        if (!value || value->empty()) {
          return fail("{}: [joints].{}: the value must be a non-empty string (a joint name)", jat,
                      canonical);
        }
        if (const auto [it, inserted] = used.emplace(*value, canonical); !inserted) {
          return fail("{}: [joints].{}: joint '{}' is already mapped from '{}'", jat, canonical,
                      *value, it->second);
        }
        by_canonical[static_cast<std::size_t>(index)] = *value;
      }
    } else {
      return fail("{}: unknown key '{}' (expected name, description, required, [joints])", at, k);
    }
  }

  // Entries in canonical order; the required joints must be among them.
  for (std::size_t i = 0; i < kCanonical.size(); ++i) {
    if (by_canonical[i].empty()) continue;
    map.canonical.emplace_back(kCanonical[i]);
    map.joint.push_back(std::move(by_canonical[i]));
  }
  if (map.canonical.empty()) return fail("{}: the map has no [joints] entries", source_name);
  if (!has_required) {
    for (std::string_view r : kDefaultRequiredJoints) map.required.emplace_back(r);
  }
  for (const std::string& r : map.required) {
    if (map.jointFor(r).empty()) {
      return fail("{}: required joint '{}' is not in [joints]", source_name, r);
    }
  }
  return map;
}

Result<std::vector<JointMap>> loadJointMaps(const std::string& config_dir) {
  // Texts to parse: (name for messages, text), sorted by name.
  std::vector<std::pair<std::string, std::string>> files;
  const std::filesystem::path dir = std::filesystem::path(config_dir) / "skeletons";
  std::error_code ec;
  if (std::filesystem::is_directory(dir, ec)) {
    for (const auto& entry : std::filesystem::directory_iterator(dir, ec)) {
      if (entry.path().extension() != ".toml") continue;
      Result<std::string> text = readFileText(entry.path().string(), 1u << 20);
      if (!text) return text.error();
      files.emplace_back(entry.path().string(), std::move(*text));
    }
    if (ec) return fail("{}: cannot list the folder: {}", dir.string(), ec.message());
  } else {
    for (const EmbeddedFile& f : embeddedFiles()) {
      if (f.path.starts_with("skeletons/") && f.path.ends_with(".toml")) {
        files.emplace_back("config/" + std::string(f.path) + " (built in)", std::string(f.data));
      }
    }
  }
  std::sort(files.begin(), files.end());
  if (files.empty()) return fail("{}: no joint maps (*.toml) found", dir.string());

  std::vector<JointMap> maps;
  for (const auto& [name, text] : files) {
    Result<JointMap> map = parseJointMap(text, name);
    if (!map) return map.error();
    maps.push_back(std::move(*map));
  }
  return maps;
}

Result<const JointMap*> selectJointMap(std::span<const JointMap> maps, const Skeleton& skeleton) {
  const JointMap* best = nullptr;
  std::size_t best_found = 0;
  double best_share = 0.0;
  std::string report;
  for (const JointMap& map : maps) {
    std::size_t found = 0;
    for (const std::string& j : map.joint) found += skeleton.find(j) >= 0 ? 1 : 0;
    std::vector<std::string> missing;
    for (const std::string& r : map.required) {
      const std::string_view name = map.jointFor(r);
      if (name.empty() || skeleton.find(name) < 0) missing.push_back(std::string(name));
    }
    const double share = map.joint.empty() ? 0.0 : static_cast<double>(found) / map.joint.size();
    report += fmt::format("\n  {}: {} of {} joints found", map.name, found, map.joint.size());
    if (!missing.empty()) report += fmt::format(", missing required {}", fmt::join(missing, ", "));
    if (!missing.empty()) continue;
    if (best == nullptr || found > best_found || (found == best_found && share > best_share)) {
      best = &map;
      best_found = found;
      best_share = share;
    }
  }
  if (best == nullptr) {
    std::string names;
    for (int j = 0; j < skeleton.jointCount() && j < 8; ++j) {
      names += (j > 0 ? ", " : "") + skeleton.names[static_cast<std::size_t>(j)];
    }
    return fail("no joint map fits the skeleton ({} joints: {}{}):{}", skeleton.jointCount(), names,
                skeleton.jointCount() > 8 ? ", ..." : "", report);
  }
  return best;
}

}  // namespace vistel
