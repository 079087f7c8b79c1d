// Image files through OpenImageIO. Reads PNG, TIFF, EXR, JPEG (anything OIIO reads);
// writes EXR (float32 or half) and PNG (8 or 16 bit). Metadata round-trip as header
// attributes, names prefixed "meso:" in the file. Alpha is straight (not premultiplied).
#pragma once

#include "meso/core/image.hpp"

#include <filesystem>

namespace meso {

enum class PixelFormat { float32, half, uint8, uint16 };

// Reads any image OIIO understands into float samples (integer formats map to [0,1]).
// Throws InputError naming the file if it is missing, unreadable or not an image.
Image read_image(const std::filesystem::path& path);

// Writes `image` to `path`; the format follows the extension (.exr, .png, .tif). Integer
// formats clamp to [0,1] and round to nearest. NaN samples are a bug: throws InternalError
// rather than writing one. Not atomic by itself: pass a path from OutputSet::add().
void write_image(const Image& image, const std::filesystem::path& path, PixelFormat format);

}  // namespace meso
