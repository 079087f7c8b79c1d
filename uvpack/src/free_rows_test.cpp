// The packer's occupancy bitmap against its definitions, on a plain bool per texel.
#include "free_rows.hpp"

#include <gtest/gtest.h>

#include <random>
#include <vector>

namespace meso {
namespace {

// A run of free texels covers [s, s + length) when every column there is below n and free.
bool all_free(const std::vector<bool>& row, int s, int length) {
  for (int c = s; c < s + length; ++c)
    if (c >= static_cast<int>(row.size()) || !row[static_cast<size_t>(c)]) return false;
  return true;
}

int longest_run(const std::vector<bool>& row) {
  int best = 0, run = 0;
  for (bool f : row) best = std::max(best, run = f ? run + 1 : 0);
  return best;
}

TEST(FreeRows, MatchesTheDefinitionsUnderRandomBlocking) {
  std::mt19937 rng(7);
  // Sizes around the word boundaries, and one small enough to be a single partial word.
  for (int n : {1, 5, 63, 64, 65, 127, 128, 129, 200, 300}) {
    FreeRows rows(n);
    std::vector<std::vector<bool>> ref(static_cast<size_t>(n), std::vector<bool>(static_cast<size_t>(n), true));
    std::uniform_int_distribution<int> any(0, n - 1);
    for (int step = 0; step < 40; ++step) {
      // Block a random span of a random row: short spans leave many short holes, long ones few.
      const int row = any(rng), a = any(rng), b = std::min(n - 1, a + std::uniform_int_distribution<int>(0, step % 2 == 0 ? 3 : n)(rng));
      size_t freed = 0;
      for (int c = a; c <= b; ++c) {
        freed += ref[static_cast<size_t>(row)][static_cast<size_t>(c)] ? 1 : 0;
        ref[static_cast<size_t>(row)][static_cast<size_t>(c)] = false;
      }
      ASSERT_EQ(rows.take(row, a, b), freed) << "n " << n << " row " << row << " [" << a << ", " << b << "]";
      const auto& want = ref[static_cast<size_t>(row)];
      ASSERT_EQ(rows.longest(row), longest_run(want)) << "n " << n << " row " << row;
      for (int c = 0; c < n; ++c) ASSERT_EQ(rows.is_free(row, c), want[static_cast<size_t>(c)]);
      // next_fit() from every column below n + 64, at lengths 1, 2, 3, 64, 65, n.
      std::vector<int> rem(static_cast<size_t>(n) + 1, 0);  // free columns from c on
      for (int c = n - 1; c >= 0; --c) rem[static_cast<size_t>(c)] = want[static_cast<size_t>(c)] ? rem[static_cast<size_t>(c) + 1] + 1 : 0;
      for (int from = 0; from < n + 64; ++from)
        for (int length : {1, 2, 3, 64, 65, n}) {
          int expected = -1;
          for (int c = from; c < n && expected < 0; ++c)
            if (rem[static_cast<size_t>(c)] >= length) expected = c;
          ASSERT_EQ(rows.next_fit(row, from, length), expected) << "n " << n << " from " << from << " length " << length;
        }
      if (step % 4 != 3) continue;
      // starts() at allowed origins s < n + 64 (every one up to 130 columns, every 7th above)
      // and every length, bit by bit.
      for (int s = 0; s < n + 64; s += (n > 130 ? 7 : 1))
        for (int length = 1; length <= 64; ++length) {
          const uint64_t got = rows.starts(row, s, length);
          for (int j = 0; j < 64; ++j)
            ASSERT_EQ((got >> j) & 1, all_free(want, s + j, length) ? 1u : 0u) << "n " << n << " s " << s << " length " << length << " j " << j;
        }
    }
    for (int r = 0; r < n; ++r) {  // every row at the end: a take() touches its own row only
      ASSERT_EQ(rows.longest(r), longest_run(ref[static_cast<size_t>(r)])) << "n " << n << " row " << r;
      for (int c = 0; c < n; ++c) ASSERT_EQ(rows.is_free(r, c), ref[static_cast<size_t>(r)][static_cast<size_t>(c)]);
    }
  }
}

}  // namespace
}  // namespace meso
