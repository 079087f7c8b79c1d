#include "cli.hpp"

#include "meso/formats/mesh_io.hpp"

namespace meso::cli {

Mesh load_mesh(Globals& g, const std::string& path, nlohmann::json& report) {
  MeshReadReport r;
  Mesh mesh = read_mesh(path, &r);
  if (r.isolated_faces)
    warn(g, path + ": " + std::to_string(r.isolated_faces) +
                " non-manifold or degenerate faces kept on vertices of their own");
  if (r.faces_without_uv) warn(g, path + ": " + std::to_string(r.faces_without_uv) + " faces have no UVs (set to 0,0)");
  report = {{"path", path},
            {"vertices", mesh.n_vertices()},
            {"faces", mesh.n_faces()},
            {"has_uvs", has_uvs(mesh)},
            {"isolated_faces", r.isolated_faces}};
  return mesh;
}

}  // namespace meso::cli
