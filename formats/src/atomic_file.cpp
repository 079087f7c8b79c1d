#include "meso/formats/atomic_file.hpp"

#include "meso/core/error.hpp"

#include <unistd.h>

#include <string>
#include <system_error>

namespace meso {

namespace fs = std::filesystem;

OutputSet::~OutputSet() {
  if (committed_) return;
  for (const auto& e : entries_) {
    std::error_code ec;
    fs::remove(e.temp, ec);
  }
}

fs::path OutputSet::add(const fs::path& final_path) {
  const fs::path parent = final_path.has_parent_path() ? final_path.parent_path() : fs::path(".");
  std::error_code ec;
  fs::create_directories(parent, ec);
  if (ec) throw InternalError(parent.string() + ": cannot create folder: " + ec.message());
  const fs::path temp =
      parent / (".meso-tmp-" + std::to_string(::getpid()) + "-" + std::to_string(entries_.size()) + "-" +
                final_path.filename().string());
  entries_.push_back({temp, final_path});
  return temp;
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
