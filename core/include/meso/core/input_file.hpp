// What every reader checks before it opens an input file.
#pragma once

#include <filesystem>
#include <string>

namespace meso {

// Throws InputError (exit 3) unless `path` names a regular file (or a link to one): "no such
// file", "cannot be read (<the system's reason>)" (a folder on the way that may not be
// searched, a loop of links), "is a folder, not <what>", or "is not a regular file (a pipe,
// socket or device)". A
// FIFO would block the reader until something writes to it, and /dev/zero would be read until
// memory runs out. `what` names the kind of file expected ("a mesh file").
void require_input_file(const std::filesystem::path& path, const std::string& what);

}  // namespace meso
