// Progress reporting without global state: long operations take a Progress& and call
// advance(); what it shows (a bar on a TTY, nothing otherwise) is the caller's choice.
#pragma once

#include <atomic>
#include <cstdint>
#include <string>

namespace meso {

class Progress {
 public:
  virtual ~Progress() = default;
  // Starts a phase of `total` units of work with a short label ("bake rays").
  virtual void begin(const std::string& label, uint64_t total) = 0;
  // Adds `units` done. Thread-safe; cheap enough to call per row or per chunk.
  virtual void advance(uint64_t units) = 0;
  virtual void end() = 0;
};

// Shows nothing. The default for libraries' callers that do not care.
class NullProgress final : public Progress {
 public:
  void begin(const std::string&, uint64_t) override {}
  void advance(uint64_t) override {}
  void end() override {}
};

NullProgress& null_progress();

// A one-line bar on stderr, redrawn at most ~10 times a second. Shows nothing unless
// `enabled` (the app enables it when stderr is a TTY and --quiet is not given).
class TerminalProgress final : public Progress {
 public:
  explicit TerminalProgress(bool enabled) : enabled_(enabled) {}
  void begin(const std::string& label, uint64_t total) override;
  void advance(uint64_t units) override;
  void end() override;
  // Erases a bar left unfinished by an error, so the error line stands alone.
  void abandon();

 private:
  void draw(bool final_draw);
  bool enabled_;
  std::string label_;
  uint64_t total_ = 0;
  std::atomic<uint64_t> done_{0};
  std::atomic<int64_t> last_draw_ms_{0};
  bool open_ = false;  // a bar is on screen without its final newline
  int64_t start_ms_ = 0;
};

}  // namespace meso
