#include "meso/bake/curvature_map.hpp"

#include "meso/bake/dilate.hpp"
#include "meso/bake/uv_raster.hpp"
#include "meso/core/dilation_sources.hpp"
#include "meso/core/error.hpp"

#include <Eigen/Dense>
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <string>

namespace meso {

namespace {

// What a face's texels interpolate, read once: per corner (face_halfedges order) the vertex
// normal, the corner's tangent and the vertex's shape tensor; the face's handedness.
struct FaceData {
  std::array<Eigen::Vector3d, 3> n, t;
  std::array<Eigen::Matrix3d, 3> s;
  double sign = 1;
};

// S = k1 d1 d1^T + k2 d2 d2^T: the shape operator of the fitted quadric (survey section 5.1,
// eq. 13: its Hessian's eigenvalues and eigenvectors) as an object-space tensor, so that it
// can be interpolated between vertices whose principal directions are unrelated (d1 and -d1
// are the same direction, and k1 = k2 leaves d1 arbitrary; the tensor has neither problem).
Eigen::Matrix3d shape_tensor(const VertexCurvature& c) {
  const Eigen::Vector3d d1(c.d1[0], c.d1[1], c.d1[2]), d2(c.d2[0], c.d2[1], c.d2[2]);
  return double(c.k1) * d1 * d1.transpose() + double(c.k2) * d2 * d2.transpose();
}

}  // namespace

CurvatureMap bake_curvature_map(const Mesh& mesh, const std::vector<TangentFrame>& frames, const std::vector<VertexCurvature>& curvature,
                                const CurvatureMapOptions& o) {
  if (o.width < 1 || o.height < 1) throw InternalError("bake_curvature_map: size must be positive");
  if (frames.size() != mesh.n_halfedges()) throw InternalError("bake_curvature_map: one tangent frame per halfedge expected");
  if (curvature.size() != mesh.n_vertices()) throw InternalError("bake_curvature_map: one curvature per vertex expected");
  if (!mesh.has_halfedge_texcoords2D() || !mesh.has_vertex_normals()) throw InternalError("bake_curvature_map: needs UVs and vertex normals");

  std::vector<FaceData> faces(mesh.n_faces());
  tbb::parallel_for(tbb::blocked_range<size_t>(0, mesh.n_faces(), 256), [&](const tbb::blocked_range<size_t>& fr) {
    for (size_t fi = fr.begin(); fi < fr.end(); ++fi) {
      FaceData& fd = faces[fi];
      const auto hs = face_halfedges(mesh, FaceHandle(static_cast<int>(fi)));
      for (size_t k = 0; k < 3; ++k) {
        const auto v = mesh.to_vertex_handle(hs[k]);
        const Vec3f& nv = mesh.normal(v);
        const Vec3f& tv = frames[static_cast<size_t>(hs[k].idx())].tangent;
        fd.n[k] = Eigen::Vector3d(nv[0], nv[1], nv[2]);
        fd.t[k] = Eigen::Vector3d(tv[0], tv[1], tv[2]);
        fd.s[k] = shape_tensor(curvature[static_cast<size_t>(v.idx())]);
      }
      // One sign per triangle (tangent_frame.hpp: all three corners carry it); the bake and
      // the previewer take corner 0's.
      fd.sign = frames[static_cast<size_t>(hs[0].idx())].sign;
    }
  });

  CurvatureMap r;
  r.image = Image(o.width, o.height, 4, 0.0f);
  std::vector<uint8_t> written(r.image.texel_count(), 0), touched(r.image.texel_count(), 0);
  // Per row: eigenvalue extremes of the row's computed texels (min/max are exact in any
  // order, so the per-row results combine deterministically).
  std::vector<double> row_lo(static_cast<size_t>(o.height), 0), row_hi(static_cast<size_t>(o.height), 0);

  // The bake's texel -> surface point rule, a band of rows at a time (identical to
  // rasterize_uv's result, without holding the whole image's samples).
  const UvRasterizer raster(mesh, o.width, o.height);
  tbb::parallel_for(tbb::blocked_range<int>(0, o.height, 8), [&](const tbb::blocked_range<int>& rows) {
    const std::vector<TexelSample> band = raster.rows(rows.begin(), rows.end());
    for (int y = rows.begin(); y < rows.end(); ++y) {
      bool any = false;
      double lo = 0, hi = 0;
      for (int x = 0; x < o.width; ++x) {
        const TexelSample& s = band[static_cast<size_t>(y - rows.begin()) * static_cast<size_t>(o.width) + static_cast<size_t>(x)];
        if (s.face < 0) continue;
        const size_t i = static_cast<size_t>(y) * static_cast<size_t>(o.width) + static_cast<size_t>(x);
        touched[i] = 1;
        const FaceData& fd = faces[static_cast<size_t>(s.face)];
        // Interpolated as the shader interpolates (unnormalised normal and tangent), the
        // tensor likewise.
        Eigen::Vector3d n = Eigen::Vector3d::Zero(), t = Eigen::Vector3d::Zero();
        Eigen::Matrix3d S = Eigen::Matrix3d::Zero();
        for (size_t k = 0; k < 3; ++k) {
          const double w = s.bary[k];
          n += w * fd.n[k];
          t += w * fd.t[k];
          S += w * fd.s[k];
        }
        // No normal (opposite vertex normals cancel) or no tangent across it: the shader has
        // no frame here either; leave the texel to dilation rather than invent one.
        if (!(n.norm() > 1e-12)) continue;
        const Eigen::Vector3d nn = n.normalized();
        const Eigen::Vector3d tp = t - nn * nn.dot(t);
        if (!(tp.norm() > 1e-9)) continue;
        const Eigen::Vector3d tt = tp.normalized();
        const Eigen::Vector3d bb = fd.sign * nn.cross(tt);
        const double ktt = tt.dot(S * tt), ktb = 0.5 * (tt.dot(S * bb) + bb.dot(S * tt)), kbb = bb.dot(S * bb);
        if (!std::isfinite(ktt) || !std::isfinite(ktb) || !std::isfinite(kbb)) continue;
        float* px = r.image.texel(x, y);
        px[0] = static_cast<float>(ktt);
        px[1] = static_cast<float>(ktb);
        px[2] = static_cast<float>(kbb);
        px[3] = 1.0f;
        written[i] = 1;
        // Eigenvalues of the symmetric 2x2: the principal curvatures as the map sees them.
        const double mean = 0.5 * (ktt + kbb), rad = std::hypot(0.5 * (ktt - kbb), ktb);
        lo = any ? std::min(lo, mean - rad) : mean - rad;
        hi = any ? std::max(hi, mean + rad) : mean + rad;
        any = true;
      }
      if (any) {
        row_lo[static_cast<size_t>(y)] = lo;
        row_hi[static_cast<size_t>(y)] = hi;
      } else {
        row_lo[static_cast<size_t>(y)] = std::nan("");  // marks a row without computed texels
      }
    }
  });

  bool first = true;
  double lo = 0, hi = 0;
  for (int y = 0; y < o.height; ++y) {
    if (std::isnan(row_lo[static_cast<size_t>(y)])) continue;
    lo = first ? row_lo[static_cast<size_t>(y)] : std::min(lo, row_lo[static_cast<size_t>(y)]);
    hi = first ? row_hi[static_cast<size_t>(y)] : std::max(hi, row_hi[static_cast<size_t>(y)]);
    first = false;
  }
  r.min = static_cast<float>(lo);
  r.max = static_cast<float>(hi);
  for (size_t i = 0; i < written.size(); ++i) {
    r.texels += written[i];
    r.undefined += touched[i] && !written[i];
  }

  // Dilation as the bake's maps (nearest computed texel, exact Euclidean), so that bilinear
  // filtering and mip-mapping at a chart's edge read curvature of that chart, not zeros.
  // Alpha keeps saying which texels were computed.
  if (r.texels != written.size() && r.texels > 0) {
    apply_dilation(r.image, dilation_sources(written, o.width, o.height, o.dilate));
    for (size_t i = 0; i < written.size(); ++i) r.image.pixels[4 * i + 3] = written[i] ? 1.0f : 0.0f;
  }

  r.image.metadata = {{"quantity", std::string("curvature")},
                      {"units", std::string("1/object")},
                      {"channels", std::string("R = k_tt, G = k_tb, B = k_bb, A = 1 computed / 0 dilated")},
                      {"convention", std::string("second fundamental form in the texel's orthonormalised MikkTSpace frame (t along +u, "
                                                 "b = sign * cross(n, t) along +v); positive where the surface bends away from its normal; "
                                                 "curvature along unit w = (wt, wb) is wt^2 k_tt + 2 wt wb k_tb + wb^2 k_bb")},
                      {"min", r.min},
                      {"max", r.max}};
  return r;
}

}  // namespace meso
