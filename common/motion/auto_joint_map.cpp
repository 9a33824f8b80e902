// Joint-map inference: naming schemes first, then topology and rest-pose geometry.
#include "common/motion/auto_joint_map.hpp"

#include <algorithm>
#include <array>
#include <cctype>
#include <cmath>
#include <set>

#include <fmt/format.h>
#include <fmt/ranges.h>
#include <glm/gtc/matrix_access.hpp>

namespace vistel {
namespace {

enum class Side { kNone, kLeft, kRight };

// A joint name split into its side and a lower-case base without separators.
struct NamePart {
  Side side = Side::kNone;
  std::string base;
};

std::string lower(std::string_view s) {
  std::string out(s);
  for (char& c : out) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return out;
}

bool isSeparator(char c) { return c == '_' || c == '.' || c == '-' || c == ' '; }

NamePart splitName(std::string_view name) {
  // Drop namespaces ("mixamorig:", "Armature|") and Rigify/Blender prefixes.
  if (const std::size_t cut = name.find_last_of(":|"); cut != std::string_view::npos) {
    name = name.substr(cut + 1);
  }
  for (std::string_view prefix : {"def-", "org-", "mch-", "mixamorig_", "mixamorig"}) {
    if (name.size() > prefix.size() && lower(name.substr(0, prefix.size())) == prefix) {
      name = name.substr(prefix.size());
      break;
    }
  }
  NamePart part;
  std::string rest(name);
  const std::string low = lower(name);
  if (low.starts_with("left")) {
    part.side = Side::kLeft;
    rest = rest.substr(4);
  } else if (low.starts_with("right")) {
    part.side = Side::kRight;
    rest = rest.substr(5);
  } else {
    // Tokens "l"/"r"/"left"/"right" between separators (thumb_01_l, upper_arm.L.001, L_Arm).
    std::vector<std::string> tokens(1);
    for (char c : rest) {
      if (isSeparator(c)) {
        tokens.emplace_back();
      } else {
        tokens.back() += c;
      }
    }
    std::string joined;
    for (std::size_t t = 0; t < tokens.size(); ++t) {
      const std::string tl = lower(tokens[t]);
      if (part.side == Side::kNone && tokens.size() > 1 && (tl == "l" || tl == "left")) {
        part.side = Side::kLeft;
      } else if (part.side == Side::kNone && tokens.size() > 1 && (tl == "r" || tl == "right")) {
        part.side = Side::kRight;
      } else {
        joined += tokens[t];
      }
    }
    rest = joined;
    // Camel case: "LHipJoint", "RHipJoint".
    if (part.side == Side::kNone && rest.size() > 2 && (rest[0] == 'L' || rest[0] == 'R') &&
        std::isupper(static_cast<unsigned char>(rest[1]))) {
      part.side = rest[0] == 'L' ? Side::kLeft : Side::kRight;
      rest = rest.substr(1);
    }
  }
  for (char c : rest) {
    if (!isSeparator(c))
      part.base += static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  }
  return part;
}

// One scheme: per canonical joint (without "l_"/"r_"), the base names to try, in order,
// separated by '|'. Sided canonical joints match names with that side.
struct SchemeEntry {
  std::string_view canonical;   // "hips" or a side-less limb name ("upperarm")
  std::string_view candidates;  // "upperarm|arm"
};
struct Scheme {
  std::string_view name;
  std::vector<SchemeEntry> entries;
};

const std::vector<Scheme>& schemes() {
  static const std::vector<Scheme> kSchemes = {
      {"mixamo",
       {{"hips", "hips"},           {"spine", "spine"},         {"chest", "spine1"},
        {"upper_chest", "spine2"},  {"neck", "neck"},           {"head", "head"},
        {"clavicle", "shoulder"},   {"upperarm", "arm"},        {"forearm", "forearm"},
        {"hand", "hand"},           {"thumb1", "handthumb1"},   {"thumb2", "handthumb2"},
        {"thumb3", "handthumb3"},   {"index1", "handindex1"},   {"index2", "handindex2"},
        {"index3", "handindex3"},   {"middle1", "handmiddle1"}, {"middle2", "handmiddle2"},
        {"middle3", "handmiddle3"}, {"ring1", "handring1"},     {"ring2", "handring2"},
        {"ring3", "handring3"},     {"pinky1", "handpinky1"},   {"pinky2", "handpinky2"},
        {"pinky3", "handpinky3"},   {"thigh", "upleg"},         {"shin", "leg"},
        {"foot", "foot"},           {"toes", "toebase"}}},
      {"vrm",
       {{"hips", "hips"},
        {"spine", "spine"},
        {"chest", "chest"},
        {"upper_chest", "upperchest"},
        {"neck", "neck"},
        {"head", "head"},
        {"clavicle", "shoulder"},
        {"upperarm", "upperarm"},
        {"forearm", "lowerarm"},
        {"hand", "hand"},
        {"thumb1", "thumbmetacarpal|thumbproximal"},
        {"thumb2", "thumbproximal|thumbintermediate"},
        {"thumb3", "thumbdistal"},
        {"index1", "indexproximal"},
        {"index2", "indexintermediate"},
        {"index3", "indexdistal"},
        {"middle1", "middleproximal"},
        {"middle2", "middleintermediate"},
        {"middle3", "middledistal"},
        {"ring1", "ringproximal"},
        {"ring2", "ringintermediate"},
        {"ring3", "ringdistal"},
        {"pinky1", "littleproximal"},
        {"pinky2", "littleintermediate"},
        {"pinky3", "littledistal"},
        {"thigh", "upperleg"},
        {"shin", "lowerleg"},
        {"foot", "foot"},
        {"toes", "toes"}}},
      {"unreal", {{"hips", "pelvis"},       {"spine", "spine01"},
                  {"chest", "spine02"},     {"upper_chest", "spine05|spine04|spine03"},
                  {"neck", "neck01|neck"},  {"head", "head"},
                  {"clavicle", "clavicle"}, {"upperarm", "upperarm"},
                  {"forearm", "lowerarm"},  {"hand", "hand"},
                  {"thumb1", "thumb01"},    {"thumb2", "thumb02"},
                  {"thumb3", "thumb03"},    {"index1", "index01"},
                  {"index2", "index02"},    {"index3", "index03"},
                  {"middle1", "middle01"},  {"middle2", "middle02"},
                  {"middle3", "middle03"},  {"ring1", "ring01"},
                  {"ring2", "ring02"},      {"ring3", "ring03"},
                  {"pinky1", "pinky01"},    {"pinky2", "pinky02"},
                  {"pinky3", "pinky03"},    {"thigh", "thigh"},
                  {"shin", "calf"},         {"foot", "foot"},
                  {"toes", "ball"}}},
      {"rigify", {{"hips", "spine"},        {"spine", "spine001"},
                  {"chest", "spine002"},    {"upper_chest", "spine003"},
                  {"neck", "spine004"},     {"head", "spine006|spine005"},
                  {"clavicle", "shoulder"}, {"upperarm", "upperarm"},
                  {"forearm", "forearm"},   {"hand", "hand"},
                  {"thumb1", "thumb01"},    {"thumb2", "thumb02"},
                  {"thumb3", "thumb03"},    {"index1", "findex01"},
                  {"index2", "findex02"},   {"index3", "findex03"},
                  {"middle1", "fmiddle01"}, {"middle2", "fmiddle02"},
                  {"middle3", "fmiddle03"}, {"ring1", "fring01"},
                  {"ring2", "fring02"},     {"ring3", "fring03"},
                  {"pinky1", "fpinky01"},   {"pinky2", "fpinky02"},
                  {"pinky3", "fpinky03"},   {"thigh", "thigh"},
                  {"shin", "shin"},         {"foot", "foot"},
                  {"toes", "toe"}}},
      {"cmu_01",
       {{"hips", "hips"},
        {"spine", "lowerback"},
        {"chest", "spine"},
        {"upper_chest", "spine1"},
        {"neck", "neck1"},
        {"head", "head"},
        {"clavicle", "shoulder"},
        {"upperarm", "arm"},
        {"forearm", "forearm"},
        {"hand", "hand"},
        {"thigh", "upleg"},
        {"shin", "leg"},
        {"foot", "foot"},
        {"toes", "toebase"}}},
      {"cmu_131",
       {{"hips", "hips"},
        {"spine", "lowerback"},
        {"chest", "chest"},
        {"upper_chest", "chest2"},
        {"neck", "neck"},
        {"head", "head"},
        {"clavicle", "collar"},
        {"upperarm", "shoulder"},
        {"forearm", "elbow"},
        {"hand", "wrist"},
        {"thigh", "hip"},
        {"shin", "knee"},
        {"foot", "ankle"},
        {"toes", "toe"}}},
      {"vistel", {{"hips", "hips"},         {"spine", "spine"},
                  {"chest", "chest"},       {"upper_chest", "upperchest"},
                  {"neck", "neck"},         {"head", "head"},
                  {"clavicle", "clavicle"}, {"upperarm", "upperarm"},
                  {"forearm", "forearm"},   {"hand", "hand"},
                  {"thumb1", "thumb1"},     {"thumb2", "thumb2"},
                  {"thumb3", "thumb3"},     {"index1", "index1"},
                  {"index2", "index2"},     {"index3", "index3"},
                  {"middle1", "middle1"},   {"middle2", "middle2"},
                  {"middle3", "middle3"},   {"ring1", "ring1"},
                  {"ring2", "ring2"},       {"ring3", "ring3"},
                  {"pinky1", "pinky1"},     {"pinky2", "pinky2"},
                  {"pinky3", "pinky3"},     {"thigh", "thigh"},
                  {"shin", "shin"},         {"foot", "foot"},
                  {"toes", "toes"}}},
  };
  return kSchemes;
}

constexpr std::size_t kCanonicalCount = 52;
constexpr std::string_view kTopology = "topology";

// Per canonical joint (canonicalJoints() order): the skeleton joint, or -1, and its origin.
struct Assignment {
  std::array<int, kCanonicalCount> joint;
  std::array<std::string, kCanonicalCount> origin;
  Assignment() { joint.fill(-1); }
  int count() const {
    return static_cast<int>(
        std::count_if(joint.begin(), joint.end(), [](int j) { return j >= 0; }));
  }
};

void put(Assignment& a, std::string_view canonical, int joint, std::string_view origin) {
  const int c = canonicalIndex(canonical);
  if (c < 0 || joint < 0) return;
  a.joint[static_cast<std::size_t>(c)] = joint;
  a.origin[static_cast<std::size_t>(c)] = std::string(origin);
}

Assignment matchScheme(const Scheme& scheme, const std::vector<NamePart>& parts) {
  Assignment a;
  std::vector<bool> used(parts.size(), false);
  const auto find = [&](Side side, std::string_view candidates) {
    std::size_t start = 0;
    while (start <= candidates.size()) {
      std::size_t end = candidates.find('|', start);
      if (end == std::string_view::npos) end = candidates.size();
      const std::string_view base = candidates.substr(start, end - start);
      for (std::size_t j = 0; j < parts.size(); ++j) {
        if (!used[j] && parts[j].side == side && parts[j].base == base) return static_cast<int>(j);
      }
      start = end + 1;
    }
    return -1;
  };
  for (const SchemeEntry& e : scheme.entries) {
    const bool sided = canonicalIndex(e.canonical) < 0;
    for (Side side : {Side::kLeft, Side::kRight}) {
      const std::string canonical =
          sided ? (side == Side::kLeft ? "l_" : "r_") + std::string(e.canonical)
                : std::string(e.canonical);
      const int j = find(sided ? side : Side::kNone, e.candidates);
      if (j >= 0) {
        used[static_cast<std::size_t>(j)] = true;
        put(a, canonical, j, scheme.name);
      }
      if (!sided) break;
    }
  }
  return a;
}

// ---- Topology and geometry ----

struct Rig {
  const Skeleton& s;
  std::vector<glm::vec3> pos;          // rest model-space position (njoint)
  std::vector<std::vector<int>> kids;  // children (njoint)
  std::vector<int> size;               // joints in the subtree, itself included (njoint)
  std::vector<std::string> why;        // reasons for what could not be found

