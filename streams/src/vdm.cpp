#include "meso/streams/vdm.hpp"

#include "meso/streams/height_ray.hpp"
#include "meso/streams/pyramid.hpp"

#include <Eigen/Dense>
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <string>

namespace meso {

VdmTable build_vdm(const HeightField& field, const VdmOptions& o, Progress& progress) {
  VdmTable table;
  table.width = field.height.width;
  table.height = field.height.height;
  table.theta = std::max(1, o.theta);
  table.phi = std::max(1, o.phi);
  table.curvatures = std::max<int>(1, static_cast<int>(o.curvatures.size()));
  const int dirs = table.directions();
  table.distance.assign(static_cast<size_t>(table.width) * static_cast<size_t>(table.height) * static_cast<size_t>(dirs), kVdmMiss);
  const MinMaxPyramid pyramid = build_min_max_pyramid(field);

  // Rays in the tracers' units (height_ray.hpp): t runs along the horizontal direction in
  // pixels. With w = W texels per unit of u, a horizontal step of t pixels is t / w units of
  // u; the ray drops (t / w) / tan(theta) units of u, which is that over `relief` in
  // normalised height; the bending c s^2 / 2 (s = t / w) likewise.
  const double w = table.width, relief = std::max(1e-12, static_cast<double>(o.relief));
  struct Direction {
    double dx, dy, dz, ddz;
  };
  std::vector<Direction> directions(static_cast<size_t>(dirs));
  for (int k = 0; k < table.curvatures; ++k)
    for (int i = 0; i < table.theta; ++i)
      for (int j = 0; j < table.phi; ++j) {
        const double theta = (i + 0.5) / table.theta * static_cast<double>(o.theta_max) * M_PI / 180.0;
        const double phi = 2.0 * M_PI * j / table.phi;
        const double c = o.curvatures.empty() ? 0.0 : static_cast<double>(o.curvatures[static_cast<size_t>(k)]);
        Direction& d = directions[static_cast<size_t>((k * table.theta + i) * table.phi + j)];
        d.dx = std::cos(phi);
        d.dy = -std::sin(phi);  // +v is up, rows go down
        d.dz = -1.0 / (std::tan(theta) * w * relief);
        d.ddz = c / (2.0 * relief * w * w);
      }

  progress.begin("vdm", static_cast<uint64_t>(table.height));
  tbb::parallel_for(tbb::blocked_range<int>(0, table.height), [&](const tbb::blocked_range<int>& rows) {
    for (int y = rows.begin(); y < rows.end(); ++y) {
      for (int x = 0; x < table.width; ++x) {
        float* out = &table.distance[(static_cast<size_t>(y) * static_cast<size_t>(table.width) + static_cast<size_t>(x)) *
                                     static_cast<size_t>(dirs)];
        for (int k = 0; k < dirs; ++k) {
          const Direction& d = directions[static_cast<size_t>(k)];
          HeightRay r;
          r.x = x + 0.5;
          r.y = y + 0.5;
          r.z = 1.0;
          r.dx = d.dx;
          r.dy = d.dy;
          r.dz = d.dz;
          r.ddz = d.ddz;
          const HeightHit hit = trace_min_max_pyramid(field, pyramid, r);
          out[k] = hit.hit ? static_cast<float>(hit.t / w) : kVdmMiss;
        }
      }
      progress.advance(1);
    }
  });
  progress.end();
  return table;
}

float CompressedVdm::value(size_t texel, int direction) const {
  double v = mean[static_cast<size_t>(direction)];
  const float* wt = weights.data() + texel * static_cast<size_t>(rank);
  const float* b = basis.data() + static_cast<size_t>(direction) * static_cast<size_t>(rank);
  for (int k = 0; k < rank; ++k) v += static_cast<double>(wt[k]) * b[k];
  return static_cast<float>(v);
}

CompressedVdm compress_vdm(const VdmTable& table, double max_rms, int max_rank) {
  CompressedVdm c;
  const size_t n = static_cast<size_t>(table.width) * static_cast<size_t>(table.height);
  const int m = table.directions();
  c.texels = static_cast<int>(n);
  c.directions = m;
  const size_t mm = static_cast<size_t>(m);

  // Column means and the covariance, accumulated over fixed blocks of texels and summed in
  // block order: the same bits whatever the thread count.
  Eigen::VectorXd mean = Eigen::VectorXd::Zero(m);
  for (size_t i = 0; i < n; ++i)
    for (int j = 0; j < m; ++j) mean[j] += table.distance[i * mm + static_cast<size_t>(j)];
  if (n) mean /= static_cast<double>(n);
  constexpr size_t kBlock = 1024;
  const size_t blocks = (n + kBlock - 1) / kBlock;
  std::vector<Eigen::MatrixXd> partial(blocks);
  tbb::parallel_for(size_t{0}, blocks, [&](size_t b) {
    Eigen::MatrixXd cov = Eigen::MatrixXd::Zero(m, m);
    Eigen::VectorXd row(m);
    for (size_t i = b * kBlock; i < std::min(n, (b + 1) * kBlock); ++i) {
      for (int j = 0; j < m; ++j) row[j] = table.distance[i * mm + static_cast<size_t>(j)] - mean[j];
      cov.selfadjointView<Eigen::Lower>().rankUpdate(row);
    }
    partial[b] = cov;
  });
  Eigen::MatrixXd cov = Eigen::MatrixXd::Zero(m, m);
  for (const Eigen::MatrixXd& p : partial) cov += p;
  cov = cov.selfadjointView<Eigen::Lower>();
  const Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> eig(cov);
  // Eigenvalues ascending; the residual energy of rank r is the sum of the m - r smallest.
  const Eigen::VectorXd lambda = eig.eigenvalues().cwiseMax(0.0);
  const double entries = std::max(1.0, static_cast<double>(n) * m);
  int rank = 0;
  double residual = lambda.sum();
  const int cap = std::clamp(max_rank, 0, m);
  while (rank < cap && std::sqrt(residual / entries) > max_rms) {
    residual -= lambda[m - 1 - rank];
    ++rank;
  }
  c.rank = rank;
  c.mean.resize(mm);
  for (int j = 0; j < m; ++j) c.mean[static_cast<size_t>(j)] = static_cast<float>(mean[j]);
  c.basis.resize(mm * static_cast<size_t>(rank));
  for (int j = 0; j < m; ++j)
    for (int k = 0; k < rank; ++k)
      c.basis[static_cast<size_t>(j) * static_cast<size_t>(rank) + static_cast<size_t>(k)] =
          static_cast<float>(eig.eigenvectors()(j, m - 1 - k));
  c.weights.resize(n * static_cast<size_t>(rank));
  tbb::parallel_for(tbb::blocked_range<size_t>(0, n), [&](const tbb::blocked_range<size_t>& range) {
    for (size_t i = range.begin(); i < range.end(); ++i)
      for (int k = 0; k < rank; ++k) {
        double s = 0;
        for (int j = 0; j < m; ++j)
          s += (table.distance[i * mm + static_cast<size_t>(j)] - mean[j]) * c.basis[static_cast<size_t>(j) * static_cast<size_t>(rank) + static_cast<size_t>(k)];
        c.weights[i * static_cast<size_t>(rank) + static_cast<size_t>(k)] = static_cast<float>(s);
      }
  });
  // The achieved error, entry by entry (float storage included).
  std::vector<double> block_sq(blocks, 0.0), block_max(blocks, 0.0);
  tbb::parallel_for(size_t{0}, blocks, [&](size_t b) {
    for (size_t i = b * kBlock; i < std::min(n, (b + 1) * kBlock); ++i)
      for (int j = 0; j < m; ++j) {
        const double e = std::abs(static_cast<double>(c.value(i, j)) - table.distance[i * mm + static_cast<size_t>(j)]);
        block_sq[b] += e * e;
        block_max[b] = std::max(block_max[b], e);
      }
  });
  double sq = 0;
  for (size_t b = 0; b < blocks; ++b) {
    sq += block_sq[b];
    c.max_error = std::max(c.max_error, block_max[b]);
  }
  c.rms_error = std::sqrt(sq / entries);
  return c;
}

}  // namespace meso

