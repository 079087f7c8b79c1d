#include "camera.hpp"

#include <algorithm>
#include <cmath>

namespace meso {

namespace {

using Vec3d = OpenMesh::Vec3d;

std::array<float, 16> multiply(const std::array<float, 16>& a, const std::array<float, 16>& b) {
  std::array<float, 16> r{};
  for (int c = 0; c < 4; ++c)
    for (int rr = 0; rr < 4; ++rr) {
      float s = 0;
      for (int k = 0; k < 4; ++k) s += a[static_cast<size_t>(k * 4 + rr)] * b[static_cast<size_t>(c * 4 + k)];
      r[static_cast<size_t>(c * 4 + rr)] = s;
    }
  return r;
}

}  // namespace

CameraPose frame_camera(const Mesh& base, const PreviewCamera& cam, float aspect, double reach) {
  // Mean normal: the area-weighted sum of face normals.
  Vec3d n(0, 0, 0);
  for (auto f : base.faces()) {
    const auto hs = face_halfedges(base, f);
    const Vec3d a = OpenMesh::vector_cast<Vec3d>(base.point(base.to_vertex_handle(hs[0])));
    const Vec3d b = OpenMesh::vector_cast<Vec3d>(base.point(base.to_vertex_handle(hs[1])));
    const Vec3d c = OpenMesh::vector_cast<Vec3d>(base.point(base.to_vertex_handle(hs[2])));
    n += OpenMesh::cross(b - a, c - a);
  }
  if (!(n.norm() > 0)) n = Vec3d(0, 0, 1);
  n.normalize();
  const Vec3d ref = std::abs(n[1]) < 0.9 ? Vec3d(0, 1, 0) : Vec3d(1, 0, 0);
  const Vec3d e1 = OpenMesh::cross(ref, n).normalize();
  const Vec3d e2 = OpenMesh::cross(n, e1);
  const Box3 box = bounding_box(base);
  const Vec3d center = OpenMesh::vector_cast<Vec3d>(box.center());
  const double radius = std::max(0.5 * box.diagonal(), 1e-30);
  const double pi = 3.14159265358979323846;
  const double a = std::clamp(static_cast<double>(cam.view_angle), 0.0, 89.9) * pi / 180.0;
  const double az = static_cast<double>(cam.azimuth) * pi / 180.0;
  const double fov = 40.0 * pi / 180.0;
  const double dist = radius / std::sin(0.5 * fov) / std::max(static_cast<double>(cam.zoom), 1e-3);
  const Vec3d side = e1 * std::cos(az) + e2 * std::sin(az);
  const Vec3d to_eye = n * std::cos(a) + side * std::sin(a);
  // Up: perpendicular to the orbit plane's side direction, so it is never parallel to the view.
  const Vec3d up_hint = e2 * std::cos(az) - e1 * std::sin(az);
  const Vec3d orbit_eye = center + to_eye * dist;
  const Vec3d f = (center - orbit_eye).normalize();
  const Vec3d r = OpenMesh::cross(f, up_hint).normalize();
  const Vec3d u = OpenMesh::cross(r, f);
  // Panning moves the eye, and the point it looks at, across the view (perpendicular to f:
  // the mesh's depth range below is unchanged).
  const Vec3d eye = orbit_eye + (r * static_cast<double>(cam.pan_x) + u * static_cast<double>(cam.pan_y)) * radius;
  std::array<float, 16> view{};
  for (int i = 0; i < 3; ++i) {
    view[static_cast<size_t>(i * 4 + 0)] = static_cast<float>(r[i]);
    view[static_cast<size_t>(i * 4 + 1)] = static_cast<float>(u[i]);
    view[static_cast<size_t>(i * 4 + 2)] = static_cast<float>(-f[i]);
  }
  view[12] = static_cast<float>(-OpenMesh::dot(r, eye));
  view[13] = static_cast<float>(-OpenMesh::dot(u, eye));
  view[14] = static_cast<float>(OpenMesh::dot(f, eye));
  view[15] = 1.0f;
  // A map 2 units below a unit base was clipped away by a depth range of the base's box alone
  // (an empty frame at any zoom).
  const double depth_radius = 1.5 * radius + (std::isfinite(reach) ? std::abs(reach) : 0.0);
  const double near_plane = std::max(dist - depth_radius, dist * 1e-3), far_plane = dist + depth_radius;
  const double ft = 1.0 / std::tan(0.5 * fov);
  std::array<float, 16> proj{};
  proj[0] = static_cast<float>(ft / aspect);
  proj[5] = static_cast<float>(ft);
  proj[10] = static_cast<float>((far_plane + near_plane) / (near_plane - far_plane));
  proj[11] = -1.0f;
  proj[14] = static_cast<float>(2.0 * far_plane * near_plane / (near_plane - far_plane));
  CameraPose pose;
  pose.view_projection = multiply(proj, view);
  pose.eye = OpenMesh::vector_cast<Vec3f>(eye);
  {
    // Elevation above the mean plane, azimuth from e1 toward e2 (the defaults: n + 0.6 e2 - 0.4 e1).
    const double el = static_cast<double>(cam.light_elevation) * pi / 180.0, laz = static_cast<double>(cam.light_azimuth) * pi / 180.0;
    pose.light = OpenMesh::vector_cast<Vec3f>((n * std::sin(el) + (e1 * std::cos(laz) + e2 * std::sin(laz)) * std::cos(el)).normalize());
  }
  pose.eye_d = eye;
  pose.right = r;
  pose.up = u;
  pose.forward = f;
  pose.tan_half_fov = 1.0 / ft;
  pose.aspect = static_cast<double>(aspect);
  return pose;
}

void pixel_ray(const CameraPose& pose, int x, int y, int width, int height, OpenMesh::Vec3d& origin, OpenMesh::Vec3d& direction) {
  // Normalised device coordinates of the pixel centre; GL's window rows go up, Image's down.
  const double nx = 2.0 * (x + 0.5) / width - 1.0, ny = 1.0 - 2.0 * (y + 0.5) / height;
  // The projection maps x_view / -z_view = nx * aspect * tan(fov / 2), likewise y without aspect.
  origin = pose.eye_d;
  direction = (pose.forward + pose.right * (nx * pose.aspect * pose.tan_half_fov) + pose.up * (ny * pose.tan_half_fov)).normalize();
}

}  // namespace meso
