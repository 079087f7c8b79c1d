// image_io.hpp's functions: each forwards to the OpenImageIO module (image_io_backend.hpp),
// opened on first use.
#include "image_io_backend.hpp"

#include "meso/core/error.hpp"
#include "meso/core/input_file.hpp"

#include <dlfcn.h>

#include <cctype>
#include <cstdlib>
#include <string>

namespace meso {

namespace {

// The module's path: MESO_IMAGE_MODULE from the environment (a relocated installation), else
// where the build put it (MESO_IMAGE_MODULE_PATH, set by formats/CMakeLists.txt).
const ImageIoBackend& backend() {
  static const ImageIoBackend* const table = [] {
    const char* env = std::getenv("MESO_IMAGE_MODULE");
    const std::string path = env && *env ? env : MESO_IMAGE_MODULE_PATH;
    void* module = ::dlopen(path.c_str(), RTLD_NOW | RTLD_LOCAL);
    if (!module) {
      const char* why = ::dlerror();
      throw InternalError("cannot load meso's image module " + path + ": " + (why ? why : "unknown error"));
    }
    using Entry = const ImageIoBackend* (*)();
    const auto entry = reinterpret_cast<Entry>(::dlsym(module, "meso_image_io_backend_v1"));
    if (!entry) throw InternalError(path + ": not meso's image module (no meso_image_io_backend_v1)");
    return entry();
  }();
  return *table;
}

}  // namespace

bool is_writable_image_extension(const std::filesystem::path& path) {
  std::string e = path.extension().string();
  for (char& c : e) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return e == ".png" || e == ".exr" || e == ".tif" || e == ".tiff";
}

Image read_image(const std::filesystem::path& path) {
  require_input_file(path, "an image");
  return backend().read_image(path);
}

void write_image(const Image& image, const std::filesystem::path& path, PixelFormat format) {
  backend().write_image(image, path, format);
}

void write_image_levels(const std::vector<Image>& levels, const std::filesystem::path& path, PixelFormat format) {
  backend().write_image_levels(levels, path, format);
}

std::vector<Image> read_image_levels(const std::filesystem::path& path) {
  require_input_file(path, "an image");
  return backend().read_image_levels(path);
}

void write_image_parts(const std::vector<Image>& parts, const std::filesystem::path& path, PixelFormat format) {
  backend().write_image_parts(parts, path, format);
}

std::vector<Image> read_image_parts(const std::filesystem::path& path) {
  require_input_file(path, "an image");
  return backend().read_image_parts(path);
}

}  // namespace meso