namespace meso {

std::vector<Image> vdm_images(const CompressedVdm& c, const HeightField& field, const VdmOptions& o) {
  // Part 0: weights, W x H, one channel per component (one zero channel at rank 0).
  const int channels = std::max(1, c.rank);
  Image weights(field.height.width, field.height.height, channels, 0.0f);
  for (size_t i = 0; i < weights.texel_count(); ++i)
    for (int k = 0; k < c.rank; ++k)
      weights.pixels[i * static_cast<size_t>(channels) + static_cast<size_t>(k)] = c.weights[i * static_cast<size_t>(c.rank) + static_cast<size_t>(k)];
  // Part 1: (rank + 1) x directions, column 0 the mean, column k + 1 component k.
  Image basis(c.rank + 1, c.directions, 1, 0.0f);
  for (int j = 0; j < c.directions; ++j) {
    basis.at(0, j) = c.mean[static_cast<size_t>(j)];
    for (int k = 0; k < c.rank; ++k) basis.at(k + 1, j) = c.basis[static_cast<size_t>(j) * static_cast<size_t>(c.rank) + static_cast<size_t>(k)];
  }
  // Curvatures with 9 significant digits: a float read back is the same float.
  std::string curvature_list;
  for (float v : o.curvatures.empty() ? std::vector<float>{0.0f} : o.curvatures) {
    char text[32];
    std::snprintf(text, sizeof text, "%.9g", static_cast<double>(v));
    curvature_list += (curvature_list.empty() ? "" : ",") + std::string(text);
  }
  weights.metadata = height_field_metadata(field);
  weights.metadata["quantity"] = std::string("view-dependent displacement (PCA)");
  weights.metadata["theta"] = o.theta;
  weights.metadata["theta_max"] = o.theta_max;
  weights.metadata["phi"] = o.phi;
  weights.metadata["curvatures"] = curvature_list;
  weights.metadata["relief"] = o.relief;
  weights.metadata["rank"] = c.rank;
  weights.metadata["rms_error"] = static_cast<float>(c.rms_error);
  weights.metadata["max_error"] = static_cast<float>(c.max_error);
  weights.metadata["miss"] = kVdmMiss;
  weights.metadata["layout"] = std::string(
      "d(texel, dir) = basis[0][dir] + sum_k weights[texel][k] basis[k+1][dir], units of u; dir = (curvature * theta + i) * phi + j; "
      "theta_i = (i + 0.5) / theta * theta_max, phi_j = 360 j / phi degrees from +u toward +v; d < -0.5: no hit");
  basis.metadata["quantity"] = std::string("view-dependent displacement basis: column 0 mean, column k + 1 component k, row = direction");
  return {std::move(weights), std::move(basis)};
}

}  // namespace meso

