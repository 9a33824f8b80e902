// The topology of a triangle mesh, counted: is it closed, is it a 2-manifold, do its
// triangles agree on orientation, how many pieces is it in. Judges a mesh by index, so
// weld a mesh split at texture seams first (triangle_soup.hpp weldVertices).
#pragma once

#include "offline/compare/triangle_soup.hpp"

namespace vistel {

struct MeshTopology {
  int vertices = 0;  // used by at least one triangle
  int triangles = 0;
  int boundary_edges = 0;        // used by one triangle: a hole's rim
  int nonmanifold_edges = 0;     // used by three or more triangles
  int misoriented_edges = 0;     // used by two triangles in the same direction
  int nonmanifold_vertices = 0;  // whose triangles form two or more fans (touching cones)
  int degenerate_triangles = 0;  // of zero area
  int components = 0;            // pieces connected through edges

  bool closed() const { return boundary_edges == 0 && nonmanifold_edges == 0; }
  bool manifold() const { return nonmanifold_edges == 0 && nonmanifold_vertices == 0; }
  bool oriented() const { return misoriented_edges == 0; }
};

// Counts the above for a valid soup (validateSoup). Cost: O(triangles) expected time and
// memory (a hash map of edges, the triangles around each vertex).
MeshTopology analyzeTopology(const TriangleSoup& soup);

}  // namespace vistel
