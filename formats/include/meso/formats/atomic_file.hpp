// All-or-nothing output: files are written under temporary names in their target folder
// and renamed into place only when every one of them is complete, so a failed run leaves
// no partial output (the rename is atomic on POSIX file systems).
#pragma once

#include <filesystem>
#include <string>
#include <vector>

namespace meso {

// The name a user gave for a path OutputSet::add() returned (".meso-tmp-<pid>-<n>-<name>"
// beside it), for messages: the temporary is never seen. Other paths come back unchanged.
inline std::string shown_output_name(const std::string& name) {
  const std::filesystem::path p(name);
  const std::string file = p.filename().string(), prefix = ".meso-tmp-";
  if (file.rfind(prefix, 0) != 0) return name;
  size_t at = prefix.size();
  for (int dash = 0; dash < 2 && at != std::string::npos; ++dash) at = file.find('-', at) + 1;  // past <pid>- and <n>-
  return at == std::string::npos || at == 0 ? name : (p.parent_path() / file.substr(at)).string();
}

class OutputSet {
 public:
  OutputSet() = default;
  OutputSet(const OutputSet&) = delete;
  OutputSet& operator=(const OutputSet&) = delete;
  ~OutputSet();  // removes every temporary not committed

  // Registers `final_path` and returns the temporary path to write it to. The temporary
  // keeps the extension (image and mesh writers choose the format by it) and is hidden
  // (".meso-tmp-<pid>-<n>-<name>"). Creates missing parent folders, and removes them again
  // if the set is never committed. Throws UsageError if `final_path` is an existing folder or
  // ends in a separator, was already added (two outputs under one name), or its folder
  // takes no new file (checked by creating the temporary and removing it again).
  std::filesystem::path add(const std::filesystem::path& final_path);

  // add() and write `text` to the temporary, checking that the write and close succeeded.
  void write_text(const std::filesystem::path& final_path, const std::string& text);

  // Renames every temporary to its final name. Every final path was checked by add(), so a
  // failure here means the file system failed under us (InternalError); files renamed
  // before it stay renamed.
  void commit();

 private:
  struct Entry {
    std::filesystem::path temp, final;
  };
  std::vector<Entry> entries_;
  std::vector<std::filesystem::path> created_folders_;  // deepest last
  bool committed_ = false;
};

}  // namespace meso
