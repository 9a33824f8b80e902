// Internal to common/deform (not a public header). Step 3 of the deformable component
// (DESIGN.md §3 "reaction forces", Gascuel 1993): normals of the deformed skin (area-weighted
// over the faces around each vertex that moved, the rigid normals elsewhere), then per partner
// body the contact area (faces whose three vertices lie on that partner's contact surface),
// its centre and the reaction force by the contact law shared with the ball dynamics
// (prop.hpp "The contact law"): each contact vertex's pressure k delta + the cores', delta its
// rigid-pose depth below the partner's skin on the partner primitive's ray (DeformState::
// pressure gets it), integrated linearly over every face around the contact (zero at a vertex
// not in contact with that partner) with the face's skinned area, along the deformed face's
// normal: force = -sum p_mean x skinned area x n. combineContacts and netContactForce
// (deform.hpp) pair the bodies' measures.
// Space: world; metres, m^2, Pa, N. Cost: normals O(faces with a moved vertex + nvert),
// contacts O(contact vertices x (their faces + their candidates)); no allocation once
// BodyContact's list holds the scene's partners.
#pragma once

#include "common/deform/deform_scratch.hpp"
#include "common/deform/task_pool.hpp"

namespace vistel {

// Step 3a: DeformState::normals (parallel over faces, then vertices).
void skinNormals(DeformFrame& fr, TaskPool* pool);

// Step 3b: DeformState::contacts from the chunks' contact lists (serial, fixed order).
void passContacts(DeformFrame& fr);

}  // namespace vistel
