#include "cli.hpp"

#include "meso/formats/mesh_io.hpp"

#include <cstdio>

namespace meso::cli {

Mesh load_mesh(Globals& g, const std::string& path, nlohmann::json& report) {
  MeshReadReport r;
  Mesh mesh = read_mesh(path, &r);
  if (r.isolated_faces)
    warn(g, path + ": " + std::to_string(r.isolated_faces) +
                " non-manifold or degenerate faces kept on vertices of their own");
  if (r.faces_without_uv) warn(g, path + ": " + std::to_string(r.faces_without_uv) + " faces have no UVs (set to 0,0)");
  if (r.step_per_edge > kWarnFloatStepPerEdge) {
    char text[200];
    std::snprintf(text, sizeof text,
                  "coordinates reach %.3g, where 32-bit floats step by %.3g; at its median edge the step is %.2g %% of the edge: finer detail is lost (move the mesh near the origin)",
                  r.largest_coordinate, r.float_step, 100 * r.step_per_edge);
    warn(g, path + ": " + text);
  }
  report = {{"path", path},
            {"vertices", mesh.n_vertices()},
            {"faces", mesh.n_faces()},
            {"has_uvs", has_uvs(mesh)},
            {"isolated_faces", r.isolated_faces}};
  return mesh;
}

}  // namespace meso::cli
