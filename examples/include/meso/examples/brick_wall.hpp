// The bundled example asset, generated deterministically instead of committed: a brick
// wall with bevelled, slightly rough bricks in recessed mortar, optionally bent around a
// vertical cylinder so that the base surface is curved. Its exact height function is
// public so that tests can compare a bake against the true answer.
#pragma once

#include "meso/core/mesh.hpp"

namespace meso {

struct BrickWallOptions {
  float width = 2.0f;         // object units along x (along the arc when bent)
  float height = 1.0f;        // object units along y
  float bend_radius = 3.0f;   // radius of the cylinder the wall is bent around; 0 = flat
  float amplitude = 0.025f;   // brick face height above the mortar, object units
  float roughness = 0.15f;    // noise amplitude relative to `amplitude`
  int columns = 512;          // grid quads along x (two triangles each)
  int rows = 256;             // grid quads along y
};

// Height above the base surface at wall coordinates (x, y) in [0,width] x [0,height],
// in object units, >= 0. Zero on the wall's border (mortar frame), so the border lies on
// the base surface.
float brick_wall_height(const BrickWallOptions& o, float x, float y);

// Point on the base surface (height 0) and its unit normal at wall coordinates (x, y).
// The flat wall lies in the z = 0 plane facing +z; the bent wall lies on the cylinder of
// radius bend_radius whose axis is parallel to y through (0, 0, -bend_radius), facing out.
void brick_wall_base(const BrickWallOptions& o, float x, float y, Vec3f& point, Vec3f& normal);

// The high-poly wall: a rows x columns grid displaced along the base normal by
// brick_wall_height(), UVs (x / width, y / height), one face group "bricks_high".
Mesh make_brick_wall(const BrickWallOptions& o);

// The base surface alone, as a grid of the given resolution with the same UVs: the ideal
// base mesh, used by tests as the low mesh of a bake whose answer is known.
Mesh make_brick_wall_base(const BrickWallOptions& o, int columns, int rows);

}  // namespace meso
