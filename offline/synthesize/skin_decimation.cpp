#include "offline/synthesize/skin_decimation.hpp"

#include <array>
#include <cmath>

#include <OpenMesh/Core/Mesh/TriMesh_ArrayKernelT.hh>
#include <OpenMesh/Core/System/omstream.hh>
#include <OpenMesh/Tools/Decimater/DecimaterT.hh>
#include <OpenMesh/Tools/Decimater/ModAspectRatioT.hh>
#include <OpenMesh/Tools/Decimater/ModHausdorffT.hh>
#include <OpenMesh/Tools/Decimater/ModNormalFlippingT.hh>
#include <OpenMesh/Tools/Decimater/ModQuadricT.hh>

#include "common/anim/seam_copies.hpp"
#include "offline/compare/triangle_tree.hpp"

namespace vistel {
namespace {

struct DecimationTraits : public OpenMesh::DefaultTraits {
  using Point = OpenMesh::Vec3d;
  using Normal = OpenMesh::Vec3d;
};
using DecimationMesh = OpenMesh::TriMesh_ArrayKernelT<DecimationTraits>;
using Decimater = OpenMesh::Decimater::DecimaterT<DecimationMesh>;

// ModHausdorffT's other side: a collapse is legal only when the faces it leaves around
// the remaining vertex lie within the tolerance of the input's surface, judged at the
// points of a barycentric grid on each (4 steps per edge, corners left out: they are
// input vertices).
template <class MeshT>
class ModSurfaceBoundT : public OpenMesh::Decimater::ModBaseT<MeshT> {
 public:
  DECIMATING_MODULE(ModSurfaceBoundT, MeshT, SurfaceBound);

  explicit ModSurfaceBoundT(MeshT& mesh) : Base(mesh, true) {}

  void setSurface(const TriangleTree* tree, double tolerance) {
    tree_ = tree;
    tolerance_ = tolerance;
  }

  float collapse_priority(const CollapseInfo& ci) override {
    constexpr int kSteps = 4;
    const Mesh& mesh = Base::mesh();
    for (const auto h : mesh.voh_range(ci.v0)) {
      const auto f = mesh.face_handle(h);
      if (!f.is_valid()) continue;
      const auto b = mesh.to_vertex_handle(h);
      const auto c = mesh.to_vertex_handle(mesh.next_halfedge_handle(h));
      if (b == ci.v1 || c == ci.v1) continue;  // collapsed away with the edge
      const auto& pb = mesh.point(b);
      const auto& pc = mesh.point(c);
      for (int i = 0; i <= kSteps; ++i) {
        for (int j = 0; i + j <= kSteps; ++j) {
          const int k = kSteps - i - j;
          if (i == kSteps || j == kSteps || k == kSteps) continue;
          const auto q = (ci.p1 * i + pb * j + pc * k) / double(kSteps);
          const glm::vec3 p(static_cast<float>(q[0]), static_cast<float>(q[1]),
                            static_cast<float>(q[2]));
          if (tree_->nearest(p).distance > tolerance_) return float(Base::ILLEGAL_COLLAPSE);
        }
      }
    }
    return float(Base::LEGAL_COLLAPSE);
  }