namespace meso {

double vdm_relief_on_mesh(double height_scale, double length_per_u) { return std::max(1e-6, height_scale / length_per_u); }

std::vector<float> vdm_curvature_slices(const std::vector<float>& k1, const std::vector<float>& k2, double length_per_u, int steps) {
  if (k1.empty() || k2.empty()) return {0.0f};
  // Nearest-rank percentile of a copy.
  auto percentile = [](std::vector<float> v, double p) {
    const size_t k = std::min(v.size() - 1, static_cast<size_t>(std::floor(p * static_cast<double>(v.size() - 1) + 0.5)));
    std::nth_element(v.begin(), v.begin() + static_cast<std::ptrdiff_t>(k), v.end());
    return static_cast<double>(v[k]);
  };
  const double lo = percentile(k2, 0.05), hi = percentile(k1, 0.95);
  // The range is judged per unit of u, as the slices are stored: in 1 / object units a
  // mesh 1e12 units across has a range of ~1e-12 and would have been taken as flat.
  const auto median_mean = [&] {
    std::vector<float> mean(k1.size());
    for (size_t i = 0; i < k1.size(); ++i) mean[i] = 0.5f * (k1[i] + k2[std::min(i, k2.size() - 1)]);
    return std::vector<float>{static_cast<float>(percentile(mean, 0.5) * length_per_u)};
  };
  if (steps <= 1 || (hi - lo) * length_per_u <= 1e-9) return median_mean();
  // Strictly increasing as floats (the previewer interpolates between neighbours): a range
  // narrow against its distance from 0 (k = 1 +- 3e-6) rounds several steps to one float.
  std::vector<float> out;
  for (int i = 0; i < steps; ++i) {
    const float v = static_cast<float>((lo + (hi - lo) * i / (steps - 1)) * length_per_u);
    if (out.empty() || v > out.back()) out.push_back(v);
  }
  return out.size() > 1 ? out : median_mean();
}

}  // namespace meso
