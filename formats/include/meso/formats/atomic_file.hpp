// All-or-nothing output: files are written under temporary names in their target folder
// and renamed into place only when every one of them is complete, so a failed run leaves
// no partial output (the rename is atomic on POSIX file systems).
#pragma once

#include <filesystem>
#include <memory>
#include <set>
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
  // A temporary file or a created folder, listed for remove_outputs_on_signals() while the
  // set may still remove it (its own copy of the path: the table holds a pointer to it).
  class Listed {
   public:
    explicit Listed(const std::filesystem::path& path, bool folder);
    ~Listed();
    Listed(const Listed&) = delete;
    Listed& operator=(const Listed&) = delete;
    const std::string& path() const { return path_; }

   private:
    std::string path_;
    bool folder_;
    int slot_ = -1;  // -1: the table was full, not listed
  };
  struct Entry {
    std::filesystem::path temp, final;
    std::unique_ptr<Listed> listed;
  };
  std::vector<Entry> entries_;
  // The entries' final paths made absolute and canonical, to refuse one named twice (kept:
  // recomputing them for every new output took 97 s of file-system calls for 3,600).
  std::set<std::filesystem::path> canonical_finals_;
  std::vector<std::unique_ptr<Listed>> created_folders_;  // deepest last
  bool committed_ = false;
};

// Installs handlers for SIGINT, SIGTERM and SIGHUP that remove the temporaries of every
// OutputSet not yet committed, and the folders they created if empty, then end the process
// by the same signal (its default action): an interrupted run leaves no partial output
// behind, as a failed one. For programs (apps/meso's main), once, before any work; a
// library never installs it. The handler only reads a fixed table and calls unlink/rmdir
// (async-signal-safe).
void remove_outputs_on_signals();

}  // namespace meso
