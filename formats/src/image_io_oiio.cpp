// The image functions of image_io.hpp on OpenImageIO, built as a loadable module (see
// image_io_backend.hpp for why): the public functions in image_io.cpp forward here.
#include "image_io_backend.hpp"

#include "meso/core/error.hpp"
#include "meso/core/memory.hpp"
#include "meso/formats/atomic_file.hpp"

#include <OpenImageIO/filesystem.h>
#include <OpenImageIO/imageio.h>

#include <fcntl.h>
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdint>
#include <filesystem>
#include <limits>
#include <memory>
#include <optional>
#include <sstream>

namespace meso {

namespace fs = std::filesystem;

// Everything here is internal to the module: it is reached only through the table below.
namespace {
constexpr const char* kPrefix = "meso:";

template <typename T>
std::vector<T> quantize(const LargeVector<float>& px, float max_value) {
  std::vector<T> out(px.size());
  for (size_t i = 0; i < px.size(); ++i) {
    const float v = std::clamp(px[i], 0.0f, 1.0f);
    out[i] = static_cast<T>(std::lround(v * max_value));
  }
  return out;
}


// OpenImageIO 2.4's PNG reader keeps libpng's default error handler, which prints
// "libpng error: ..." to stderr before OIIO reports the same error through geterror(): a
// damaged PNG would get two lines besides meso's one. So while a PNG is opened or decoded,
// stderr points at /dev/null (images are read on the calling thread only; the error itself
// still reaches the user, through geterror()).
class QuietStderr {
 public:
  explicit QuietStderr(bool quiet) {
    if (!quiet) return;
    std::fflush(stderr);
    saved_ = ::dup(2);
    const int null = ::open("/dev/null", O_WRONLY | O_CLOEXEC);
    if (saved_ >= 0 && null >= 0) ::dup2(null, 2);
    if (null >= 0) ::close(null);
  }
  ~QuietStderr() {
    if (saved_ < 0) return;
    std::fflush(stderr);
    ::dup2(saved_, 2);
    ::close(saved_);
  }
  QuietStderr(const QuietStderr&) = delete;
  QuietStderr& operator=(const QuietStderr&) = delete;

