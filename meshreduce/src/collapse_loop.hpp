// meso's edge-collapse loop on OpenMesh's collapse primitives.
//
// Why not OpenMesh's DecimaterT: its heap holds one entry per vertex and, after every
// collapse, re-evaluates every outgoing halfedge of every vertex of the old one-ring with
// every module (about 40 full legality and priority evaluations per collapse), and it
// cannot move the kept vertex (ModQuadric places it on an endpoint). Here:
//  - the heap holds edges (an indexed 4-ary heap: key + edge per slot, one position per
//    edge; no stale entries, no allocation after setup);
//  - an edge's key is its quadric cost at its placement (cheap: a 10-double sum and two
//    regularised 3x3 solves by cofactors, quadric.hpp); the legality tests (topology, then the modules) run only
//    on the edge about to be collapsed; a refused edge leaves the heap and comes back when a
//    collapse changes its neighbourhood (an endpoint adjacent to the new vertex);
//  - after a collapse only the edges around the new vertex get new keys (no other quadric
//    changed).
// Positions live in a double array in coordinates normalised to the unit box (centre and a
// power-of-two scale, so unmoved points round-trip exactly); quadrics are per vertex,
// area-weighted, plus boundary/seam constraint planes.
#pragma once

#include "meso/core/mesh.hpp"
#include "meso/core/progress.hpp"
#include "meso/meshreduce/progressive.hpp"

#include "quadric.hpp"

#include <cstdint>
#include <memory>
#include <string>
#include <vector>

namespace meso::reduce {

using Vec2f = OpenMesh::Vec2f;

// Where the kept vertex goes.
enum class Placement : uint8_t {
  optimal,  // both endpoints inside a chart: the quadric's minimiser (with fallbacks)
  onto,     // v0 inside a chart, v1 on a seam/boundary: v1 stays where it is
  slide,    // a seam/boundary edge: the kept vertex moves along the edge (t in [0, 1])
};

// A face that survives the collapse and has v0 or v1 as a corner ("the moving corner").
struct FanFace {
  FaceHandle f;
  HalfedgeHandle corner;  // the halfedge into the moving corner in f, before the collapse
  Vec3d old_p, b, c;      // the moving corner before, then the other two corners (winding order)
  Vec2f old_uv, uv_b, uv_c, new_uv;
  bool adjacent_fl = false, adjacent_fr = false;  // shares an edge with fl / fr
  bool from_v0 = false;  // the moving corner is v0 (else v1)
  uint8_t side = 0;      // slides: on fl's side of the seam (0) or fr's (1)
};

// The collapse of halfedge h: v0 = from(h) disappears, v1 = to(h) is kept and moves to q.
struct Candidate {
  Mesh::EdgeHandle e;
  HalfedgeHandle h;
  VertexHandle v0, v1;
  FaceHandle fl, fr;       // the faces of h and of its opposite (either may be invalid)
  Placement placement = Placement::optimal;
  double t = 1;            // slide: q = p0 + t (p1 - p0)
  Vec3d p0, p1, q;
  double cost = 0;
  // Slides: v0's and v1's other seam/boundary neighbours (invalid if v1 is a corner), and
  // their UVs on the side of fl (0) and fr (1).
  VertexHandle other0, other1;
  Vec2f uv0[2], uv1[2], uv_other0[2], uv_other1[2];
  bool side_valid[2] = {false, false};
  const std::vector<FanFace>* fan = nullptr;  // faces around v0 and v1 but fl and fr
};

// Boundary halfedges carry no corner, and their UVs are whatever the input held (OpenMesh
// leaves them uninitialised), but OpenMesh's OBJ writer lists every halfedge's UV: one fixed
// value makes equal meshes write equal files (reduce_mesh and progressive_level both call it).
inline void clear_boundary_uvs(Mesh& mesh) {
  if (!mesh.has_halfedge_texcoords2D()) return;
  for (auto h : mesh.halfedges())
    if (mesh.is_boundary(h)) mesh.set_texcoord2D(h, Vec2f(0, 0));
}

class CollapseLoop;

// A constraint on collapses (the counterpart of an OpenMesh Decimater binary module): asked
// about each collapse about to be made, told about each one made.
class CollapseModule {
 public:
  virtual ~CollapseModule() = default;
  virtual const char* name() const = 0;
  // Called once, after the loop has set up positions, quadrics and features.
  virtual void initialize(CollapseLoop&) {}
  // Whether the collapse keeps the module's guarantee.
  virtual bool allow(const Candidate& c) = 0;
  // The collapse is about to be made (every module allowed it); the mesh is still as before.
  virtual void commit(const Candidate&) {}
  size_t rejected = 0;
};

struct LoopOptions {
  size_t target_faces = 0;
  bool has_uvs = false;
  double boundary_weight = 100.0;  // ReduceOptions::boundary_weight
  double seam_weight = 100.0;      // ReduceOptions::seam_weight
  // Lazy keys (ReduceQuality::fast): after a collapse, the edges around the kept vertex that
  // are queued keep their old keys instead of being re-evaluated. Every pop is re-evaluated
  // anyway (run()): a key that rose goes back into the heap, one that fell is collapsed at
  // once. Collapsing only merges quadrics and moves a vertex towards their minimum, so a key
  // mostly rises, and many queued edges around a vertex are not popped before another
  // collapse next to them changes them again: this skips the eager re-evaluations (about
  // seven of the eleven per collapse), of which the re-pops give some back (on the bricks
  // 13 % fewer instructions in all), at the price of edges whose key fell waiting their turn.
  bool lazy = false;
  // Face planes weighted by the mean face area instead of each face's own area (ReduceQuality::best).
  bool uniform_planes = false;
  // The progress bar's label: "meshreduce", or "meshreduce, pass N" when a reduction that
  // left flipped faces runs again (meshreduce.cpp).
  std::string label = "meshreduce";
};

class CollapseLoop {
 public:
  // `mesh` must be garbage-collected, with status attributes. Positions are normalised here.
  CollapseLoop(Mesh& mesh, const LoopOptions& options);

