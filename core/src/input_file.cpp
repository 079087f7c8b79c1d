#include "meso/core/input_file.hpp"

#include "meso/core/error.hpp"

namespace meso {

void require_input_file(const std::filesystem::path& path, const std::string& what) {
  std::error_code ec;
  const auto status = std::filesystem::status(path, ec);
  if (ec && ec != std::errc::no_such_file_or_directory) throw InputError(path.string(), "cannot be read (" + ec.message() + ")");
  if (!std::filesystem::exists(status)) throw InputError(path.string(), "no such file");
  if (std::filesystem::is_directory(status)) throw InputError(path.string(), "is a folder, not " + what);
  if (!std::filesystem::is_regular_file(status)) throw InputError(path.string(), "is not a regular file (a pipe, socket or device)");
}

}  // namespace meso
