// The previewer's camera, shared by the OpenGL renderer (renderer.cpp) and the CPU
// reference renderer (reference.cpp) so that both see exactly the same view. No OpenGL here.
#pragma once

#include "meso/preview/preview.hpp"

#include <array>

namespace meso {

// Camera placement derived from the mesh (mean normal, bounding sphere) and PreviewCamera.
struct CameraPose {
  std::array<float, 16> view_projection;  // column-major, what the vertex shader multiplies by
  Vec3f eye;
  Vec3f light;  // unit, toward the light, fixed relative to the mesh
  // The same camera in double, from which view_projection was made: eye, unit right, up and
  // forward (view) directions, tan of half the vertical field of view, width / height.
  OpenMesh::Vec3d eye_d{0, 0, 0}, right{1, 0, 0}, up{0, 1, 0}, forward{0, 0, -1};
  double tan_half_fov = 1, aspect = 1;
};
// `reach`: how far (object units) the displaced surface may lie from the base, the larger of
// |displacement min| and |max|; the depth range covers the base's box grown by it, so a
// surface displaced far below or above its base is not clipped. The framing is the base's.
CameraPose frame_camera(const Mesh& base, const PreviewCamera& camera, float aspect, double reach = 0);

// The ray through the centre of pixel (x, y) of a width x height image, rows from the top
// (Image's convention): the ray along which the rasteriser samples that pixel with
// view_projection (window coordinates x + 0.5, height - y - 0.5). Origin: the eye; the
// direction is a unit vector.
void pixel_ray(const CameraPose& pose, int x, int y, int width, int height, OpenMesh::Vec3d& origin, OpenMesh::Vec3d& direction);

}  // namespace meso
