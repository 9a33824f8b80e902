// The static implicit model of one body (DESIGN.md §2, §3): PrimitiveSet (the
// primitives with their fitted radii and material), CombinationGraph (which primitives
// blend, which collide) and Calibration (per skin vertex: class, defining primitives,
// weight w_v, rest-contact thresholds, relaxation weights). Built offline (vistel_build)
// or by makeBall (props), then shared read-only by every pipeline.
//
// Spaces and units: primitive shapes are in bind-pose model space, metres; field values
// are dimensionless (the iso-value T, e.g. 0.5); stiffness is pascals per metre of
// penetration depth; time constants are seconds.
#pragma once

#include <array>
#include <cstdint>
#include <limits>
#include <string>
#include <string_view>
#include <vector>

#include "common/base/result.hpp"
#include "common/deform/density.hpp"
#include "common/deform/shape.hpp"

namespace vistel {

inline constexpr float kRigidStiffness = std::numeric_limits<float>::infinity();
inline constexpr int kMaxPrimitives = 4096;
inline constexpr std::int16_t kNoPrimitive = -1;

enum class PrimitiveRole : std::uint8_t {
  kLimb = 0,   // a body part's volume; defines limb vertices
  kJoint = 1,  // joint sphere between two limbs; defines joint vertices with both limbs
  kBone = 2,   // a bone close under the skin (elbow, knee): blends in only where near
};

enum class Elasticity : std::uint8_t {
  kElastic = 0,       // the contact offset is the instantaneous solution
  kPlastic = 1,       // a dent stays when contact ends (later contacts may deepen it)
  kViscoelastic = 2,  // a dent recovers as exp(-dt / time_constant) when contact ends
};

// The calibration weights w_v of a primitive's own skin (its limb or joint vertices) as a
// field around it in bind-pose model space: the skin that primitive makes lies where
// w(P) F(P) = T, so a partner vertex meets that skin, not the raw iso-surface F = T
// (which a fitted primitive misses by centimetres on a real face or hand). Looked up at a
// point's key (skinWeightKey in posed_primitives.hpp: where its ray from the skeleton
// crosses the shell at r_out / 2), so w is constant along each ray. Trilinear over n^3
// samples spanning `box`, clamped at its faces; n = 0: 1 everywhere (exact primitives,
// props).
struct SkinWeightGrid {
  Bounds box;                 // bind-pose model space; min < max on every axis
  int n = 0;                  // samples per axis: 0, or 2..kMaxSkinWeightSamples
  std::vector<float> values;  // n^3, x fastest, then y, then z; each in [kMinSkinWeight,
                              // kMaxSkinWeight]
  float max_value = 1.0f;     // the largest sample (1 when n = 0)
};
inline constexpr int kMaxSkinWeightSamples = 16;
inline constexpr float kMinSkinWeight = 0.25f;
inline constexpr float kMaxSkinWeight = 32.0f;

// w at a bind-space point (see SkinWeightGrid).
inline float skinWeightAt(const SkinWeightGrid& g, const glm::vec3& p) {
  if (g.n < 2) return 1.0f;
  const float last = static_cast<float>(g.n - 1);
  const glm::vec3 u = glm::clamp((p - g.box.min) / (g.box.max - g.box.min) * last, glm::vec3(0.0f),
                                 glm::vec3(last));
  const glm::ivec3 i = glm::min(glm::ivec3(u), glm::ivec3(g.n - 2));
  const glm::vec3 t = u - glm::vec3(i);
  // The cell's eight samples from its lowest corner (x fastest, then y, then z).
  const auto n = static_cast<std::size_t>(g.n);
  const float* const c = g.values.data() +
                         (static_cast<std::size_t>(i.z) * n + static_cast<std::size_t>(i.y)) * n +
                         static_cast<std::size_t>(i.x);
  const auto at = [c, n](std::size_t dx, std::size_t dy, std::size_t dz) {
    return c[(dz * n + dy) * n + dx];
  };
  const auto lerp = [](float a, float b, float s) { return a + s * (b - a); };
  const float y0 =
      lerp(lerp(at(0, 0, 0), at(1, 0, 0), t.x), lerp(at(0, 1, 0), at(1, 1, 0), t.x), t.y);
  const float y1 =
      lerp(lerp(at(0, 0, 1), at(1, 0, 1), t.x), lerp(at(0, 1, 1), at(1, 1, 1), t.x), t.y);
  return lerp(y0, y1, t.z);
}

struct Primitive {
  std::string name;  // e.g. "l_forearm" (unique within the set)
  PrimitiveRole role = PrimitiveRole::kLimb;
  int bone = 0;         // joint whose skinning transform carries it
  Shape shape;          // bind-pose model space, prepared
  float r_in = 0.05f;   // best-fit skeleton distance of its vertices (its
                        // surface); metres, or a profile ratio for cone-spheres
  float r_out = 0.08f;  // the bound: no field at skeleton distance >= r_out
  float weight = 1.0f;  // shape weight W = iso / f(r_in / r_out)
  Density density;
  float stiffness = 3.0e4f;  // Pa per metre of depth; kRigidStiffness = rigid
  Elasticity elasticity = Elasticity::kElastic;
  float time_constant = 0.5f;  // viscoelastic recovery time, seconds (> 0)
  bool collides = true;        // takes part in collisions (bone primitives do not)
  SkinWeightGrid skin_weight;  // filled by calibration (calibrateModel)
};

struct PrimitiveSet {
  float iso = 0.5f;                    // T, 0 < T < 1
  int diff_exponent = 4;               // n of DIFF(a, b) = |a^n - b^n|^(1/n), 1..8
  float propagation_amplitude = 0.3f;  // a: bulge height per unit of deepest penetration
  float propagation_width = 0.45f;     // delta: field width of the propagation zone
                                       // (0 < delta < iso, so it ends inside the support)
  std::vector<Primitive> items;        // (nprim)
};

// Adjacent limbs that blend through their joint primitive (DIFF at the joint vertices).
struct Blend {
  std::uint16_t limb_a = 0;
  std::uint16_t limb_b = 0;
  std::uint16_t joint = 0;
};

struct CombinationGraph {
  std::vector<Blend> blends;                                // one per joint primitive
  std::vector<std::array<std::uint16_t, 2>> collide_pairs;  // same-body pairs that collide,
                                                            // i < j, sorted, unique
  // Derived by finalizeGraph (not stored): nprim x nprim collision matrix.
  int primitive_count = 0;
  std::vector<std::uint8_t> collide_matrix;
  std::vector<std::uint8_t> neighbour_matrix;  // nprim x nprim: joined through a joint

