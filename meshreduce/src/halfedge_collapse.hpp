// The halfedge collapse of meshreduce and of the progressive-mesh replay: the connectivity
// change of OpenMesh's PolyConnectivity::collapse, made with the kernel's inline accessors.
//
// Why not OpenMesh's own: Debian builds libOpenMeshCore with assertions on, and every
// status or property lookup inside the library compares two std::string type names (an
// allocation and a free each); with its out-of-line adjust_outgoing_halfedge and
// is_valid_handle calls, mesh.collapse() was 28 % of all the instructions of a reduction
// (callgrind, docs/benchmarks.md). Compiled in meso's translation units the same accessors
// are a load or two.
//
// The result is the same halfedge structure, element for element, as OpenMesh's collapse
// (the same next/prev links, the same outgoing halfedge per vertex, the same halfedge per
// face, the same deleted flags), so outputs, circulator orders and progressive records do
// not change: the meshreduce tests compare both on every collapse of a reduction.
#pragma once

#include "meso/core/mesh.hpp"

#include <array>

namespace meso::reduce {

// Collapses halfedge h: its from-vertex is removed, its to-vertex kept (positions are not
// touched). The caller must have checked the collapse is legal (the link condition;
// CollapseLoop::collapse_ok or OpenMesh's is_collapse_ok). The mesh must have the status
// attributes of meso::Mesh (vertices, halfedges, edges, faces) and prev halfedges.
class HalfedgeCollapser {
 public:
  explicit HalfedgeCollapser(Mesh& mesh) : m_(mesh) {}

  void collapse(HalfedgeHandle h0) {
    const HalfedgeHandle h1 = m_.next_halfedge_handle(h0);
    const HalfedgeHandle o0 = m_.opposite_halfedge_handle(h0);
    const HalfedgeHandle o1 = m_.next_halfedge_handle(o0);
    collapse_edge(h0);
    // A face left with two edges (a loop) goes; its two edges become one.
    if (m_.next_halfedge_handle(m_.next_halfedge_handle(h1)) == h1) collapse_loop(m_.next_halfedge_handle(h1));
    if (m_.next_halfedge_handle(m_.next_halfedge_handle(o1)) == o1) collapse_loop(o1);
  }

 private:
  // The edge of h goes: every halfedge into its from-vertex vo now points to its to-vertex
  // vh, and the two faces at the edge lose one side (they become loops, removed next).
  void collapse_edge(HalfedgeHandle h) {
    const HalfedgeHandle hn = m_.next_halfedge_handle(h), hp = m_.prev_halfedge_handle(h);
    const HalfedgeHandle o = m_.opposite_halfedge_handle(h);
    const HalfedgeHandle on = m_.next_halfedge_handle(o), op = m_.prev_halfedge_handle(o);
    const FaceHandle fh = m_.face_handle(h), fo = m_.face_handle(o);
    const VertexHandle vh = m_.to_vertex_handle(h), vo = m_.to_vertex_handle(o);

    // Incoming halfedges of vo, clockwise from its outgoing halfedge's opposite (the order
    // does not matter: each is redirected once).
    const HalfedgeHandle start = m_.halfedge_handle(vo);
    if (start.is_valid()) {
      HalfedgeHandle out = start;
      do {
        const HalfedgeHandle in = m_.opposite_halfedge_handle(out);
        out = m_.next_halfedge_handle(in);
        m_.set_vertex_handle(in, vh);
      } while (out != start);
    }

    m_.set_next_halfedge_handle(hp, hn);
    m_.set_next_halfedge_handle(op, on);
    if (fh.is_valid()) m_.set_halfedge_handle(fh, hn);
    if (fo.is_valid()) m_.set_halfedge_handle(fo, on);

    if (m_.halfedge_handle(vh) == o) m_.set_halfedge_handle(vh, hn);
    adjust_outgoing_halfedge(vh);
    m_.set_halfedge_handle(vo, HalfedgeHandle());  // isolated

    m_.status(m_.edge_handle(h)).set_deleted(true);
    m_.status(vo).set_deleted(true);
    m_.status(h).set_deleted(true);
    m_.status(o).set_deleted(true);
  }

  // h0 and next(h0) form a face with two sides (or h0's face is the boundary): h0's edge
  // goes and next(h0) takes its place in the face across h0.
  void collapse_loop(HalfedgeHandle h0) {
    const HalfedgeHandle h1 = m_.next_halfedge_handle(h0);
    const HalfedgeHandle o0 = m_.opposite_halfedge_handle(h0), o1 = m_.opposite_halfedge_handle(h1);
    const VertexHandle v0 = m_.to_vertex_handle(h0), v1 = m_.to_vertex_handle(h1);
    const FaceHandle fh = m_.face_handle(h0), fo = m_.face_handle(o0);

    m_.set_next_halfedge_handle(h1, m_.next_halfedge_handle(o0));
    m_.set_next_halfedge_handle(m_.prev_halfedge_handle(o0), h1);
    m_.set_face_handle(h1, fo);

    m_.set_halfedge_handle(v0, h1);
    adjust_outgoing_halfedge(v0);
    m_.set_halfedge_handle(v1, o1);
    adjust_outgoing_halfedge(v1);

    if (fo.is_valid() && m_.halfedge_handle(fo) == o0) m_.set_halfedge_handle(fo, h1);

    if (fh.is_valid()) {
      m_.set_halfedge_handle(fh, HalfedgeHandle());
      m_.status(fh).set_deleted(true);
    }
    m_.status(m_.edge_handle(h0)).set_deleted(true);
    m_.status(h0).set_deleted(true);
    m_.status(o0).set_deleted(true);
  }

  // A boundary vertex's outgoing halfedge must be a boundary one (OpenMesh's invariant, which
  // its is_boundary(v) and circulators rely on): the first one met clockwise, as OpenMesh's
  // adjust_outgoing_halfedge picks it.
  void adjust_outgoing_halfedge(VertexHandle v) {
    const HalfedgeHandle start = m_.halfedge_handle(v);
    if (!start.is_valid()) return;
    HalfedgeHandle out = start;
    do {
      if (m_.is_boundary(out)) {
        m_.set_halfedge_handle(v, out);
        return;
      }
      out = m_.next_halfedge_handle(m_.opposite_halfedge_handle(out));
    } while (out != start);
  }

  Mesh& m_;
};

// Removes deleted elements, as mesh.garbage_collection() does, with the same result (the
// same swaps of the last live element into each hole). The work is OpenMesh's own template
// (ArrayKernelT_impl.hh), instantiated here for handle lists that are empty by type, so that
// it compiles in this translation unit: the library's instantiation of the plain call looks
// up the status property with type-name string comparisons (Debian's assertions) for every
// element, 6-8 % of a reduction's instructions.
inline void compact(Mesh& mesh) {
  std::array<VertexHandle*, 0> vertices;
  std::array<HalfedgeHandle*, 0> halfedges;
  std::array<FaceHandle*, 0> faces;
  static_cast<OpenMesh::ArrayKernel&>(mesh).garbage_collection(vertices, halfedges, faces);
}

}  // namespace meso::reduce