  void add(std::unique_ptr<CollapseModule> module) { modules_.push_back(std::move(module)); }

  // Runs until the face target is met or no legal collapse remains; returns the collapses made.
  size_t run(Progress& progress);

  // Writes moved positions back to the mesh (object units). Unmoved vertices keep their
  // input coordinates bit for bit.
  void write_back();

  // Appends every collapse made to `pm` (progressive.hpp): the halfedge, then the kept
  // vertex's position as write_back() would leave it and the UVs of its corners, so that a
  // replay stopped after any collapse equals this loop stopped there.
  void record(ProgressiveMesh* pm) { record_ = pm; }

  // Locks: a pinned vertex is never removed and never moves. Placement collapses a free
  // vertex onto a pinned one (as onto a seam corner); an edge whose ends are both pinned is
  // still evaluated so that the lock module that pinned them refuses it (and counts it).
  // Called by modules in initialize(), before the heap is built.
  void pin(VertexHandle v) { pinned_[static_cast<size_t>(v.idx())] = 1; }
  bool pinned(VertexHandle v) const { return pinned_[static_cast<size_t>(v.idx())] != 0; }

  // Read access for modules.
  const Mesh& mesh() const { return mesh_; }
  const Vec3d& pos(VertexHandle v) const { return pos_[static_cast<size_t>(v.idx())]; }
  bool is_feature(Mesh::EdgeHandle e) const { return efeat_[static_cast<size_t>(e.idx())] != 0; }
  double scale() const { return scale_; }  // object units -> normalised units
  size_t faces() const { return faces_; }
  double max_cost() const { return max_cost_; }
  const std::vector<std::unique_ptr<CollapseModule>>& modules() const { return modules_; }

 private:
  struct Slot {
    float key;
    int edge;
  };

  bool evaluate(Mesh::EdgeHandle e, Candidate& c);
  bool collapse_ok(HalfedgeHandle h);
  void gather_fan(Candidate& c);
  void walk(Candidate& c, VertexHandle v, HalfedgeHandle start, int start_side, bool from_v0);
  Vec2f reproject_uv(const Candidate& c) const;
  bool folds(const Vec2f& uv) const;  // whether giving every fan face this UV folds one
  void apply(const Candidate& c);
  void update_features_around(VertexHandle w);
  uint16_t feature_degree(VertexHandle v) const;
  bool seam(Mesh::EdgeHandle e) const;
  Vec3f object_point(VertexHandle v) const;  // what write_back() gives v now

  // Indexed 4-ary heap on (key, edge): half the depth of a binary heap, the four children of
  // a slot in 32 contiguous bytes. Its instruction count is that of the binary heap's
  // (callgrind); a wall-clock gain was not measured apart. (key, edge) is a strict total
  // order, so the pop order, and with it the reduction, does not depend on the heap's shape.
  static constexpr size_t kHeapArity = 4;
  bool less(const Slot& a, const Slot& b) const { return a.key < b.key || (a.key == b.key && a.edge < b.edge); }
  void heap_set(int edge, float key);
  void heap_remove(int edge);
  void sift_up(size_t i);
  void sift_down(size_t i);
  void place(size_t i, const Slot& s) {
    heap_[i] = s;
    hpos_[static_cast<size_t>(s.edge)] = static_cast<int>(i);
  }
  void push_edge(Mesh::EdgeHandle e);

  Mesh& mesh_;
  LoopOptions options_;
  Vec3d center_{0, 0, 0};
  double scale_ = 1;
  std::vector<Vec3d> pos_;
  std::vector<Quadric> quadric_;
  std::vector<uint8_t> efeat_, moved_, pinned_;
  std::vector<uint16_t> vdeg_;  // feature edges per vertex
  std::vector<Slot> heap_;
  std::vector<int> hpos_;
  std::vector<FanFace> fan_;
  std::vector<int> around_;  // edges around the collapsing edge's ends
  std::vector<uint32_t> ring_mark_;  // collapse_ok: stamp of v1's one-ring
  uint32_t ring_stamp_ = 0;
  std::vector<std::unique_ptr<CollapseModule>> modules_;
  size_t faces_ = 0;
  double max_cost_ = 0;
  ProgressiveMesh* record_ = nullptr;
};

}  // namespace meso::reduce
