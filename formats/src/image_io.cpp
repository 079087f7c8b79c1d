#include "meso/formats/image_io.hpp"

#include "meso/core/error.hpp"

#include <OpenImageIO/imageio.h>

#include <algorithm>
#include <cmath>
#include <cstdint>

namespace meso {

namespace fs = std::filesystem;

namespace {
constexpr const char* kPrefix = "meso:";

template <typename T>
std::vector<T> quantize(const std::vector<float>& px, float max_value) {
  std::vector<T> out(px.size());
  for (size_t i = 0; i < px.size(); ++i) {
    const float v = std::clamp(px[i], 0.0f, 1.0f);
    out[i] = static_cast<T>(std::lround(v * max_value));
  }
  return out;
}
}  // namespace

Image read_image(const fs::path& path) {
  const std::string name = path.string();
  if (!fs::exists(path)) throw InputError(name, "no such file");
  // meso's images carry straight (unassociated) alpha, as PNG stores it: ask OIIO not to
  // premultiply on read (and not to divide on write), which would also lose precision.
  OIIO::ImageSpec config;
  config.attribute("oiio:UnassociatedAlpha", 1);
  auto in = OIIO::ImageInput::open(name, &config);
  if (!in) {
    std::string err = OIIO::geterror();
    if (err.empty()) err = "not an image file OpenImageIO can read";
    // OIIO messages can span lines; keep the first.
    err = err.substr(0, err.find('\n'));
    throw InputError(name, "cannot read image: " + err);
  }
  const OIIO::ImageSpec& spec = in->spec();
  if (spec.width <= 0 || spec.height <= 0 || spec.nchannels <= 0 || spec.depth > 1)
    throw InputError(name, "unsupported image layout");
  Image img(spec.width, spec.height, spec.nchannels);
  if (!in->read_image(0, 0, 0, spec.nchannels, OIIO::TypeDesc::FLOAT, img.pixels.data())) {
    std::string err = in->geterror();
    throw InputError(name, "cannot read image data: " + err.substr(0, err.find('\n')));
  }
  for (const auto& p : spec.extra_attribs) {
    const std::string key = p.name().string();
    if (key.rfind(kPrefix, 0) != 0) continue;
    const std::string k = key.substr(std::char_traits<char>::length(kPrefix));
    if (p.type() == OIIO::TypeDesc::FLOAT) img.metadata[k] = p.get_float();
    else if (p.type() == OIIO::TypeDesc::INT) img.metadata[k] = p.get_int();
    else img.metadata[k] = p.get_string();
  }
  in->close();
  for (float v : img.pixels) {
    if (!std::isfinite(v)) throw InputError(name, "image contains NaN or infinite samples");
  }
  return img;
}

void write_image(const Image& image, const fs::path& path, PixelFormat format) {
  const std::string name = path.string();
  if (image.empty()) throw InternalError(name + ": refusing to write an empty image");
  for (float v : image.pixels) {
    if (std::isnan(v)) throw InternalError(name + ": image has NaN samples (a bug in meso)");
  }
  auto out = OIIO::ImageOutput::create(name);
  if (!out) throw InternalError(name + ": no image writer for this extension");
  OIIO::TypeDesc type = OIIO::TypeDesc::FLOAT;
  switch (format) {
    case PixelFormat::float32: type = OIIO::TypeDesc::FLOAT; break;
    case PixelFormat::half: type = OIIO::TypeDesc::HALF; break;
    case PixelFormat::uint8: type = OIIO::TypeDesc::UINT8; break;
    case PixelFormat::uint16: type = OIIO::TypeDesc::UINT16; break;
  }
  OIIO::ImageSpec spec(image.width, image.height, image.channels, type);
  spec.attribute("oiio:UnassociatedAlpha", 1);
  if (format == PixelFormat::float32 || format == PixelFormat::half) spec.attribute("compression", "zip");
  // No timestamps in headers: outputs must be byte-identical across runs. OIIO's EXR writer
  // stamps the current time into capDate unless DateTime is given; an empty one writes none.
  spec.attribute("DateTime", "");
  for (const auto& [k, v] : image.metadata) {
    const std::string key = std::string(kPrefix) + k;
    if (const int* i = std::get_if<int>(&v)) spec.attribute(key, *i);
    else if (const float* f = std::get_if<float>(&v)) spec.attribute(key, *f);
    else spec.attribute(key, std::get<std::string>(v));
  }
  if (!out->open(name, spec)) throw InternalError(name + ": cannot open for writing: " + out->geterror());
  bool ok = false;
  if (format == PixelFormat::uint8) {
    auto q = quantize<uint8_t>(image.pixels, 255.0f);
    ok = out->write_image(OIIO::TypeDesc::UINT8, q.data());
  } else if (format == PixelFormat::uint16) {
    auto q = quantize<uint16_t>(image.pixels, 65535.0f);
    ok = out->write_image(OIIO::TypeDesc::UINT16, q.data());
  } else {
    ok = out->write_image(OIIO::TypeDesc::FLOAT, image.pixels.data());
  }
  if (!ok || !out->close()) throw InternalError(name + ": cannot write image: " + out->geterror());
}

}  // namespace meso
