// The lower envelope of parabolas, the core of Felzenszwalb & Huttenlocher's linear-time
// distance transforms ("Distance Transforms of Sampled Functions", Theory of Computing
// 2012, algorithm DT(f)). Used by the distance field (streams) and exact dilation (bake).
#pragma once

#include <cstddef>
#include <limits>
#include <vector>

namespace meso {

// For samples p = 0..n-1 with values f(p), the function q -> min_p (q - p)^2 + f(p),
// evaluated at any real positions q. f must be finite (use a large value for "nothing").
struct LowerEnvelope {
  std::vector<int> v;      // roots of the parabolas on the envelope, left to right
  std::vector<double> z;   // z[j], z[j+1]: where parabola v[j] is lowest
  int k = 0;               // index of the last parabola on the envelope

  void build(const double* f, int n, int stride) {
    constexpr double kInf = std::numeric_limits<double>::infinity();
    v.resize(static_cast<size_t>(n));
    z.resize(static_cast<size_t>(n) + 1);
    auto at = [&](int p) { return f[static_cast<size_t>(p) * static_cast<size_t>(stride)] + double(p) * p; };
    k = 0;
    v[0] = 0;
    z[0] = -kInf;
    z[1] = kInf;
    int vk = 0;
    double gk = at(0);
    for (int q = 1; q < n; ++q) {
      // Intersection s = (g_q - g_v) / (2 (q - v)) with the last parabola v (g_p = f(p) + p^2);
      // pop parabolas the new one hides entirely. Compared as a product (q > v), so only the
      // kept intersection costs a division. z[0] = -inf ends the loop at k = 0.
      const double gq = at(q);
      while (gq - gk <= 2.0 * (q - vk) * z[static_cast<size_t>(k)]) {
        --k;
        vk = v[static_cast<size_t>(k)];
        gk = at(vk);
      }
      const double s = (gq - gk) / (2.0 * (q - vk));
      ++k;
      v[static_cast<size_t>(k)] = q;
      z[static_cast<size_t>(k)] = s;
      z[static_cast<size_t>(k) + 1] = kInf;
      vk = q;
      gk = gq;
    }
  }

  // Evaluation walks the envelope once for non-decreasing positions q through a cursor.
  struct Cursor {
    int j = 0;
  };
  // The sample p whose parabola is lowest at q.
  int root(double q, Cursor& c) const {
    while (z[static_cast<size_t>(c.j) + 1] < q) ++c.j;
    return v[static_cast<size_t>(c.j)];
  }
  double eval(const double* f, int stride, double q, Cursor& c) const {
    const int p = root(q, c);
    return (q - p) * (q - p) + f[static_cast<size_t>(p) * static_cast<size_t>(stride)];
  }
};

}  // namespace meso
