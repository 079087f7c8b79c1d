// Progressive meshes (Hoppe 1996): the input mesh and the ordered collapses reduce_mesh made,
// so that every level of detail between input and output can be rebuilt.
//
// The record is the input itself (positions, faces with their corner order, per-corner UVs,
// face groups) plus, per collapse, the halfedge collapsed and the exact float values the
// reduction wrote: the kept vertex's new position and the UVs of its corners. Replaying the
// first k collapses with OpenMesh's collapse() on the same halfedge structure and compacting
// as reduce_mesh does gives, bit for bit, what reduce_mesh returns when it stops after k
// collapses, i.e. reduce_mesh with target_faces = the level's face count. (Hoppe's vertex
// splits would refine from the base mesh instead; replaying collapses from the input needs no
// inverse topology and reuses the reducer's own primitive, which is what makes the levels
// exact.) The file format (.pm) is documented in docs/formats.md.
#pragma once

#include "meso/core/mesh.hpp"

#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <string>
#include <vector>

namespace meso {

struct ProgressiveMesh {
  // The input, as reduce_mesh saw it (deleted elements dropped).
  std::vector<Vec3f> positions;
  std::vector<uint32_t> corners;  // 3 per face: the vertices in the face's corner order
  bool has_uvs = false;
  std::vector<Vec2f> corner_uvs;  // with UVs: 3 per face, in the same order
  std::vector<uint32_t> face_groups;
  std::vector<std::string> group_names;

  // Collapse i: halfedge h goes, its to-vertex w is kept. Afterwards w is at `position`,
  // and (with UVs) its corners take the next uvs, one per face around w in the order of
  // OpenMesh's incoming-halfedge circulator: uvs holds them for every collapse in turn.
  struct Collapse {
    uint32_t halfedge = 0;  // in the input's halfedge numbering (stable: no compaction before the end)
    Vec3f position{0, 0, 0};  // object units, as reduce_mesh writes it
  };
  std::vector<Collapse> collapses;
  std::vector<Vec2f> uvs;

  size_t input_faces() const { return corners.size() / 3; }
  // The face count after the last collapse (input_faces() when there is none); computed when
  // the record is made or read.
  size_t final_faces = 0;
  // Names the record in errors (the file it was read from); empty for one made in memory.
  std::string source;
};

// The input mesh of the record, with the halfedge structure the collapses refer to: vertices
// added in order, then faces in order with OpenMesh's add_face (its corner order kept).
// Throws InputError (source) when a face cannot be added (a corrupt record).
Mesh progressive_base_input(const ProgressiveMesh& pm);

// Level of detail: replays collapses while the mesh has more than target_faces faces (or
// until the record ends), then compacts and recomputes vertex normals as reduce_mesh does.
// The result is bit-identical to reduce_mesh(input, options with target_faces) for any
// target_faces at or above final_faces. `collapses` receives the number replayed. Throws
// InputError (source) on a record that does not replay (invalid halfedge, illegal collapse,
// wrong number of UVs).
Mesh progressive_level(const ProgressiveMesh& pm, size_t target_faces, size_t* collapses = nullptr);

// The .pm file: little-endian, checksummed (docs/formats.md). write_progressive throws
// InternalError when the file cannot be written; read_progressive throws InputError
// ("FILE: problem") for a missing, truncated or corrupt file. Same record, same bytes.
void write_progressive(const ProgressiveMesh& pm, const std::filesystem::path& path);
ProgressiveMesh read_progressive(const std::filesystem::path& path);

}  // namespace meso
