// A bumpy torus with a mirrored half: the curved mesh with UV seams and mirrored tangent
// frames that the identity-bake checks run on, in the library (bake_accuracy_test.cpp) and
// through the command line (tests/cli_test.cpp). Header-only: it needs Eigen, which the
// support library does not link.
#pragma once

#include "meso/core/mesh.hpp"
#include "test_support.hpp"

#include <Eigen/Dense>

#include <cmath>

namespace meso::test {

// A torus around the z axis, major radius R, tube radius r + amp * sin(2 pi ks s) sin(2 pi kt t)
// (ks, kt integers: periodic), at s, t in [0, 1]: theta = 2 pi s around z, phi = 2 pi t around
// the tube.
struct BumpyTorus {
  static constexpr double kPi = 3.14159265358979323846;

  double R = 1.0, r = 0.35, amp = 0.0;
  int ks = 8, kt = 4;

  double rho(double s, double t) const { return r + amp * std::sin(2 * kPi * ks * s) * std::sin(2 * kPi * kt * t); }
  Eigen::Vector3d point(double s, double t) const {
    const double th = 2 * kPi * s, ph = 2 * kPi * t, q = rho(s, t);
    return {(R + q * std::cos(ph)) * std::cos(th), (R + q * std::cos(ph)) * std::sin(th), q * std::sin(ph)};
  }
  // The analytic unit normal (outward): normalize(dP/ds x dP/dt).
  Eigen::Vector3d normal(double s, double t) const {
    const double th = 2 * kPi * s, ph = 2 * kPi * t, q = rho(s, t);
    const double q_s = amp * 2 * kPi * ks * std::cos(2 * kPi * ks * s) * std::sin(2 * kPi * kt * t);
    const double q_t = amp * 2 * kPi * kt * std::sin(2 * kPi * ks * s) * std::cos(2 * kPi * kt * t);
    const Eigen::Vector3d e(std::cos(ph) * std::cos(th), std::cos(ph) * std::sin(th), std::sin(ph));  // tube normal
    const Eigen::Vector3d d_th(-(R + q * std::cos(ph)) * std::sin(th), (R + q * std::cos(ph)) * std::cos(th), 0.0);
    const Eigen::Vector3d d_ph(-q * std::sin(ph) * std::cos(th), -q * std::sin(ph) * std::sin(th), q * std::cos(ph));
    const Eigen::Vector3d p_s = 2 * kPi * d_th + q_s * e, p_t = 2 * kPi * d_ph + q_t * e;
    return p_s.cross(p_t).normalized();
  }
  // The parameters of a point on the surface: the bump runs along the tube normal, which the
  // point's angles determine exactly.
  void params(const Eigen::Vector3d& p, double& s, double& t) const {
    s = std::atan2(p.y(), p.x()) / (2 * kPi);
    t = std::atan2(p.z(), std::hypot(p.x(), p.y()) - R) / (2 * kPi);
    s -= std::floor(s);
    t -= std::floor(t);
  }
  Mesh mesh(int columns, int rows) const {
    return make_parametric(
        columns, rows,
        [this](double s, double t) {
          const Eigen::Vector3d p = point(s, t);
          return Vec3f(static_cast<float>(p.x()), static_cast<float>(p.y()), static_cast<float>(p.z()));
        },
        true, true);
  }
};

// Lays out a parametric mesh's UVs (s, t) as two charts: the half s < 1/2 as it is, the half
// s > 1/2 mirrored in u (u decreasing with s) beside it. So the mesh has the wrap seams, a
// seam with a change of orientation at s = 1/2, and mirrored tangent frames on one half.
inline void mirror_half(Mesh& m) {
  for (auto f : m.faces()) {
    const auto hs = face_halfedges(m, f);
    float sc = 0;
    for (auto h : hs) sc += m.texcoord2D(h)[0] / 3.0f;
    for (auto h : hs) {
      const Vec2f st = m.texcoord2D(h);
      const float u = sc < 0.5f ? 0.03f + 0.9f * st[0] : 0.97f - 0.9f * (st[0] - 0.5f);
      m.set_texcoord2D(h, Vec2f(u, 0.03f + 0.94f * st[1]));
    }
  }
}

}  // namespace meso::test