 private:
  int saved_ = -1;
};

bool is_png(const fs::path& path) {
  unsigned char magic[4] = {};
  std::FILE* f = std::fopen(path.c_str(), "rb");
  if (!f) return false;
  const size_t n = std::fread(magic, 1, sizeof magic, f);
  std::fclose(f);
  return n == 4 && magic[0] == 0x89 && magic[1] == 'P' && magic[2] == 'N' && magic[3] == 'G';
}

// A PNG is an 8-byte signature and chunks (u32 big-endian length, 4-byte type, data, CRC)
// up to IEND. A file cut short is caught here by walking the chunk headers, before libpng
// meets the end of the data: its error path longjmps over OIIO 2.4's frames (leaking a
// string, which LeakSanitizer reports) and prints to stderr. "" when the chunks are whole.
std::string png_cut_short(const fs::path& path) {
  std::FILE* f = std::fopen(path.c_str(), "rb");
  if (!f) return {};
  const uint64_t size = static_cast<uint64_t>(fs::file_size(path));
  uint64_t at = 8;
  std::string problem = "cut short: no IEND chunk";
  while (at + 12 <= size) {
    unsigned char head[8];
    if (std::fseek(f, static_cast<long>(at), SEEK_SET) != 0 || std::fread(head, 1, 8, f) != 8) break;
    const uint64_t length = (uint64_t{head[0]} << 24) | (uint64_t{head[1]} << 16) | (uint64_t{head[2]} << 8) | head[3];
    const std::string type(reinterpret_cast<const char*>(head + 4), 4);
    if (at + 12 + length > size) {
      problem = "cut short: its " + type + " chunk at byte " + std::to_string(at) + " runs past the end of the file (" +
                std::to_string(size) + " bytes)";
      break;
    }
    if (type == "IEND") {
      problem.clear();
      break;
    }
    at += 12 + length;
  }
  std::fclose(f);
  return problem;
}

std::unique_ptr<OIIO::ImageInput> open_input(const fs::path& path) {
  const std::string name = path.string();
  if (!fs::exists(path)) throw InputError(name, "no such file");  // the readers of image_io.cpp check more first
  // meso's images carry straight (unassociated) alpha, as PNG stores it: ask OIIO not to
  // premultiply on read (and not to divide on write), which would also lose precision.
  OIIO::ImageSpec config;
  config.attribute("oiio:UnassociatedAlpha", 1);
  const bool png = is_png(path);
  if (png) {
    const std::string cut = png_cut_short(path);
    if (!cut.empty()) throw InputError(name, cut);
  }
  std::unique_ptr<OIIO::ImageInput> in;
  {
    const QuietStderr quiet(png);
    in = OIIO::ImageInput::open(name, &config);
  }
  if (!in) {
    std::string err = OIIO::geterror();
    if (err.empty()) err = "not an image file OpenImageIO can read";
    // OIIO messages can span lines; keep the first.
    throw InputError(name, "cannot read image: " + err.substr(0, err.find('\n')));
  }
  return in;
}

// Reads the MIP level the input is positioned at (its current spec).
Image read_level(OIIO::ImageInput& in, const std::string& name, int level, int subimage = 0) {
  const OIIO::ImageSpec& spec = in.spec();
  if (spec.width <= 0 || spec.height <= 0 || spec.nchannels <= 0 || spec.depth > 1)
    throw InputError(name, "unsupported image layout");
  // The header's size is checked before the pixels are allocated from it (a PNG header
  // claiming 65536 x 65536 had run the machine out of memory, exit 4): as floats, more than
  // the machine's memory cannot be read here.
  const double bytes = static_cast<double>(spec.width) * spec.height * spec.nchannels * sizeof(float), memory = physical_memory_bytes();
  if (memory > 0 && bytes > memory) {
    char text[200];
    std::snprintf(text, sizeof text, "its header claims %d x %d pixels of %d channels: %.1f GB as floats, more than this machine's %.1f GB",
                  spec.width, spec.height, spec.nchannels, bytes / 1e9, memory / 1e9);
    throw InputError(name, text);
  }
  Image img(spec.width, spec.height, spec.nchannels);
  bool read = false;
  {
    const QuietStderr quiet(std::string(in.format_name()) == "png");
    read = in.read_image(subimage, level, 0, spec.nchannels, OIIO::TypeDesc::FLOAT, img.pixels.data());
  }
  // A truncated TIFF strip is reported through geterror() while read_image() still returns
  // true, with the missing rows left at zero: any pending error fails the read.
  const std::string err = in.geterror();
  if (!read || !err.empty())
    throw InputError(name, "cannot read image data: " + (err.empty() ? std::string("unknown error") : err.substr(0, err.find('\n'))));
  // TIFF: "meso:key=value" lines of ImageDescription (write_image), as text like PNG's.
  if (std::string(in.format_name()) == "tiff") {
    std::istringstream lines(spec.get_string_attribute("ImageDescription"));
    for (std::string line; std::getline(lines, line);) {
      if (!line.empty() && line.back() == '\r') line.pop_back();  // CRLF, if another tool rewrote it
      const size_t eq = line.find('=');
      if (line.rfind(kPrefix, 0) == 0 && eq != std::string::npos)
        img.metadata[line.substr(std::char_traits<char>::length(kPrefix), eq - std::char_traits<char>::length(kPrefix))] = line.substr(eq + 1);
    }
  }
  for (const auto& p : spec.extra_attribs) {
    const std::string key = p.name().string();
    if (key.rfind(kPrefix, 0) != 0) continue;
    const std::string k = key.substr(std::char_traits<char>::length(kPrefix));
    if (p.type() == OIIO::TypeDesc::FLOAT) img.metadata[k] = p.get_float();
    else if (p.type() == OIIO::TypeDesc::INT) img.metadata[k] = p.get_int();
    else img.metadata[k] = p.get_string();
  }
  for (size_t i = 0; i < img.pixels.size(); ++i) {
    if (std::isfinite(img.pixels[i])) continue;
    const size_t texel = i / static_cast<size_t>(img.channels);
    throw InputError(name, std::string(std::isnan(img.pixels[i]) ? "NaN" : "infinite") + " sample at texel (" +
                               std::to_string(texel % static_cast<size_t>(img.width)) + ", " +
                               std::to_string(texel / static_cast<size_t>(img.width)) + ") channel " +
                               std::to_string(i % static_cast<size_t>(img.channels)) +
                               (level ? " of MIP level " + std::to_string(level) : std::string()));
  }
  return img;
}


// An OpenEXR image whose data window is not its display window (a compositor's auto-crop, or
// overscan) is placed in its display window, the frame the UVs map: samples outside the data
// window are zero (OpenEXR's meaning of "no data"), and data outside the display window is
// cut away. Without this a cropped map was read at the crop's size and stretched over the
// whole UV square. Only OpenEXR: OIIO reports a PNG's oFFs (or a TIFF's position) as a data
// window offset with a display window of the data's own size at the origin, which would
// shift the image out of its frame; those offsets are placements on a page, not crops.
Image in_display_window(Image data, const OIIO::ImageSpec& spec, const std::string& name) {
  if (spec.x == spec.full_x && spec.y == spec.full_y && spec.width == spec.full_width && spec.height == spec.full_height) return data;
  if (spec.full_width <= 0 || spec.full_height <= 0) return data;  // no display window recorded
  // Both images are held while the data is placed.
  const double bytes = (static_cast<double>(spec.full_width) * spec.full_height + static_cast<double>(data.width) * data.height) *
                       data.channels * sizeof(float);
  const double memory = physical_memory_bytes();
  if (memory > 0 && bytes > memory) {
    char text[200];
    std::snprintf(text, sizeof text, "placing its data in its display window of %d x %d pixels of %d channels needs %.1f GB as floats, more than this machine's %.1f GB",
                  spec.full_width, spec.full_height, data.channels, bytes / 1e9, memory / 1e9);
    throw InputError(name, text);
  }
  Image out(spec.full_width, spec.full_height, data.channels, 0.0f);
  out.metadata = std::move(data.metadata);
  // Data pixel (x, y) is display pixel (x + spec.x - full_x, y + spec.y - full_y); 64-bit
  // arithmetic, since the offsets are any int.
  const int64_t dx = static_cast<int64_t>(spec.x) - spec.full_x, dy = static_cast<int64_t>(spec.y) - spec.full_y;
  const int64_t x0 = std::max<int64_t>(0, -dx), x1 = std::min<int64_t>(data.width, out.width - dx);
  const int64_t y0 = std::max<int64_t>(0, -dy), y1 = x0 < x1 ? std::min<int64_t>(data.height, out.height - dy) : y0;
  const size_t c = static_cast<size_t>(data.channels);
  for (int64_t y = y0; y < y1; ++y) {
    const float* from = &data.pixels[(static_cast<size_t>(y) * static_cast<size_t>(data.width) + static_cast<size_t>(x0)) * c];
    float* to = &out.pixels[(static_cast<size_t>(y + dy) * static_cast<size_t>(out.width) + static_cast<size_t>(x0 + dx)) * c];
    std::copy(from, from + static_cast<size_t>(x1 - x0) * c, to);
  }
  return out;
}

Image read_image(const fs::path& path) {
  auto in = open_input(path);
  Image data = read_level(*in, path.string(), 0);
  if (std::string(in->format_name()) != "openexr") return data;
  return in_display_window(std::move(data), in->spec(), path.string());
}


OIIO::TypeDesc type_of(PixelFormat format) {
  switch (format) {
    case PixelFormat::half: return OIIO::TypeDesc::HALF;
    case PixelFormat::uint8: return OIIO::TypeDesc::UINT8;
    case PixelFormat::uint16: return OIIO::TypeDesc::UINT16;
    case PixelFormat::float32: break;
  }
  return OIIO::TypeDesc::FLOAT;
}

// The file's own name for messages (an OutputSet's temporary is never seen).
std::string shown_name(const std::string& name) { return shown_output_name(name); }

// No map meso writes holds NaN or Inf ("never write NaN into a map"), nor, in half, a value
// that half would turn into Inf: either is a bug upstream, refused before a byte is written.
void check_writable(const Image& image, const std::string& name, PixelFormat format) {
  if (image.empty()) throw InternalError(shown_name(name) + ": refusing to write an empty image");
  const float limit = format == PixelFormat::half ? 65504.0f : std::numeric_limits<float>::max();
  for (float v : image.pixels) {
    if (!(std::abs(v) <= limit))
      throw InternalError(shown_name(name) + ": image has " + (std::isnan(v) ? "NaN" : "infinite") + " samples" +
                          (std::isfinite(v) ? " in half floats" : "") + " (a bug in meso)");
  }
}

OIIO::ImageSpec spec_of(const Image& image, PixelFormat format, const ImageMetadata& metadata, bool text_only = false, bool numbered = false) {
  OIIO::ImageSpec spec(image.width, image.height, image.channels, type_of(format));
  // Beyond RGBA (or when asked, for more than one channel), name channels so that their
  // sorted order (EXR stores channels sorted by name) is their index order: c000, c001, ...
  if (image.channels > 4 || (numbered && image.channels > 1)) {
    spec.channelnames.clear();
    char name[16];
    for (int c = 0; c < image.channels; ++c) {
      std::snprintf(name, sizeof name, "c%03d", c);
      spec.channelnames.emplace_back(name);
    }
  }
  spec.attribute("oiio:UnassociatedAlpha", 1);
  if (format == PixelFormat::float32 || format == PixelFormat::half) spec.attribute("compression", "zip");
  // No timestamps in headers: outputs must be byte-identical across runs. OIIO's EXR writer
  // stamps the current time into capDate unless DateTime is given; an empty one writes none.
  spec.attribute("DateTime", "");
  for (const auto& [k, v] : metadata) {
    const std::string key = std::string(kPrefix) + k;
    if (text_only) {
      // PNG keeps text chunks only: numbers as text, floats round-trippable ("%.9g").
      char buffer[32];
      if (const int* i = std::get_if<int>(&v)) spec.attribute(key, std::to_string(*i));
      else if (const float* f = std::get_if<float>(&v)) {
        std::snprintf(buffer, sizeof buffer, "%.9g", static_cast<double>(*f));
        spec.attribute(key, std::string(buffer));
      } else spec.attribute(key, std::get<std::string>(v));
    } else if (const int* i = std::get_if<int>(&v)) spec.attribute(key, *i);
    else if (const float* f = std::get_if<float>(&v)) spec.attribute(key, *f);
    else spec.attribute(key, std::get<std::string>(v));
  }
  return spec;
}

bool write_pixels(OIIO::ImageOutput& out, const Image& image, PixelFormat format) {
  if (format == PixelFormat::uint8) {
    auto q = quantize<uint8_t>(image.pixels, 255.0f);
    return out.write_image(OIIO::TypeDesc::UINT8, q.data());
  }
  if (format == PixelFormat::uint16) {
    auto q = quantize<uint16_t>(image.pixels, 65535.0f);
    return out.write_image(OIIO::TypeDesc::UINT16, q.data());
  }
  return out.write_image(OIIO::TypeDesc::FLOAT, image.pixels.data());
}

// Some of OIIO's writers do not see a failed write: its PNG writer closes a file truncated by
// a full disk as if complete, and OpenEXR 3.1's tiled writer never returns (its tile tasks'
// semaphore is never posted after a failed write). Those write through this file, which
// remembers a failed write and tells the writer it succeeded, so the writer runs to its end
// and finish() reports whether every byte reached the file.
class CheckedFile final : public OIIO::Filesystem::IOFile {
 public:
  explicit CheckedFile(const std::string& name) : IOFile(name, Write), name_(name) {
    if (!opened()) throw InternalError(shown_name(name) + ": cannot open for writing");
  }
  size_t write(const void* buf, size_t size) override { return note(IOFile::write(buf, size), size); }
  size_t pwrite(const void* buf, size_t size, int64_t offset) override { return note(IOFile::pwrite(buf, size, offset), size); }
  // The writer for the file's extension, writing here.
  std::unique_ptr<OIIO::ImageOutput> create() {
    auto out = OIIO::ImageOutput::create(name_, this);
    if (out && !out->supports("ioproxy")) throw InternalError(shown_name(name_) + ": this image writer cannot write through meso's checked file");
    return out;
  }
  // After the writer is closed and destroyed (OpenEXR writes a tiled file's offset table
  // when its file object is destroyed).
  void finish() {
    if (std::fflush(handle()) != 0) failed_ = true;
    close();
    if (failed_) throw InternalError(shown_name(name_) + ": write failed (is the disk full?)");
  }

