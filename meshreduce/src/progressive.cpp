#include "meso/meshreduce/progressive.hpp"

#include "meso/core/error.hpp"
#include "meso/core/input_file.hpp"
#include "meso/core/mesh_extent.hpp"

#include "collapse_loop.hpp"
#include "halfedge_collapse.hpp"

#include <OpenMesh/Core/System/omstream.hh>

#include <cmath>
#include <cstring>
#include <fstream>
#include <iterator>

namespace meso {

namespace {

// "\x89MESOPM\n": a high byte and a newline catch transfers that mangle binary files (as
// PNG's signature does).
constexpr unsigned char kMagic[8] = {0x89, 'M', 'E', 'S', 'O', 'P', 'M', '\n'};
constexpr uint32_t kVersion = 1;
constexpr uint32_t kFlagUvs = 1;
constexpr size_t kHeaderBytes = 72, kFooterBytes = 8;
// OpenMesh handles are ints and a triangle mesh has at most 6 halfedges per face.
constexpr uint64_t kMaxElements = (uint64_t{1} << 31) / 6;

// FNV-1a, 64 bits: detects any corruption a truncation check misses, cheaply (one pass).
uint64_t fnv1a(const unsigned char* p, size_t n) {
  uint64_t h = 0xcbf29ce484222325ull;
  for (size_t i = 0; i < n; ++i) {
    h ^= p[i];
    h *= 0x100000001b3ull;
  }
  return h;
}

// OpenMesh prints to its error stream when add_face refuses a face; a corrupt record is
// reported once, as an InputError.
class QuietOpenMesh {
 public:
  QuietOpenMesh() : was_(omerr().is_enabled()) { omerr().disable(); }
  ~QuietOpenMesh() {
    if (was_) omerr().enable();
  }
  QuietOpenMesh(const QuietOpenMesh&) = delete;
  QuietOpenMesh& operator=(const QuietOpenMesh&) = delete;

 private:
  bool was_;
};

std::string name_of(const ProgressiveMesh& pm) { return pm.source.empty() ? std::string("progressive mesh") : pm.source; }

// Little-endian encoding, byte by byte: the file is the same on every host.
class Out {
 public:
  void bytes(const void* p, size_t n) { buf_.append(static_cast<const char*>(p), n); }
  void u32(uint32_t v) {
    for (int i = 0; i < 4; ++i) buf_.push_back(static_cast<char>((v >> (8 * i)) & 0xff));
  }
  void u64(uint64_t v) {
    for (int i = 0; i < 8; ++i) buf_.push_back(static_cast<char>((v >> (8 * i)) & 0xff));
  }
  void f32(float f) {
    uint32_t v;
    std::memcpy(&v, &f, 4);
    u32(v);
  }
  std::string& buffer() { return buf_; }

 private:
  std::string buf_;
};

class In {
 public:
  In(const unsigned char* p, size_t n) : p_(p), n_(n) {}
  uint32_t u32() {
    uint32_t v = 0;
    for (int i = 0; i < 4; ++i) v |= static_cast<uint32_t>(p_[at_ + static_cast<size_t>(i)]) << (8 * i);
    at_ += 4;
    return v;
  }
  uint64_t u64() {
    uint64_t v = 0;
    for (int i = 0; i < 8; ++i) v |= static_cast<uint64_t>(p_[at_ + static_cast<size_t>(i)]) << (8 * i);
    at_ += 8;
    return v;
  }
  float f32() {
    const uint32_t v = u32();
    float f;
    std::memcpy(&f, &v, 4);
    return f;
  }
  std::string text(size_t n) {
    std::string s(reinterpret_cast<const char*>(p_ + at_), n);
    at_ += n;
    return s;
  }
  size_t at() const { return at_; }
  size_t left() const { return n_ - at_; }

