#include "meso/core/progress.hpp"

#include <chrono>
#include <cstdio>
#include <mutex>

namespace meso {
namespace {
int64_t now_ms() {
  using namespace std::chrono;
  return duration_cast<milliseconds>(steady_clock::now().time_since_epoch()).count();
}
std::mutex& draw_mutex() {
  static std::mutex m;
  return m;
}
}  // namespace

NullProgress& null_progress() {
  static NullProgress p;
  return p;
}

void TerminalProgress::begin(const std::string& label, uint64_t total) {
  label_ = label;
  total_ = total;
  done_ = 0;
  start_ms_ = now_ms();
  last_draw_ms_ = 0;
  if (enabled_) {
    open_ = true;
    draw(false);
  }
}

void TerminalProgress::advance(uint64_t units) {
  done_.fetch_add(units, std::memory_order_relaxed);
  if (!enabled_) return;
  const int64_t t = now_ms();
  int64_t last = last_draw_ms_.load(std::memory_order_relaxed);
  if (t - last < 100) return;
  if (!last_draw_ms_.compare_exchange_strong(last, t)) return;  // another thread draws
  draw(false);
}

void TerminalProgress::end() {
  if (!enabled_) return;
  done_ = total_;
  draw(true);
  open_ = false;
}

void TerminalProgress::abandon() {
  if (!enabled_ || !open_) return;
  std::lock_guard<std::mutex> lock(draw_mutex());
  std::fputs("\r\033[K", stderr);
  std::fflush(stderr);
  open_ = false;
}

void TerminalProgress::draw(bool final_draw) {
  std::lock_guard<std::mutex> lock(draw_mutex());
  const double f = total_ ? std::min(1.0, static_cast<double>(done_.load()) / static_cast<double>(total_)) : 1.0;
  constexpr int kWidth = 30;
  const int filled = static_cast<int>(f * kWidth);
  char bar[kWidth + 1];
  for (int i = 0; i < kWidth; ++i) bar[i] = i < filled ? '#' : '.';
  bar[kWidth] = 0;
  const double secs = static_cast<double>(now_ms() - start_ms_) / 1000.0;
  std::fprintf(stderr, "\r%-18s [%s] %5.1f%% %6.1fs", label_.c_str(), bar, f * 100.0, secs);
  if (final_draw) std::fputc('\n', stderr);
  std::fflush(stderr);
}

}  // namespace meso