  // Whether i and j are joined through a joint primitive: the two limbs of a blend, or a
  // joint and one of its limbs.
  bool neighbours(int i, int j) const {
    return neighbour_matrix[static_cast<std::size_t>(i) *
                                static_cast<std::size_t>(primitive_count) +
                            static_cast<std::size_t>(j)] != 0;
  }

  bool collides(int i, int j) const {
    return collide_matrix[static_cast<std::size_t>(i) * static_cast<std::size_t>(primitive_count) +
                          static_cast<std::size_t>(j)] != 0;
  }
};

// Sorts and dedupes collide_pairs and builds the matrix.
void finalizeGraph(CombinationGraph& graph, int primitive_count);

enum class VertexClass : std::uint8_t {
  kLimb = 0,   // D_v = F_p0 (+ bone)
  kJoint = 1,  // D_v = F_p0 (the joint) + DIFF(F_p1, F_p2) (+ bone); p1 its own side's limb
  kFree = 2,   // carried by a bone without a primitive (fingers...): a planar own field of
               // slope `slope` through its rigid position; p0 is the owner for collisions
};

// A same-body primitive that vertex v treats specially: its iso-value for the pair is
// raised to what the rest posture already has (rest contacts: armpit, crotch, the
// joint's own limbs), and kPairAlways makes it a collision candidate in every frame (the
// opposite limb of a joint vertex) whether or not Step 1 lists it.
inline constexpr std::uint8_t kPairAlways = 1;
struct VertexPair {
  std::int16_t prim = kNoPrimitive;
  std::uint8_t flags = 0;
  float iso = 0.5f;  // the pair's threshold (>= the set's iso)
};

// Calibration::rigid values.
inline constexpr std::uint8_t kRigidLimb = 1;
inline constexpr std::uint8_t kRigidInner = 2;      // a free vertex with no primitive and no pair:
                                                    // carried by its skinning alone, never
                                                    // deformed, never in contact
inline constexpr std::uint8_t kRigidUntouched = 3;  // a limb vertex of a primitive of its own
                                                    // (adoptFreeVertices: fingers, toes...):
                                                    // its field serves contact; untouched,
                                                    // it keeps its skinned position

struct Calibration {
  std::vector<VertexClass> vertex_class;           // (nvert)
  std::vector<std::array<std::int16_t, 4>> prims;  // (nvert) p0, p1, p2, bone; unused = -1
  std::vector<float> w;                            // (nvert) calibration weight w_v
  std::vector<float> slope;                        // (nvert) free vertices: own-field
                                                   // slope per metre (> 0); else 0
  std::vector<std::uint8_t> rigid;                 // (nvert) kRigidLimb: a limb vertex
                                                   // skinned entirely by its primitive's
                                                   // bone, so D_v cannot change while
                                                   // untouched; kRigidInner: an inner
                                                   // layer (inner_layers.hpp);
                                                   // kRigidUntouched: see there; else 0
  std::vector<float> own_weight;                   // (nvert, or empty: all 1) the share of
                                                   // the vertex's skin weight carried by
                                                   // its own primitives' bones (see
                                                   // DeformOptions::own_fade_low)
  std::vector<std::uint32_t> pair_offsets;         // (nvert + 1) into pairs
  std::vector<VertexPair> pairs;                   // rest-contact / always pairs
  std::vector<std::uint32_t> ring_offsets;         // (nvert + 1) into ring
  std::vector<std::uint32_t> ring;                 // one-ring neighbours
  std::vector<float> ring_weights;                 // rest barycentric weights (sum 1)

  int vertexCount() const { return static_cast<int>(vertex_class.size()); }
};

struct ImplicitModel {
  PrimitiveSet primitives;
  CombinationGraph graph;
  Calibration calibration;
};

// Checks ranges and sizes: iso in (0,1), exponents, every primitive (bone < joint_count,
// valid shape and density, 0 < r_in < r_out, finite positive weight, stiffness > 0,
// time constant > 0), graph indices and roles, and calibration arrays of vertex_count
// entries with in-range indices and finite weights. The message names the element.
Status validatePrimitiveSet(const PrimitiveSet& set, int joint_count);
Status validateCombinationGraph(const CombinationGraph& graph, const PrimitiveSet& set);
Status validateCalibration(const Calibration& calibration, const PrimitiveSet& set,
                           int vertex_count);
Status validateImplicitModel(const ImplicitModel& model, int joint_count, int vertex_count);

// The body part a primitive belongs to: its name up to the first '/' (the primitives
// adoptFreeVertices adds for fingers, toes, the upper chest... are named "<part>/<joint>",
// e.g. "l_hand/index_01_l"), else the whole name. Views into `name`.
std::string_view primitivePart(std::string_view name);

// Shape weight W so that the field equals iso on the offset surface at r_in.
float shapeWeight(const Density& density, float iso, float r_in, float r_out);

}  // namespace vistel