  explicit Rig(const Skeleton& skeleton) : s(skeleton) {
    const std::vector<glm::mat4> model = restModelTransforms(s);
    const std::size_t n = s.names.size();
    pos.resize(n);
    kids.resize(n);
    size.assign(n, 1);
    for (std::size_t j = 0; j < n; ++j) pos[j] = glm::vec3(glm::column(model[j], 3));
    for (std::size_t j = n; j-- > 1;) {
      const int p = s.parents[j];
      if (p >= 0) size[static_cast<std::size_t>(p)] += size[j];
    }
    for (std::size_t j = 1; j < n; ++j) {
      if (s.parents[j] >= 0)
        kids[static_cast<std::size_t>(s.parents[j])].push_back(static_cast<int>(j));
    }
  }
  const std::vector<int>& children(int j) const { return kids[static_cast<std::size_t>(j)]; }
  int sizeOf(int j) const { return size[static_cast<std::size_t>(j)]; }
  glm::vec3 at(int j) const { return pos[static_cast<std::size_t>(j)]; }
  int largestChild(int j) const {
    int best = -1;
    for (int c : children(j)) {
      if (best < 0 || sizeOf(c) > sizeOf(best)) best = c;
    }
    return best;
  }
  // A leaf that only marks where a bone ends ("HeadTop_End", "Finger0Nub").
  bool isTip(int j) const {
    if (!children(j).empty()) return false;
    const std::string n = lower(s.names[static_cast<std::size_t>(j)]);
    return n.ends_with("end") || n.ends_with("nub") || n.ends_with("tip");
  }
};

glm::vec3 safeNormalize(glm::vec3 v) {
  const float len = glm::length(v);
  return len > 1e-8f ? v / len : glm::vec3(0.0f);
}

void dropTip(const Rig& rig, std::vector<int>& chain) {
  if (chain.size() > 1 && rig.isTip(chain.back())) chain.pop_back();
}

// A limb: from j through single children; at a fork, on into the largest child unless every
// child is small (a hand's fingers), where the limb ends.
std::vector<int> limbChain(const Rig& rig, int j) {
  std::vector<int> chain{j};
  for (;;) {
    const std::vector<int>& k = rig.children(j);
    if (k.empty()) break;
    if (k.size() >= 2) {
      int biggest = 0;
      for (int c : k) biggest = std::max(biggest, rig.sizeOf(c));
      if (biggest <= 5) break;
    }
    j = k.size() == 1 ? k[0] : rig.largestChild(j);
    chain.push_back(j);
  }
  dropTip(rig, chain);
  return chain;
}

// Single children only (neck to head, finger phalanges).
std::vector<int> simpleChain(const Rig& rig, int j) {
  std::vector<int> chain{j};
  while (rig.children(j).size() == 1) {
    j = rig.children(j)[0];
    chain.push_back(j);
  }
  dropTip(rig, chain);
  return chain;
}

// True when j forks into at least three chains, two of them (the arms) longer than one joint.
bool isBranchOfThree(const Rig& rig, int j) {
  const std::vector<int>& k = rig.children(j);
  if (k.size() < 3) return false;
  int long_ones = 0;
  for (int c : k) long_ones += rig.sizeOf(c) >= 2 ? 1 : 0;
  return long_ones >= 2;
}

void mapFingers(const Rig& rig, int hand, std::string_view side, Assignment& a) {
  const std::vector<int>& k = rig.children(hand);
  if (k.size() != 5) return;
  std::vector<std::vector<int>> chains;
  glm::vec3 mean(0.0f);
  for (int c : k) {
    chains.push_back(simpleChain(rig, c));
    if (chains.back().size() > 3) chains.back().resize(3);
    mean += safeNormalize(rig.at(chains.back().back()) - rig.at(hand));
  }
  mean = safeNormalize(mean);
  // Thumb: the chain that leaves the hand most to the side of the others.
  std::size_t thumb = 0;
  float worst = 2.0f;
  for (std::size_t i = 0; i < chains.size(); ++i) {
    const float d = glm::dot(safeNormalize(rig.at(chains[i].back()) - rig.at(hand)), mean);
    if (d < worst) {
      worst = d;
      thumb = i;
    }
  }
  glm::vec3 across = rig.at(chains[thumb].front()) - rig.at(hand);
  across = safeNormalize(across - glm::dot(across, mean) * mean);
  std::vector<std::size_t> others;
  for (std::size_t i = 0; i < chains.size(); ++i) {
    if (i != thumb) others.push_back(i);
  }
  std::sort(others.begin(), others.end(), [&](std::size_t x, std::size_t y) {
    return glm::dot(rig.at(chains[x].front()) - rig.at(hand), across) >
           glm::dot(rig.at(chains[y].front()) - rig.at(hand), across);
  });
  const std::array<std::string_view, 5> names = {"thumb", "index", "middle", "ring", "pinky"};
  for (std::size_t f = 0; f < 5; ++f) {
    const std::vector<int>& chain = chains[f == 0 ? thumb : others[f - 1]];
    for (std::size_t p = 0; p < chain.size(); ++p) {
      put(a, fmt::format("{}{}{}", side, names[f], p + 1), chain[p], kTopology);
    }
  }
}

Assignment inferTopology(Rig& rig) {
  Assignment a;
  // Hips: the first joint from the root that forks into three chains.
  int hips = 0;
  for (;;) {
    int long_kids = 0;
    for (int c : rig.children(hips)) long_kids += rig.sizeOf(c) >= 2 ? 1 : 0;
    if (long_kids >= 3) break;
    if (rig.children(hips).empty()) {
      rig.why.push_back(
          "no hips: the skeleton never forks into a spine and two legs (three chains)");
      return a;
    }
    hips = rig.largestChild(hips);
  }
  put(a, "hips", hips, kTopology);

  // Spine: the largest child chain up to the fork into neck and arms.
  std::vector<int> spine;
  int top = rig.largestChild(hips);
  spine.push_back(top);
  while (!isBranchOfThree(rig, top) && !rig.children(top).empty()) {
    top = rig.largestChild(top);
    spine.push_back(top);
  }
  const bool has_branch = isBranchOfThree(rig, top);
  if (!has_branch) {
    rig.why.push_back("no shoulders: the spine never forks into a neck and two arms");
  }
  const glm::vec3 up = safeNormalize(rig.at(top) - rig.at(hips));

  // Legs: the two other hip chains that point most away from the head.
  struct Leg {
    std::vector<int> chain;
    float down;
  };
  std::vector<Leg> legs;
  for (int c : rig.children(hips)) {
    if (c == spine.front() || rig.sizeOf(c) < 2) continue;
    std::vector<int> chain = limbChain(rig, c);
    const float down = -glm::dot(safeNormalize(rig.at(chain.back()) - rig.at(hips)), up);
    if (down > 0.5f) legs.push_back({std::move(chain), down});
  }
  std::sort(legs.begin(), legs.end(), [](const Leg& x, const Leg& y) { return x.down > y.down; });
  if (legs.size() < 2) {
    rig.why.push_back(fmt::format(
        "no legs: {} chain(s) below the hips point away from the head (two needed)", legs.size()));
    legs.clear();
  }
  legs.resize(std::min<std::size_t>(legs.size(), 2));

  // Thigh, shin and foot: the two longest consecutive bones of the chain end at the knee and
  // the ankle (a short hip joint before them, toes and a toe tip after them do not count);
  // the joint after the foot, if any, is the toes, whose direction gives forward.
  const auto length = [&](int from, int to) { return glm::length(rig.at(to) - rig.at(from)); };
  std::vector<int> toes(legs.size(), -1);
  glm::vec3 forward(0.0f);
  for (std::size_t l = 0; l < legs.size(); ++l) {
    std::vector<int>& c = legs[l].chain;
    if (c.size() < 3) continue;
    std::size_t best = 0;
    float best_length = -1.0f;
    for (std::size_t i = 0; i + 2 < c.size(); ++i) {
      const float sum = length(c[i], c[i + 1]) + length(c[i + 1], c[i + 2]);
      if (sum > best_length + 1e-6f) {
        best_length = sum;
        best = i;
      }
    }
    if (best + 3 < c.size()) {
      toes[l] = c[best + 3];
      const glm::vec3 d = rig.at(toes[l]) - rig.at(c[best + 2]);
      forward += d - glm::dot(d, up) * up;
    }
    c.erase(c.begin() + static_cast<std::ptrdiff_t>(best + 3), c.end());
  }
  forward = safeNormalize(forward);
  if (glm::length(forward) < 0.5f) {
    // No toes: vistel's +Z, or Blender's -Y for a Z-up rig.
    const glm::vec3 guess = std::abs(up.z) > 0.7f ? glm::vec3(0, -1, 0) : glm::vec3(0, 0, 1);
    forward = safeNormalize(guess - glm::dot(guess, up) * up);
  }
  const glm::vec3 left = safeNormalize(glm::cross(up, forward));
  const glm::vec3 centre = rig.at(hips);

  if (legs.size() == 2) {
    const auto side_of = [&](std::size_t l) {
      return glm::dot(rig.at(legs[l].chain.back()) - centre, left);
    };
    const std::size_t li = side_of(0) >= side_of(1) ? 0 : 1;
    for (std::size_t l = 0; l < 2; ++l) {
      const std::string s = l == li ? "l_" : "r_";
      const std::vector<int>& c = legs[l].chain;
      const std::size_t n = c.size();
      if (n >= 3) {
        put(a, s + "thigh", c[n - 3], kTopology);
        put(a, s + "shin", c[n - 2], kTopology);
        put(a, s + "foot", c[n - 1], kTopology);
      } else if (n == 2) {
        put(a, s + "thigh", c[0], kTopology);
        put(a, s + "shin", c[1], kTopology);
      }
      put(a, s + "toes", toes[l], kTopology);
    }
  }

  // Spine joints between hips and the fork.
  const std::size_t k = spine.size();
  put(a, "spine", spine[0], kTopology);
  if (k == 2) put(a, "chest", spine[1], kTopology);
  if (k >= 3) {
    put(a, "chest", spine[(k - 1) / 2], kTopology);
    put(a, "upper_chest", spine[k - 1], kTopology);
  }
  if (!has_branch) return a;

  // At the fork: the neck reaches highest; the arms are the two largest other chains.
  const std::vector<int>& forks = rig.children(top);
  int neck = -1;
  float best_up = -2.0f;
  for (int c : forks) {
    const std::vector<int> chain = simpleChain(rig, c);
    const float u = glm::dot(safeNormalize(rig.at(chain.back()) - rig.at(top)), up);
    if (u > best_up) {
      best_up = u;
      neck = c;
    }
  }
  // Neck to head: joints sitting on the fork (CMU's zero-length "Neck") are skipped; a chain
  // ending in a leaf after two or more joints ends in the head's tip (unnamed "HeadTop_End").
  std::vector<int> head_chain = simpleChain(rig, neck);
  const float torso = glm::length(rig.at(top) - rig.at(hips));
  while (head_chain.size() > 1 &&
         glm::length(rig.at(head_chain[0]) - rig.at(top)) < 0.02f * torso) {
    head_chain.erase(head_chain.begin());
  }
  const std::size_t m = head_chain.size();
  const bool ends_in_leaf = rig.children(head_chain.back()).empty();
  const int head = m >= 3 && ends_in_leaf ? head_chain[m - 2] : head_chain.back();
  if (m >= 2) put(a, "neck", head_chain[0], kTopology);
  put(a, "head", head, kTopology);

  std::vector<int> arms;
  for (int c : forks) {
    if (c != neck) arms.push_back(c);
  }
  std::sort(arms.begin(), arms.end(), [&](int x, int y) { return rig.sizeOf(x) > rig.sizeOf(y); });
  if (arms.size() < 2 || rig.sizeOf(arms[1]) < 2) {
    rig.why.push_back("no arms: the top of the spine has fewer than two arm chains");
    return a;
  }
  std::array<std::vector<int>, 2> arm_chains = {limbChain(rig, arms[0]), limbChain(rig, arms[1])};
  const auto side_of = [&](std::size_t i) {
    return glm::dot(rig.at(arm_chains[i].back()) - rig.at(top), left);
  };
  const std::size_t li = side_of(0) >= side_of(1) ? 0 : 1;
  for (std::size_t i = 0; i < 2; ++i) {
    const std::string s = i == li ? "l_" : "r_";
    const std::vector<int>& c = arm_chains[i];
    const std::size_t n = c.size();
    if (n < 2) {
      // A joint that forks at once into small chains: no upper arm and forearm to find.
      rig.why.push_back(fmt::format("no {}arm: its chain forks at once into small branches", s));
      continue;
    }
    if (n == 2) {
      put(a, s + "upperarm", c[0], kTopology);
      put(a, s + "forearm", c[1], kTopology);
      continue;
    }
    put(a, s + "hand", c[n - 1], kTopology);
    put(a, s + "forearm", c[n - 2], kTopology);
    put(a, s + "upperarm", c[n - 3], kTopology);
    if (n >= 4) put(a, s + "clavicle", c[n - 4], kTopology);
    mapFingers(rig, c[n - 1], s, a);
  }
  return a;
}

// Left/right by the rest pose: +1 when l_upperarm (or l_thigh) lies on the body's left of
// its right counterpart, -1 when on its right, 0 when unknown.
int sideAgreement(const Assignment& names, const Assignment& topo) {
  for (std::string_view part : {"upperarm", "thigh"}) {
    const int nl = names.joint[static_cast<std::size_t>(canonicalIndex(fmt::format("l_{}", part)))];
    const int nr = names.joint[static_cast<std::size_t>(canonicalIndex(fmt::format("r_{}", part)))];
    const int tl = topo.joint[static_cast<std::size_t>(canonicalIndex(fmt::format("l_{}", part)))];
    const int tr = topo.joint[static_cast<std::size_t>(canonicalIndex(fmt::format("r_{}", part)))];
    if (nl < 0 || nr < 0 || tl < 0 || tr < 0) continue;
    if (nl == tl && nr == tr) return 1;
    if (nl == tr && nr == tl) return -1;
  }
  return 0;
}

}  // namespace

Result<JointMapChoice> inferJointMap(const Skeleton& skeleton) {
  if (Status st = validateSkeleton(skeleton); !st) return st.error();
  std::vector<NamePart> parts;
  for (const std::string& n : skeleton.names) parts.push_back(splitName(n));

  // The scheme naming the most joints.
  Assignment names;
  for (const Scheme& scheme : schemes()) {
    Assignment a = matchScheme(scheme, parts);
    if (a.count() > names.count()) names = std::move(a);
  }
  Rig rig(skeleton);
  Assignment topo = inferTopology(rig);
  // Where the names call the pose's right side left, topology fills with the names' sides
  // (else it would hand a named side's joints to the other).
  const bool mirrored = sideAgreement(names, topo) < 0;
  if (mirrored) {
    const auto canonical = canonicalJoints();
    for (std::size_t c = 0; c < kCanonicalCount; ++c) {
      if (!canonical[c].starts_with("l_")) continue;
      const auto r = static_cast<std::size_t>(
          canonicalIndex(std::string("r_") + std::string(canonical[c].substr(2))));
      std::swap(topo.joint[c], topo.joint[r]);
      std::swap(topo.origin[c], topo.origin[r]);
    }
  }

  // Names first; topology fills what they leave, with joints the names did not take.
  Assignment out = names.count() >= 3 ? names : Assignment{};
  std::set<int> used;
  for (int j : out.joint) {
    if (j >= 0) used.insert(j);
  }
  for (std::size_t c = 0; c < kCanonicalCount; ++c) {
    if (out.joint[c] >= 0 || topo.joint[c] < 0 || used.count(topo.joint[c]) > 0) continue;
    out.joint[c] = topo.joint[c];
    out.origin[c] = topo.origin[c];
    used.insert(topo.joint[c]);
  }

  JointMapChoice choice;
  choice.inferred = true;
  if (mirrored) {
    choice.notes.push_back(
        "the joint names call the rest pose's right side left (a mirrored rig, or one facing "
        "away from its toes); the names' sides are kept");
  }
  std::vector<std::string> missing;
  for (std::string_view r : kDefaultRequiredJoints) {
    if (out.joint[static_cast<std::size_t>(canonicalIndex(r))] < 0) missing.emplace_back(r);
  }
  if (!missing.empty()) {
    return fail(
        "cannot map the skeleton ({} joints) to a humanoid: required joint(s) {} not found{}{}",
        skeleton.jointCount(), fmt::join(missing, ", "), rig.why.empty() ? "" : ": ",
        fmt::join(rig.why, "; "));
  }
  choice.map.name = "inferred";
  choice.map.source = "inferred from joint names and the rest pose";
  for (std::string_view r : kDefaultRequiredJoints) choice.map.required.emplace_back(r);
  const auto canonical = canonicalJoints();
  for (std::size_t c = 0; c < kCanonicalCount; ++c) {
    if (out.joint[c] < 0) continue;
    choice.map.canonical.emplace_back(canonical[c]);
    choice.map.joint.push_back(skeleton.names[static_cast<std::size_t>(out.joint[c])]);
    choice.origin.push_back(out.origin[c]);
  }
  return choice;
}

Result<JointMapChoice> chooseJointMap(std::span<const JointMap> maps, const Skeleton& skeleton) {
  Result<const JointMap*> selected = selectJointMap(maps, skeleton);
  if (selected) {
    JointMapChoice choice;
    choice.map = **selected;
    choice.origin.assign(choice.map.canonical.size(), choice.map.name);
    return choice;
  }
  Result<JointMapChoice> inferred = inferJointMap(skeleton);
  if (inferred) return inferred;
  return fail("{}\nand {}", inferred.error().message, selected.error().message);
}

Result<JointMapChoice> explicitJointMap(const JointMap& explicit_map, const Skeleton& skeleton) {
  if (Status st = validateSkeleton(skeleton); !st) return st.error();
  if (explicit_map.canonical.size() != explicit_map.joint.size()) {
    return fail("joint map '{}': {} canonical names for {} joints", explicit_map.name,
                explicit_map.canonical.size(), explicit_map.joint.size());
  }
  const std::size_t njoint = skeleton.names.size();
  std::vector<int> joint_of(kCanonicalCount, -1);
  std::vector<std::string> origin_of(kCanonicalCount);
  std::set<int> used;
  for (std::size_t e = 0; e < explicit_map.canonical.size(); ++e) {
    const int c = canonicalIndex(explicit_map.canonical[e]);
    if (c < 0) {
      return fail("joint map '{}': '{}' is not a canonical joint", explicit_map.name,
                  explicit_map.canonical[e]);
    }
    int j = -1;
    for (std::size_t k = 0; k < njoint; ++k) {
      if (skeleton.names[k] == explicit_map.joint[e]) j = static_cast<int>(k);
    }
    if (j < 0) {
      return fail("joint map '{}': {} is '{}', which the skeleton does not have", explicit_map.name,
                  explicit_map.canonical[e], explicit_map.joint[e]);
    }
    if (joint_of[static_cast<std::size_t>(c)] >= 0 || !used.insert(j).second) {
      return fail("joint map '{}': {} or joint '{}' is named twice", explicit_map.name,
                  explicit_map.canonical[e], explicit_map.joint[e]);
    }
    joint_of[static_cast<std::size_t>(c)] = j;
    origin_of[static_cast<std::size_t>(c)] = explicit_map.name;
  }
  JointMapChoice choice;
  // What the explicit map leaves out, inferred (with joints it did not take).
  if (Result<JointMapChoice> inferred = inferJointMap(skeleton); inferred) {
    for (std::size_t e = 0; e < inferred->map.canonical.size(); ++e) {
      const auto c = static_cast<std::size_t>(canonicalIndex(inferred->map.canonical[e]));
      if (joint_of[c] >= 0) continue;
      int j = -1;
      for (std::size_t k = 0; k < njoint; ++k) {
        if (skeleton.names[k] == inferred->map.joint[e]) j = static_cast<int>(k);
      }
      if (j < 0 || !used.insert(j).second) continue;
      joint_of[c] = j;
      origin_of[c] = inferred->origin[e];
    }
    choice.notes = inferred->notes;
  }
  choice.inferred = false;
  choice.map.name = explicit_map.name;
  choice.map.source = explicit_map.source;
  choice.map.required = explicit_map.required;
  if (choice.map.required.empty()) {
    for (std::string_view r : kDefaultRequiredJoints) choice.map.required.emplace_back(r);
  }
  const auto canonical = canonicalJoints();
  for (std::size_t c = 0; c < kCanonicalCount; ++c) {
    if (joint_of[c] < 0) continue;
    choice.map.canonical.emplace_back(canonical[c]);
    choice.map.joint.push_back(skeleton.names[static_cast<std::size_t>(joint_of[c])]);
    choice.origin.push_back(origin_of[c]);
  }
  std::vector<std::string> missing;
  for (const std::string& r : choice.map.required) {
    if (choice.map.jointFor(r).empty()) missing.push_back(r);
  }
  if (!missing.empty()) {
    return fail("joint map '{}': required joint(s) {} neither mapped nor inferred",
                explicit_map.name, fmt::join(missing, ", "));
  }
  return choice;
}

std::string describeJointMapChoice(const JointMapChoice& choice) {
  std::string out = fmt::format("map: {} ({})\n", choice.map.name, choice.map.source);
  for (std::size_t i = 0; i < choice.map.canonical.size(); ++i) {
    out += fmt::format("  {:<12} <- {:<24} [{}]\n", choice.map.canonical[i], choice.map.joint[i],
                       i < choice.origin.size() ? choice.origin[i] : std::string());
  }
  for (const std::string& n : choice.notes) out += fmt::format("note: {}\n", n);
  return out;
}

}  // namespace vistel
