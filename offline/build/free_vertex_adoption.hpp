// Free vertices given a field of their own (issue 25 item 4), at model build time: the
// skin's free vertices (no primitive defines them) grouped by the joint carrying most of
// their weight, each group made a limb primitive of its own.
#pragma once

#include "common/anim/skeleton.hpp"
#include "common/anim/skin_mesh.hpp"
#include "common/base/result.hpp"
#include "common/deform/calibrate.hpp"
#include "common/deform/implicit_model.hpp"

namespace vistel {

// Free vertices given a field of their own (issue 25 item 4): fingers, toes, the upper
// chest, the collarbones, a crown beyond the head's support. Each free vertex goes with the
// joint that carries most of its skin weight, and the joint's free vertices (at least
// min_vertices of them) become the limb vertices of a primitive of their own carried by that
// joint (a phalanx, a toe, the upper chest, a cap over the crown): a capsule on their
// principal segment (a sphere for a compact group), r_in their mean skeleton distance, r_out
// past the farthest of them, material from the primitive that owned them for collisions.
// Within the body a new primitive collides with what its former owner collides with, except
// the owner, the owner's neighbours across a joint primitive (the owner meets those through
// the joint's blend) and the other new primitives (a finger does not collide with its hand,
// its forearm or any finger); and there its vertices take the partner's whole contact, as
// they did free (DeformScratch::adopted): self-contact costs what it did. Other bodies meet it
// as any primitive, by relative deformability (its vertices without a bulge). A former owner
// carried by the same joint keeps fitting its skin weights to the vertices it fitted before (so its
// skin does not move). Skeletons without finger or toe bones get no such primitives (their vertices
// are then on the hand's and foot's bones, and not free). Inner layers (inner_layers.hpp) are left
// alone. The builder runs it after calibration (BuildOptions::adopt_free_vertices).
struct AdoptionOptions {
  int min_vertices = 4;            // free vertices a joint needs for a primitive of its own
  float max_surface_ratio = 0.7f;  // r_in / r_out at most this
  float reach = 1.25f;             // r_out at least this times the farthest vertex's distance
};

struct AdoptionReport {
  int primitives = 0;             // primitives added
  int adopted = 0;                // free vertices given a new primitive
  CalibrationReport calibration;  // the model's calibration afterwards
};

// Adopts the free vertices of a calibrated model (calibrateModel run, the graph finalized)
// of `skin` on `skeleton` (the skin the model was calibrated on: same vertex count, joints in
// range), then recalibrates it (as calibrateModel with `calibration`) and keeps the ring
// arrays. Nothing to adopt: the model is left as it was (the report's calibration then
// counts the classes only), so a second call changes nothing.
// Primitives are named "<former owner>/<joint>" (e.g. "l_hand/index_01_l", "torso/spine_03";
// the joint's name alone when the vertices had no owner; suffixed with '+' where taken), so
// that primitivePart groups them with their body part. For the adopted vertices,
// Calibration::own_weight is the share of their skin weight on their primitive's bone, and
// Calibration::rigid is kRigidLimb where that is all of it, else kRigidUntouched: untouched,
// an adopted vertex keeps its skinned position, as it did free (its field is for contact;
// solving every adopted vertex every frame cost bench_deform's Steps 1-3 about a tenth more).
// Fails on mismatched sizes or when the set would exceed kMaxPrimitives.
// Cost: offline; one more calibration.
Result<AdoptionReport> adoptFreeVertices(ImplicitModel& model, const Skeleton& skeleton,
                                         const SkinMesh& skin, const AdoptionOptions& options = {},
                                         const FieldCalibrationOptions& calibration = {});

}  // namespace vistel