 private:
  size_t note(size_t done, size_t size) {
    if (done != size) failed_ = true;
    return size;
  }
  std::string name_;
  bool failed_ = false;
};

void write_image(const Image& image, const fs::path& path, PixelFormat format) {
  const std::string name = path.string();
  check_writable(image, name, format);
  std::string extension = path.extension().string();
  std::transform(extension.begin(), extension.end(), extension.begin(), [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  const bool png = extension == ".png";
  std::optional<CheckedFile> checked;
  if (png) checked.emplace(name);
  auto out = png ? checked->create() : OIIO::ImageOutput::create(name);
  if (!out) throw InternalError(shown_name(name) + ": no image writer for this extension");
  const bool tiff = extension == ".tif" || extension == ".tiff";
  OIIO::ImageSpec spec = spec_of(image, format, image.metadata, png || tiff);
  if (tiff) {
    // TIFF has no free-form attributes (OIIO drops them): the metadata goes into the
    // ImageDescription tag as "meso:key=value" lines, which read_level() parses back.
    std::string description;
    for (const auto& p : spec.extra_attribs) {
      const std::string key = p.name().string();
      if (key.rfind(kPrefix, 0) != 0) continue;
      std::string value = p.get_string();
      std::replace(value.begin(), value.end(), '\n', ' ');  // one line per key
      description += key + "=" + value + "\n";
    }
    for (const auto& [k, v] : image.metadata) spec.erase_attribute(std::string(kPrefix) + k);
    if (!description.empty()) spec.attribute("ImageDescription", description);
  }
  if (!out->open(name, spec)) throw InternalError(shown_name(name) + ": cannot open for writing: " + out->geterror());
  if (!write_pixels(*out, image, format) || !out->close()) throw InternalError(shown_name(name) + ": cannot write image: " + out->geterror());
  if (png) {
    out.reset();
    checked->finish();
  }
}

void write_image_levels(const std::vector<Image>& levels, const fs::path& path, PixelFormat format) {
  const std::string name = path.string();
  if (levels.empty()) throw InternalError(shown_name(name) + ": no levels to write");
  for (size_t k = 0; k < levels.size(); ++k) {
    check_writable(levels[k], name, format);
    if (levels[k].channels != levels[0].channels) throw InternalError(shown_name(name) + ": levels differ in channel count");
    if (k > 0 && (levels[k].width != std::max(1, levels[k - 1].width / 2) || levels[k].height != std::max(1, levels[k - 1].height / 2)))
      throw InternalError(shown_name(name) + ": level sizes do not halve (rounding down) from one level to the next");
  }
  if (format != PixelFormat::float32 && format != PixelFormat::half) throw InternalError(shown_name(name) + ": MIP levels are written as EXR only");
  CheckedFile checked(name);  // a tiled EXR (see CheckedFile)
  auto out = checked.create();
  if (!out || !out->supports("mipmap")) throw InternalError(shown_name(name) + ": this format cannot hold MIP levels (use .exr)");
  for (size_t k = 0; k < levels.size(); ++k) {
    OIIO::ImageSpec spec = spec_of(levels[k], format, k == 0 ? levels[0].metadata : ImageMetadata{});
    // A tiled, MIP-mapped EXR (OpenEXR's MIPMAP_LEVELS, rounding down).
    spec.tile_width = spec.tile_height = 64;
    spec.attribute("openexr:levelmode", 1);
    spec.attribute("textureformat", "Plain Texture");
    const auto mode = k == 0 ? OIIO::ImageOutput::Create : OIIO::ImageOutput::AppendMIPLevel;
    if (!out->open(name, spec, mode)) throw InternalError(shown_name(name) + ": cannot open for writing: " + out->geterror());
    if (!write_pixels(*out, levels[k], format)) throw InternalError(shown_name(name) + ": cannot write level " + std::to_string(k) + ": " + out->geterror());
  }
  if (!out->close()) throw InternalError(shown_name(name) + ": cannot write image: " + out->geterror());
  out.reset();
  checked.finish();
}

std::vector<Image> read_image_levels(const fs::path& path) {
  auto in = open_input(path);
  std::vector<Image> levels{read_level(*in, path.string(), 0)};
  for (int k = 1; in->seek_subimage(0, k); ++k) levels.push_back(read_level(*in, path.string(), k));
  return levels;
}

void write_image_parts(const std::vector<Image>& parts, const fs::path& path, PixelFormat format) {
  const std::string name = path.string();
  for (const Image& part : parts) check_writable(part, name, format);
  if (format != PixelFormat::float32 && format != PixelFormat::half) throw InternalError(shown_name(name) + ": parts are written as EXR only");
  auto out = OIIO::ImageOutput::create(name);
  if (!out || !out->supports("multiimage")) throw InternalError(shown_name(name) + ": this format cannot hold several parts (use .exr)");
  std::vector<OIIO::ImageSpec> specs;
  // OpenEXR requires every part to share the display window: the largest part's extent.
  int full_w = 0, full_h = 0;
  for (const Image& part : parts) {
    full_w = std::max(full_w, part.width);
    full_h = std::max(full_h, part.height);
  }
  for (const Image& part : parts) {
    specs.push_back(spec_of(part, format, part.metadata, false, true));
    specs.back().full_x = specs.back().full_y = 0;
    specs.back().full_width = full_w;
    specs.back().full_height = full_h;
  }
  if (!out->open(name, static_cast<int>(specs.size()), specs.data())) throw InternalError(shown_name(name) + ": cannot open for writing: " + out->geterror());
  for (size_t k = 0; k < parts.size(); ++k) {
    if (k > 0 && !out->open(name, specs[k], OIIO::ImageOutput::AppendSubimage))
      throw InternalError(shown_name(name) + ": cannot add part " + std::to_string(k) + ": " + out->geterror());
    if (!write_pixels(*out, parts[k], format)) throw InternalError(shown_name(name) + ": cannot write part " + std::to_string(k) + ": " + out->geterror());
  }
  if (!out->close()) throw InternalError(shown_name(name) + ": cannot write image: " + out->geterror());
}

std::vector<Image> read_image_parts(const fs::path& path) {
  auto in = open_input(path);
  std::vector<Image> parts{read_level(*in, path.string(), 0, 0)};
  for (int k = 1; in->seek_subimage(k, 0); ++k) parts.push_back(read_level(*in, path.string(), 0, k));
  return parts;
}

// The table of the functions above (the public names of image_io.hpp are declared too, but
// only in the program that opens this module).
const ImageIoBackend kBackend = {read_image,        write_image,       write_image_levels,
                                 read_image_levels, write_image_parts, read_image_parts};

}  // namespace

}  // namespace meso

extern "C" MESO_IMAGE_BACKEND_EXPORT const meso::ImageIoBackend* meso_image_io_backend_v1() { return &meso::kBackend; }