 private:
  const unsigned char* p_;
  size_t n_;
  size_t at_ = 0;
};

}  // namespace

Mesh progressive_base_input(const ProgressiveMesh& pm) {
  const std::string name = name_of(pm);
  const size_t nv = pm.positions.size(), nf = pm.input_faces();
  if (pm.corners.size() != 3 * nf || pm.face_groups.size() != nf || (pm.has_uvs && pm.corner_uvs.size() != 3 * nf))
    throw InputError(name, "inconsistent array sizes");
  Mesh mesh;
  if (pm.has_uvs) mesh.request_halfedge_texcoords2D();
  mesh.reserve(nv, 3 * nf / 2 + 3, nf);
  for (const Vec3f& p : pm.positions) mesh.add_vertex(p);
  std::vector<int> groups(nf, 0);
  const QuietOpenMesh quiet;
  for (size_t f = 0; f < nf; ++f) {
    const uint32_t* c = &pm.corners[3 * f];
    if (c[0] >= nv || c[1] >= nv || c[2] >= nv || c[0] == c[1] || c[1] == c[2] || c[0] == c[2])
      throw InputError(name, "face " + std::to_string(f) + " has invalid corners");
    if (pm.face_groups[f] >= pm.group_names.size()) throw InputError(name, "face " + std::to_string(f) + " has an invalid group");
    groups[f] = static_cast<int>(pm.face_groups[f]);
    const FaceHandle fh = mesh.add_face(VertexHandle(static_cast<int>(c[0])), VertexHandle(static_cast<int>(c[1])),
                                        VertexHandle(static_cast<int>(c[2])));
    if (!fh.is_valid()) throw InputError(name, "face " + std::to_string(f) + " cannot be added (not manifold)");
    if (!pm.has_uvs) continue;
    // add_face makes the halfedge into the first corner the face's halfedge, so the corner
    // order is the stored one.
    const auto hs = face_halfedges(mesh, fh);
    for (size_t k = 0; k < 3; ++k) mesh.set_texcoord2D(hs[k], pm.corner_uvs[3 * f + k]);
  }
  set_face_groups(mesh, pm.group_names, groups);
  // As read_mesh checked the mesh the record was made from (an empty record, or positions
  // forged to +-3e38 with the checksum recomputed, had replayed into a mesh meso refuses).
  check_mesh_extent(mesh, name);
  return mesh;
}

Mesh progressive_level(const ProgressiveMesh& pm, size_t target_faces, size_t* collapses) {
  const std::string name = name_of(pm);
  Mesh mesh = progressive_base_input(pm);
  reduce::compact(mesh);  // as reduce_mesh (nothing is deleted)
  size_t faces = mesh.n_faces(), uv = 0, k = 0;
  for (; k < pm.collapses.size() && faces > target_faces; ++k) {
    const ProgressiveMesh::Collapse& c = pm.collapses[k];
    auto bad = [&](const std::string& what) { return InputError(name, "collapse " + std::to_string(k) + ": " + what); };
    if (c.halfedge >= mesh.n_halfedges()) throw bad("halfedge out of range");
    const HalfedgeHandle h(static_cast<int>(c.halfedge));
    // The reducer made only legal collapses; a record asking for another one is corrupt
    // (and collapse() would break the mesh).
    if (mesh.status(mesh.edge_handle(h)).deleted() || !mesh.is_collapse_ok(h)) throw bad("not a legal collapse");
    if (!std::isfinite(c.position[0]) || !std::isfinite(c.position[1]) || !std::isfinite(c.position[2]))
      throw bad("position is not finite");
    faces -= static_cast<size_t>(mesh.face_handle(h).is_valid()) +
             static_cast<size_t>(mesh.face_handle(mesh.opposite_halfedge_handle(h)).is_valid());
    const VertexHandle w = mesh.to_vertex_handle(h);
    reduce::HalfedgeCollapser(mesh).collapse(h);
    mesh.set_point(w, c.position);
    if (!pm.has_uvs) continue;
    // The corners of w in the circulator order the reducer recorded them in.
    for (auto in : mesh.vih_range(w)) {
      if (!mesh.face_handle(in).is_valid()) continue;
      if (uv >= pm.uvs.size()) throw bad("the record has too few UVs");
      mesh.set_texcoord2D(in, pm.uvs[uv++]);
    }
  }
  if (k == pm.collapses.size() && (faces != pm.final_faces || uv != pm.uvs.size()))
    throw InputError(name, "the collapses do not end at the recorded face and UV counts");
  reduce::compact(mesh);
  reduce::clear_boundary_uvs(mesh);
  check_mesh_extent(mesh, name);  // the recorded positions of the kept vertices too
  compute_angle_weighted_normals(mesh);
  if (collapses) *collapses = k;
  return mesh;
}

void write_progressive(const ProgressiveMesh& pm, const std::filesystem::path& path) {
  const size_t nf = pm.input_faces();
  Out o;
  std::string names;
  {
    Out n;
    for (const auto& g : pm.group_names) {
      n.u32(static_cast<uint32_t>(g.size()));
      n.bytes(g.data(), g.size());
    }
    names = std::move(n.buffer());
  }
  o.buffer().reserve(kHeaderBytes + names.size() + 12 * pm.positions.size() + (pm.has_uvs ? 40 : 16) * nf +
                     16 * pm.collapses.size() + 8 * pm.uvs.size() + kFooterBytes);
  o.bytes(kMagic, sizeof kMagic);
  o.u32(kVersion);
  o.u32(pm.has_uvs ? kFlagUvs : 0);
  o.u64(pm.positions.size());
  o.u64(nf);
  o.u64(pm.group_names.size());
  o.u64(names.size());
  o.u64(pm.collapses.size());
  o.u64(pm.has_uvs ? pm.uvs.size() : 0);
  o.u64(pm.final_faces);
  o.bytes(names.data(), names.size());
  for (const Vec3f& p : pm.positions)
    for (int i = 0; i < 3; ++i) o.f32(p[i]);
  for (const uint32_t c : pm.corners) o.u32(c);
  for (const uint32_t g : pm.face_groups) o.u32(g);
  if (pm.has_uvs)
    for (const Vec2f& uv : pm.corner_uvs) o.f32(uv[0]), o.f32(uv[1]);
  for (const auto& c : pm.collapses) {
    o.u32(c.halfedge);
    for (int i = 0; i < 3; ++i) o.f32(c.position[i]);
  }
  if (pm.has_uvs)
    for (const Vec2f& uv : pm.uvs) o.f32(uv[0]), o.f32(uv[1]);
  std::string& buf = o.buffer();
  o.u64(fnv1a(reinterpret_cast<const unsigned char*>(buf.data()), buf.size()));

  std::ofstream f(path, std::ios::binary | std::ios::trunc);
  f.write(buf.data(), static_cast<std::streamsize>(buf.size()));
  f.close();
  if (!f) throw InternalError(path.string() + ": cannot write the progressive mesh");
}

ProgressiveMesh read_progressive(const std::filesystem::path& path) {
  const std::string name = path.string();
  require_input_file(path, "a progressive mesh (.pm)");
  std::ifstream f(path, std::ios::binary);
  if (!f) throw InputError(name, "cannot open");
  const std::string data((std::istreambuf_iterator<char>(f)), std::istreambuf_iterator<char>());
  if (f.bad()) throw InputError(name, "cannot read");
  const auto* bytes = reinterpret_cast<const unsigned char*>(data.data());
  const size_t size = data.size();
  if (size < sizeof kMagic || std::memcmp(bytes, kMagic, sizeof kMagic) != 0)
    throw InputError(name, "not a meso progressive mesh (.pm)");
  if (size < kHeaderBytes + kFooterBytes) throw InputError(name, "truncated (" + std::to_string(size) + " bytes)");
  In in(bytes, size);
  in.text(sizeof kMagic);
  const uint32_t version = in.u32(), flags = in.u32();
  if (version != kVersion) throw InputError(name, "unsupported .pm version " + std::to_string(version) + " (this meso reads 1)");
  if (flags & ~kFlagUvs) throw InputError(name, "unknown flags " + std::to_string(flags));
  const bool uvs = (flags & kFlagUvs) != 0;
  const uint64_t nv = in.u64(), nf = in.u64(), ng = in.u64(), name_bytes = in.u64(), nc = in.u64(), nu = in.u64(),
                 final_faces = in.u64();
  // Every count is bounded before it is multiplied (no overflow below).
  for (const uint64_t n : {nv, nf, ng, nc, nu})
    if (n > kMaxElements) throw InputError(name, "corrupt header (a count of " + std::to_string(n) + ")");
  if (name_bytes > size) throw InputError(name, "truncated (" + std::to_string(size) + " bytes)");
  if (!uvs && nu != 0) throw InputError(name, "corrupt header (collapse UVs without corner UVs)");
  const uint64_t expected = kHeaderBytes + name_bytes + 12 * nv + (uvs ? 40 : 16) * nf + 16 * nc + 8 * nu + kFooterBytes;
  if (size < expected)
    throw InputError(name, "truncated (" + std::to_string(size) + " bytes, the header announces " + std::to_string(expected) + ")");
  if (size > expected) throw InputError(name, "corrupt (" + std::to_string(size - expected) + " bytes past the end)");
  {
    In footer(bytes + size - kFooterBytes, kFooterBytes);
    if (footer.u64() != fnv1a(bytes, size - kFooterBytes)) throw InputError(name, "corrupt (checksum mismatch)");
  }

  ProgressiveMesh pm;
  pm.source = name;
  pm.has_uvs = uvs;
  const size_t names_end = in.at() + name_bytes;
  for (uint64_t g = 0; g < ng; ++g) {
    if (names_end - in.at() < 4) throw InputError(name, "corrupt group names");
    const uint32_t len = in.u32();
    if (len > names_end - in.at()) throw InputError(name, "corrupt group names");
    pm.group_names.push_back(in.text(len));
  }
  if (in.at() != names_end) throw InputError(name, "corrupt group names");
  pm.positions.resize(nv);
  for (auto& p : pm.positions) {
    for (int i = 0; i < 3; ++i) p[i] = in.f32();
    if (!std::isfinite(p[0]) || !std::isfinite(p[1]) || !std::isfinite(p[2])) throw InputError(name, "a position is not finite");
  }
  pm.corners.resize(3 * nf);
  for (auto& c : pm.corners) {
    c = in.u32();
    if (c >= nv) throw InputError(name, "a face refers to vertex " + std::to_string(c) + " of " + std::to_string(nv));
  }
  pm.face_groups.resize(nf);
  for (auto& g : pm.face_groups) {
    g = in.u32();
    if (g >= ng) throw InputError(name, "a face refers to group " + std::to_string(g) + " of " + std::to_string(ng));
  }
  auto read_uv = [&](Vec2f& uv) {
    uv[0] = in.f32();
    uv[1] = in.f32();
    if (!std::isfinite(uv[0]) || !std::isfinite(uv[1])) throw InputError(name, "a UV is not finite");
  };
  if (uvs) {
    pm.corner_uvs.resize(3 * nf);
    for (auto& uv : pm.corner_uvs) read_uv(uv);
  }
  pm.collapses.resize(nc);
  for (auto& c : pm.collapses) {
    c.halfedge = in.u32();
    for (int i = 0; i < 3; ++i) c.position[i] = in.f32();
  }
  pm.uvs.resize(nu);
  for (auto& uv : pm.uvs) read_uv(uv);
  // Each collapse removes one face (a boundary edge) or two: the last level's face count is
  // bounded by the collapse count before any replay (a replay checks it exactly at the end).
  if (final_faces > nf || nc > nf || final_faces + nc > nf || final_faces + 2 * nc < nf)
    throw InputError(name, "corrupt header (face counts)");
  pm.final_faces = final_faces;
  return pm;
}

}  // namespace meso
