// A parent part's rim shared by several blend regions: where the bands cut at two joints
// touch (the neck and the shoulders on a slim torso, the two hips at the crotch), the
// parent keeps one rim around several children. It is split into one closed rim per
// child so that each region is again an annulus (seam_loft.hpp):
//
// 1. Each rim vertex is labelled with the child whose rim lies nearest; runs shorter than
//    three vertices take their predecessor's label.
// 2. A child whose label forms one run is clipped off: its piece is the run closed by a
//    chord from the run's end back to its start, across the region between this child
//    and the child of the next run; the shared rim goes on with the chord in its place
//    (run the other way), relabelled as the previous run. Repeated until one label is left
//    (a pair of pants cut into two annuli along an arc, then again).
// 3. Chord vertices lie midway between the two children's surfaces, pulled onto their
//    blended field (part_field.hpp) by Newton steps.
//
// Every chord edge is used once by each of the two pieces it separates, in opposite
// directions, so the lofted regions still make a closed 2-manifold. Space: model space,
// metres. Cost: O(rim x children's rims) plus O(chord vertices) field queries.
#pragma once

#include <cstdint>
#include <span>
#include <vector>

#include "offline/synthesize/part_field.hpp"
#include "offline/synthesize/seam_loft.hpp"

namespace vistel {

struct ChordVertex {
  glm::vec3 position{0.0f};
  glm::vec3 normal{0.0f};
  std::uint32_t from = 0, to = 0;  // output indices of the chord's ends
  float t = 0.0f;                  // along the chord from `from` to `to`
};

struct SharedRimSplit {
  std::vector<RimCurve> pieces;     // per child (given order), in the parent rim's sense;
                                    // empty when the child got no run
  std::vector<ChordVertex> chords;  // new vertices, numbered from first_new_vertex
};

// `rim` in the parent's sense; `children` the children's rims (their own sense) and
// `child_fields` their parts' fields, same order; new chord vertices numbered from
// `first_new_vertex`, about `spacing` apart.
SharedRimSplit splitSharedRim(const RimCurve& rim, std::span<const RimCurve* const> children,
                              std::span<const PartField* const> child_fields,
                              std::uint32_t first_new_vertex, float spacing);

}  // namespace vistel
