#include "meso/streams/vdm.hpp"

#include "meso/streams/height_ray.hpp"
#include "meso/streams/pyramid.hpp"

#include <Eigen/Dense>
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>

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
