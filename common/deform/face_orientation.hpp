// Internal to common/deform (not a public header). The last guard of Step 2: no face of the
// deformed skin is turned inside out against the skinned skin (the rigid positions) unless it
// lies in a contact. The field's surface, the relaxation and the smoothing each move vertices
// by millimetres to centimetres; in a tight crease (a bent knee, the hip) a small face between
// vertices moved by different amounts can flip, which shading shows as a dark speck and which
// is a fold the skinning did not have. The guard pulls the corrections c = P' - P of such a
// face's vertices back towards the skinned positions (halving them, a few rounds), and where
// that does not turn the face back, returns them to the skinned positions, where no face is
// inverted. Faces with a vertex in contact (on a contact surface, or penetrating in the rigid
// pose) are left alone: two skins that meet fold onto one another by design.
// Space: world, metres. Cost: O(nvert) flag tests plus the faces around moved vertices; serial
// and in vertex order, so the result does not depend on threads; no allocation.
#pragma once

#include "common/deform/deform_scratch.hpp"

namespace vistel {

// Restores the orientation of inverted faces (see above), marking the rings of the vertices
// it moves for new normals. Returns how many vertices it pulled back.
int restoreFaceOrientation(DeformFrame& fr);

}  // namespace vistel
