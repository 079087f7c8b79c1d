#pragma once
// The packer's occupancy bitmap (uv_pack.cpp), apart so that its bit arithmetic is tested
// against the definitions (free_rows_test.cpp).

#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <vector>

namespace meso {

// An n x n atlas's free texels, one bit per texel, row by row (bit c % 64 of word c / 64 is
// column c; 1 free). At a bit a texel, a 4096² atlas is 2 MB and stays in cache while the
// packer's scan reads a footprint's rows at every candidate (with an int per texel it missed
// the cache at each: 2.5x the time at 4096²). Each row ends in zero words (blocked) past
// column n - 1, so windows that reach past the row's end need no bounds test.
class FreeRows {
 public:
  explicit FreeRows(int n) : words_(static_cast<size_t>(n) / 64 + 4), bits_(static_cast<size_t>(n) * words_, 0) {
    for (int row = 0; row < n; ++row) {
      uint64_t* w = bits_.data() + static_cast<size_t>(row) * words_;
      for (int c = 0; c < n; c += 64) w[c / 64] = n - c >= 64 ? ~uint64_t{0} : (uint64_t{1} << (n - c)) - 1;
    }
  }
  bool is_free(int row, int c) const { return (bits_[index(row, c)] >> (c % 64)) & 1; }
  // Blocks columns [a, b] of a row (0 <= a <= b < n); returns how many of them were free.
  size_t take(int row, int a, int b) {
    size_t freed = 0;
    for (int c = a; c <= b;) {
      const int end = std::min(b, c / 64 * 64 + 63);
      const uint64_t mask = (~uint64_t{0} >> (63 - (end - c))) << (c % 64);
      uint64_t& w = bits_[index(row, c)];
      freed += static_cast<size_t>(__builtin_popcountll(w & mask));
      w &= ~mask;
      c = end + 1;
    }
    return freed;
  }
  // The longest run of free texels in a row, a word at a time.
  int longest(int row) const {
    const uint64_t* w = bits_.data() + index(row, 0);
    int best = 0, run = 0;
    for (size_t i = 0; i < words_; ++i) {
      const uint64_t x = w[i];
      if (x == ~uint64_t{0}) {
        run += 64;
        continue;
      }
      for (int pos = 0; pos < 64;) {
        const int ones = __builtin_ctzll(~(x >> pos));  // x >> pos has zeros on top: ~ is nonzero
        run += ones;
        pos += ones;
        if (pos == 64) break;  // the run goes on into the next word
        best = std::max(best, run);
        run = 0;
        const uint64_t rest = x >> pos;
        if (rest == 0) break;
        pos += __builtin_ctzll(rest);
      }
    }
    return std::max(best, run);
  }
  // The first column c >= from where columns [c, c + length) of the row are all free
  // (length >= 1), or -1: a walk over the row's free runs, a word of blocked columns at a
  // time.
  int next_fit(int row, int from, int length) const {
    for (int c = first_free(row, from); c >= 0;) {
      const int end = first_blocked(row, c);
      if (end - c >= length) return c;
      c = first_free(row, end);
    }
    return -1;
  }
  // Bit j set when columns [s + j, s + j + length - 1] of the row are all free, for j in
  // [0, 64) (0 <= s < n + 64, 1 <= length <= 64): the 128 bits from s ANDed with themselves
  // shifted by doubling distances (log2 length steps), reading no bit past s + 127.
  uint64_t starts(int row, int s, int length) const {
    const uint64_t* w = bits_.data() + index(row, s);
    const int shift = s % 64;
    uint64_t lo = w[0], hi = w[1];  // bits s .. s + 63 and s + 64 .. s + 127
    if (shift != 0) {
      lo = lo >> shift | hi << (64 - shift);
      hi = hi >> shift | w[2] << (64 - shift);
    }
    if ((lo | hi) == 0) return 0;
    for (int have = 1; have < length;) {  // lo bit j: columns [s + j, s + j + have) free
      const int k = std::min(have, length - have);  // 1 .. 32
      lo &= lo >> k | hi << (64 - k);
      hi &= hi >> k;
      have += k;
    }
    return lo;
  }

 private:
  // The first free column >= c of the row, or -1.
  int first_free(int row, int c) const {
    size_t i = static_cast<size_t>(c) / 64;
    if (i >= words_) return -1;
    const uint64_t* w = bits_.data() + index(row, 0);
    uint64_t x = w[i] & (~uint64_t{0} << (c % 64));
    while (x == 0) {
      if (++i == words_) return -1;
      x = w[i];
    }
    return static_cast<int>(i * 64) + __builtin_ctzll(x);
  }
  // The first blocked column >= c (c below n + 64): the zero words past the row's end stop it.
  int first_blocked(int row, int c) const {
    const uint64_t* w = bits_.data() + index(row, 0);
    size_t i = static_cast<size_t>(c) / 64;
    uint64_t x = ~w[i] & (~uint64_t{0} << (c % 64));
    while (x == 0) x = ~w[++i];
    return static_cast<int>(i * 64) + __builtin_ctzll(x);
  }
  size_t index(int row, int c) const { return static_cast<size_t>(row) * words_ + static_cast<size_t>(c) / 64; }
  size_t words_;
  std::vector<uint64_t> bits_;
};

}  // namespace meso
