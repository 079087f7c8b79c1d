#include "meso/formats/atomic_file.hpp"

#include "meso/core/error.hpp"

#include <fcntl.h>
#include <unistd.h>

#include <atomic>
#include <cerrno>
#include <csignal>
#include <cstring>

#include <fstream>
#include <string>
#include <system_error>

namespace meso {

namespace fs = std::filesystem;

namespace {

// Every listed path of the live OutputSets, for the signal handler: fixed tables of atomic
// pointers, files and folders apart (a set lists its temporaries and new folders while it
// may still remove them, and clears their slots before freeing the strings). More outputs at
// once than slots would go unlisted, and an interrupt would leave them: the tables hold the
// most any command makes (`preview --turntable` up to 3600 frames; with 256 slots an
// interrupted 3600-frame turntable had left 115 temporaries), 64 kB each.
constexpr int kSlots = 8192;
std::atomic<const char*> g_files[kSlots];
std::atomic<const char*> g_folders[kSlots];

void remove_listed_and_reraise(int sig) {
  const int saved = errno;
  for (auto& f : g_files)
    if (const char* p = f.load()) ::unlink(p);
  // Folders after their files; nested new folders empty from the inside out, so passes
  // repeat while one goes (a removed one fails the next time: the loop ends).
  for (bool removed = true; removed;) {
    removed = false;
    for (auto& f : g_folders)
      if (const char* p = f.load(); p && ::rmdir(p) == 0) removed = true;
  }
  errno = saved;
  ::signal(sig, SIG_DFL);
  ::raise(sig);
}

}  // namespace

OutputSet::Listed::Listed(const fs::path& path, bool folder) : path_(path.string()), folder_(folder) {
  auto& table = folder ? g_folders : g_files;
  for (int i = 0; i < kSlots; ++i) {
    const char* expected = nullptr;
    if (table[i].compare_exchange_strong(expected, path_.c_str())) {
      slot_ = i;
      return;
    }
  }
}

OutputSet::Listed::~Listed() {
  if (slot_ >= 0) (folder_ ? g_folders : g_files)[slot_].store(nullptr);
}

void remove_outputs_on_signals() {
  struct sigaction action {};
  action.sa_handler = remove_listed_and_reraise;
  sigemptyset(&action.sa_mask);
  for (int sig : {SIGINT, SIGTERM, SIGHUP}) ::sigaction(sig, &action, nullptr);
}

OutputSet::~OutputSet() {
  if (committed_) return;
  std::error_code ec;
  for (const auto& e : entries_) fs::remove(e.temp, ec);
  // Folders this set created, deepest first, if nothing else was put in them.
  for (auto it = created_folders_.rbegin(); it != created_folders_.rend(); ++it) {
    if (fs::is_empty((*it)->path(), ec)) fs::remove((*it)->path(), ec);
  }
}

fs::path OutputSet::add(const fs::path& final_path) {
  std::error_code ec;
  if (fs::is_directory(final_path, ec)) throw UsageError(final_path.string() + ": is a folder, not an output file");
  if (!final_path.has_filename()) throw UsageError(final_path.string() + ": names a folder (a trailing /), not an output file");
  // Two outputs of one run under one name: the second would silently replace the first.
  const fs::path same = fs::weakly_canonical(fs::absolute(final_path, ec), ec);
  if (canonical_finals_.count(same)) throw UsageError(final_path.string() + ": named for two outputs of this run");
  const fs::path parent = final_path.has_parent_path() ? final_path.parent_path() : fs::path(".");
  for (fs::path p = parent; !p.empty(); p = p.parent_path()) {
    if (fs::exists(p, ec) && !fs::is_directory(p, ec)) throw UsageError(p.string() + ": is a file, not a folder");
    if (p == p.parent_path()) break;
  }
  // Remember which ancestors do not exist yet, outermost first, before creating them.
  std::vector<fs::path> missing;
  for (fs::path p = parent; !p.empty() && !fs::exists(p, ec); p = p.parent_path()) {
    missing.insert(missing.begin(), p);
    if (p == p.parent_path()) break;
  }
  fs::create_directories(parent, ec);
  if (ec) throw UsageError(parent.string() + ": cannot create folder: " + ec.message());
  if (!fs::is_directory(parent)) throw UsageError(parent.string() + ": is not a folder");
  for (const fs::path& p : missing) created_folders_.push_back(std::make_unique<Listed>(p, true));
  const fs::path temp =
      parent / (".meso-tmp-" + std::to_string(::getpid()) + "-" + std::to_string(entries_.size()) + "-" +
                final_path.filename().string());
  // Fail now, naming the user's path and the reason, if the folder takes no new file (a
  // read-only folder, /proc): later the writer would name the temporary file.
  const int fd = ::open(temp.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0644);  // a stale temporary of a dead run with this pid is replaced
  if (fd < 0) throw UsageError(final_path.string() + ": cannot write there: " + std::strerror(errno));
  ::close(fd);
  fs::remove(temp, ec);
  entries_.push_back({temp, final_path, std::make_unique<Listed>(temp, false)});
  canonical_finals_.insert(same);
  return temp;
}

void OutputSet::write_text(const fs::path& final_path, const std::string& text) {
  const fs::path temp = add(final_path);
  std::ofstream f(temp, std::ios::binary);
  f << text;
  f.close();
  if (!f) throw InternalError(final_path.string() + ": cannot write");
}

void OutputSet::commit() {
  for (const auto& e : entries_) {
    if (!fs::exists(e.temp)) throw InternalError(e.final.string() + ": output was not written");
  }
  for (const auto& e : entries_) {
    std::error_code ec;
    fs::rename(e.temp, e.final, ec);
    if (ec) throw InternalError(e.final.string() + ": cannot rename into place: " + ec.message());
  }
  committed_ = true;
  // Renamed: nothing is left for an interrupt to remove.
  for (auto& e : entries_) e.listed.reset();
  created_folders_.clear();
}

}  // namespace meso