 private:
  const TriangleTree* tree_ = nullptr;
  double tolerance_ = 0.0;
};

}  // namespace

Result<DecimatedMesh> decimateMesh(std::span<const glm::vec3> positions,
                                   std::span<const std::uint32_t> indices,
                                   std::span<const std::uint8_t> removable,
                                   const DecimationOptions& options) {
  const std::size_t nv = positions.size();
  if (indices.size() % 3 != 0) return fail("{} indices: not whole triangles", indices.size());
  for (std::size_t i = 0; i < indices.size(); ++i) {
    if (indices[i] >= nv) return fail("index {} is {}, past {} vertices", i, indices[i], nv);
  }
  if (!removable.empty() && removable.size() != nv) {
    return fail("{} removable flags for {} vertices", removable.size(), nv);
  }
  if (!(options.max_error_m > 0.0f)) return fail("max error {} m: not > 0", options.max_error_m);
  const std::size_t nt = indices.size() / 3;

  // Vertices at exactly the same place (texture seams) are one: welded[v] is the group,
  // first_copy[g] its first vertex, copies[g] how many.
  const std::vector<std::uint32_t> first = firstCopies(positions);
  std::vector<std::uint32_t> welded(nv);
  std::vector<std::uint32_t> first_copy;
  std::vector<std::uint32_t> copies;
  for (std::size_t v = 0; v < nv; ++v) {
    if (first[v] == v) {
      welded[v] = static_cast<std::uint32_t>(first_copy.size());
      first_copy.push_back(static_cast<std::uint32_t>(v));
      copies.push_back(0);
    } else {
      welded[v] = welded[first[v]];
    }
    ++copies[welded[v]];
  }
  const std::size_t ng = first_copy.size();

  // The half-edge mesh: one vertex per group, the triangles in input order (a face's
  // handle index is its triangle when every triangle was taken).
  DecimationMesh mesh;
  mesh.request_vertex_status();
  mesh.request_edge_status();
  mesh.request_face_status();
  mesh.request_face_normals();
  std::vector<DecimationMesh::VertexHandle> vh(ng);
  for (std::size_t g = 0; g < ng; ++g) {
    const glm::vec3& p = positions[first_copy[g]];
    vh[g] = mesh.add_vertex(DecimationMesh::Point(p.x, p.y, p.z));
  }
  std::vector<int> face_of(nt, -1);  // input triangle -> face handle index, -1: not taken
  std::vector<char> hold(ng, 0);
  std::vector<std::uint32_t> unmanaged;
  const bool err_enabled = omerr().is_enabled();
  omerr().disable();  // add_face reports each complex edge it refuses
  for (std::size_t t = 0; t < nt; ++t) {
    const std::array<std::uint32_t, 3> g = {welded[indices[3 * t]], welded[indices[3 * t + 1]],
                                            welded[indices[3 * t + 2]]};
    DecimationMesh::FaceHandle fh;
    if (g[0] != g[1] && g[1] != g[2] && g[2] != g[0]) {
      fh = mesh.add_face(vh[g[0]], vh[g[1]], vh[g[2]]);
    }
    if (!fh.is_valid()) {
      unmanaged.push_back(static_cast<std::uint32_t>(t));
      continue;
    }
    face_of[t] = fh.idx();
  }
  if (err_enabled) omerr().enable();

  // Held: vertices that may not go, seam vertices, boundary vertices, and around each
  // triangle OpenMesh could not take, its corners and their neighbours (so that no
  // collapse can make an edge it shares).
  for (std::size_t v = 0; v < nv; ++v) {
    if (!removable.empty() && removable[v] == 0) hold[welded[v]] = 1;
  }
  for (std::size_t g = 0; g < ng; ++g) {
    if (copies[g] > 1 || mesh.is_boundary(vh[g]) || mesh.is_isolated(vh[g])) hold[g] = 1;
  }
  for (const std::uint32_t t : unmanaged) {
    for (int c = 0; c < 3; ++c) {
      const std::uint32_t g = welded[indices[3 * t + c]];
      hold[g] = 1;
      for (const DecimationMesh::VertexHandle n : mesh.vv_range(vh[g])) {
        hold[static_cast<std::size_t>(n.idx())] = 1;
      }
    }
  }
  for (std::size_t g = 0; g < ng; ++g) mesh.status(vh[g]).set_locked(hold[g] != 0);
  mesh.update_face_normals();

  // Collapses: quadric error first, within the Hausdorff bound both ways, no flips, no
  // slivers.
  TriangleSoup input;
  input.positions.assign(positions.begin(), positions.end());
  input.indices.assign(indices.begin(), indices.end());
  const TriangleTree tree(input);
  DecimatedMesh out;
  out.unmanaged_triangles = static_cast<int>(unmanaged.size());
  {
    Decimater decimater(mesh);
    OpenMesh::Decimater::ModQuadricT<DecimationMesh>::Handle quadric;
    OpenMesh::Decimater::ModHausdorffT<DecimationMesh>::Handle hausdorff;
    OpenMesh::Decimater::ModNormalFlippingT<DecimationMesh>::Handle flipping;
    OpenMesh::Decimater::ModAspectRatioT<DecimationMesh>::Handle aspect;
    ModSurfaceBoundT<DecimationMesh>::Handle bound;
    decimater.add(quadric);
    decimater.add(hausdorff);
    decimater.add(flipping);
    decimater.add(aspect);
    decimater.add(bound);
    decimater.module(quadric).unset_max_err();  // the priority; the bound is Hausdorff's
    decimater.module(hausdorff).set_tolerance(options.max_error_m);
    decimater.module(flipping).set_max_normal_deviation(options.max_normal_turn_deg);
    decimater.module(aspect).set_aspect_ratio(options.max_aspect_ratio);
    decimater.module(bound).setSurface(&tree, options.max_error_m);
    if (!decimater.initialize()) return fail("OpenMesh's decimater did not initialise");
    out.collapses = static_cast<int>(decimater.decimate());
  }

  // The surviving vertices: every copy of a group not collapsed away, in input order.
  std::vector<std::uint32_t> renumber(nv, UINT32_MAX);
  for (std::size_t v = 0; v < nv; ++v) {
    if (mesh.status(vh[welded[v]]).deleted()) continue;
    renumber[v] = static_cast<std::uint32_t>(out.kept.size());
    out.kept.push_back(static_cast<std::uint32_t>(v));
  }

  // The surviving triangles in input order; a corner still at one of the input
  // triangle's groups keeps its copy, a moved one takes its group's first copy, and the
  // corners start where the input's did when that corner is still there.
  for (std::size_t t = 0; t < nt; ++t) {
    std::array<std::uint32_t, 3> corner{};
    if (face_of[t] < 0) {
      for (int c = 0; c < 3; ++c) corner[c] = indices[3 * t + c];
    } else {
      const DecimationMesh::FaceHandle fh = mesh.face_handle(static_cast<unsigned>(face_of[t]));
      if (mesh.status(fh).deleted()) continue;
      int c = 0;
      for (const DecimationMesh::VertexHandle v : mesh.fv_range(fh)) {
        const auto g = static_cast<std::uint32_t>(v.idx());
        corner[c] = first_copy[g];
        for (int k = 0; k < 3; ++k) {
          if (welded[indices[3 * t + k]] == g) corner[c] = indices[3 * t + k];
        }
        ++c;
      }
      if (corner[1] == indices[3 * t])
        corner = {corner[1], corner[2], corner[0]};
      else if (corner[2] == indices[3 * t])
        corner = {corner[2], corner[0], corner[1]};
    }
    for (const std::uint32_t v : corner) out.indices.push_back(renumber[v]);
    out.origin.push_back(static_cast<std::uint32_t>(t));
  }
  return out;
}

}  // namespace vistel
