#include "meso/formats/atomic_file.hpp"

#include "meso/core/error.hpp"

#include <unistd.h>

#include <fstream>
#include <string>
#include <system_error>

namespace meso {

namespace fs = std::filesystem;

OutputSet::~OutputSet() {
  if (committed_) return;
  std::error_code ec;
  for (const auto& e : entries_) fs::remove(e.temp, ec);
  // Folders this set created, deepest first, if nothing else was put in them.
  for (auto it = created_folders_.rbegin(); it != created_folders_.rend(); ++it) {
    if (fs::is_empty(*it, ec)) fs::remove(*it, ec);
  }
}

fs::path OutputSet::add(const fs::path& final_path) {
  std::error_code ec;
  if (fs::is_directory(final_path, ec)) throw UsageError(final_path.string() + ": is a folder, not an output file");
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
  if (ec) throw InternalError(parent.string() + ": cannot create folder: " + ec.message());
  if (!fs::is_directory(parent)) throw UsageError(parent.string() + ": is not a folder");
  created_folders_.insert(created_folders_.end(), missing.begin(), missing.end());
  const fs::path temp =
      parent / (".meso-tmp-" + std::to_string(::getpid()) + "-" + std::to_string(entries_.size()) + "-" +
                final_path.filename().string());
  entries_.push_back({temp, final_path});
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
}

}  // namespace meso
