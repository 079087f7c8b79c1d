// Image files through OpenImageIO. Reads PNG, TIFF, EXR, JPEG (anything OIIO reads);
// writes EXR (float32 or half) and PNG (8 or 16 bit). Metadata round-trip as header
// attributes, names prefixed "meso:" in the file. Alpha is straight (not premultiplied).
#pragma once

#include "meso/core/image.hpp"

#include <filesystem>
#include <vector>

namespace meso {

enum class PixelFormat { float32, half, uint8, uint16 };

// Reads any image OIIO understands into float samples (integer formats map to [0,1]). An
// OpenEXR image is read at the size of its display window: where the data window differs (a
// cropped EXR, overscan), samples outside it read 0 and data outside the display window is
// dropped. Other formats' page offsets (a PNG's oFFs) are ignored.
// Throws InputError naming the file if it is missing, unreadable or not an image.
Image read_image(const std::filesystem::path& path);

// Whether write_image takes this file name: .png, .exr, .tif or .tiff (any case). The
// commands check the names a user gives before any work.
bool is_writable_image_extension(const std::filesystem::path& path);

// Writes `image` to `path`; the format follows the extension (.exr, .png, .tif). Integer
// formats clamp to [0,1] and round to nearest. NaN samples are a bug: throws InternalError
// rather than writing one. Not atomic by itself: pass a path from OutputSet::add().
void write_image(const Image& image, const std::filesystem::path& path, PixelFormat format);

// Writes a MIP chain as one tiled, MIP-mapped EXR (OpenEXR MIPMAP_LEVELS, sizes rounding
// down, as OpenGL's). Level k+1 must be max(1, floor(level k / 2)) per side. The metadata of
// levels[0] goes into the header. Channels are named by OIIO's defaults (R, G, B, A, ...).
void write_image_levels(const std::vector<Image>& levels, const std::filesystem::path& path, PixelFormat format);

// Reads every MIP level of an image file (one level for files without MIP maps).
std::vector<Image> read_image_levels(const std::filesystem::path& path);

// Writes several images as the parts of one multi-part EXR (OpenEXR multi-part, OIIO
// subimages), in order, each with its own size, channels and metadata. A part's channels are
// named c000, c001, ... (sorted by name, as EXR stores them, in index order), whatever
// their count; a part of one channel is Y.
void write_image_parts(const std::vector<Image>& parts, const std::filesystem::path& path, PixelFormat format);

// Reads every part of a multi-part image file (one part for ordinary files).
std::vector<Image> read_image_parts(const std::filesystem::path& path);

}  // namespace meso
