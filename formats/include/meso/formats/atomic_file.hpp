// All-or-nothing output: files are written under temporary names in their target folder
// and renamed into place only when every one of them is complete, so a failed run leaves
// no partial output (the rename is atomic on POSIX file systems).
#pragma once

#include <filesystem>
#include <vector>

namespace meso {

class OutputSet {
 public:
  OutputSet() = default;
  OutputSet(const OutputSet&) = delete;
  OutputSet& operator=(const OutputSet&) = delete;
  ~OutputSet();  // removes every temporary not committed

  // Registers `final_path` and returns the temporary path to write it to. The temporary
  // keeps the extension (image and mesh writers choose the format by it) and is hidden
  // (".meso-tmp-<pid>-<name>"). Creates the parent folder if needed.
  std::filesystem::path add(const std::filesystem::path& final_path);

  // Renames every temporary to its final name. Throws InternalError on failure.
  void commit();

 private:
  struct Entry {
    std::filesystem::path temp, final;
  };
  std::vector<Entry> entries_;
  bool committed_ = false;
};

}  // namespace meso
