#include "meso/formats/image_io.hpp"

#include "meso/core/error.hpp"
#include "test_support.hpp"

#include <sys/stat.h>

#include <OpenEXR/ImfChannelList.h>
#include <OpenEXR/ImfHeader.h>
#include <OpenEXR/ImfMultiPartInputFile.h>
#include <OpenEXR/ImfFrameBuffer.h>
#include <OpenEXR/ImfOutputFile.h>
#include <gtest/gtest.h>

#include <limits>

#include <cmath>
#include <ctime>
#include <filesystem>
#include <string>
#include <utility>
#include <vector>

namespace meso {
namespace {

// CRC-32 of a PNG chunk's type and data (PNG's, reflected 0xEDB88320).
uint32_t png_crc(const std::string& type_and_data) {
  uint32_t crc = 0xFFFFFFFFu;
  for (unsigned char byte : type_and_data) {
    crc ^= byte;
    for (int k = 0; k < 8; ++k) crc = (crc >> 1) ^ (0xEDB88320u & (0u - (crc & 1u)));
  }
  return crc ^ 0xFFFFFFFFu;
}

std::string big_endian(uint32_t v) {
  return {static_cast<char>(v >> 24), static_cast<char>((v >> 16) & 0xFF), static_cast<char>((v >> 8) & 0xFF), static_cast<char>(v & 0xFF)};
}

Image ramp(int w, int h, int c) {
  Image img(w, h, c);
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x)
      for (int k = 0; k < c; ++k) img.at(x, y, k) = std::sin(0.37f * float(x) + 0.11f * float(y) + float(k)) * 0.5f + 0.5f;
  return img;
}

TEST(ImageIo, ExrFloatRoundTripIsExactWithMetadata) {
  test::TempDir dir;
  Image img = ramp(37, 19, 1);
  img.pixels[5] = -1234.5f;  // displacement may be negative and large
  img.metadata = {{"units", std::string("object")}, {"scale", 0.25f}, {"levels", 3}};
  write_image(img, dir / "d.exr", PixelFormat::float32);
  const Image back = read_image(dir / "d.exr");
  ASSERT_EQ(back.width, 37);
  ASSERT_EQ(back.height, 19);
  ASSERT_EQ(back.channels, 1);
  EXPECT_EQ(back.pixels, img.pixels);
  EXPECT_EQ(std::get<std::string>(back.metadata.at("units")), "object");
  EXPECT_EQ(std::get<float>(back.metadata.at("scale")), 0.25f);
  EXPECT_EQ(std::get<int>(back.metadata.at("levels")), 3);
}

TEST(ImageIo, MultiPartExrKeepsEachPart) {
  test::TempDir dir;
  Image a(5, 3, 12), b(9, 1, 2);
  for (size_t i = 0; i < a.pixels.size(); ++i) a.pixels[i] = 0.25f * static_cast<float>(i);
  for (size_t i = 0; i < b.pixels.size(); ++i) b.pixels[i] = -1.5f * static_cast<float>(i);
  a.metadata["rank"] = 7;
  b.metadata["what"] = std::string("basis");
  write_image_parts({a, b}, dir / "p.exr", PixelFormat::float32);
  const std::vector<Image> parts = read_image_parts(dir / "p.exr");
  ASSERT_EQ(parts.size(), 2u);
  EXPECT_EQ(parts[0].width, 5);
  EXPECT_EQ(parts[0].channels, 12);
  EXPECT_EQ(parts[0].pixels, a.pixels) << "channels beyond RGBA keep their order";
  EXPECT_EQ(std::get<int>(parts[0].metadata.at("rank")), 7);
  EXPECT_EQ(parts[1].pixels, b.pixels);
  EXPECT_EQ(std::get<std::string>(parts[1].metadata.at("what")), "basis");
}

// A part's channels are c000, c001, ... at any count above one (RGBA's names at four or fewer
// would be stored as A, B, G, R: a reader by name or by stored order would lose the index
// order), and Y alone; read from the file with OpenEXR itself, not through meso's reader.
TEST(ImageIo, MultiPartExrNamesChannelsByIndex) {
  test::TempDir dir;
  Image one(3, 2, 1, 0.5f), three(3, 2, 3, 0.25f), four(4, 1, 4, 1.0f);
  write_image_parts({three, one, four}, dir / "n.exr", PixelFormat::half);
  Imf::MultiPartInputFile file((dir / "n.exr").c_str());
  ASSERT_EQ(file.parts(), 3);
  auto names = [&](int part) {
    std::vector<std::string> out;
    const Imf::ChannelList& list = file.header(part).channels();
    for (auto c = list.begin(); c != list.end(); ++c) out.emplace_back(c.name());
    return out;
  };
  EXPECT_EQ(names(0), (std::vector<std::string>{"c000", "c001", "c002"}));
  EXPECT_EQ(names(1), (std::vector<std::string>{"Y"}));
  EXPECT_EQ(names(2), (std::vector<std::string>{"c000", "c001", "c002", "c003"}));
}

TEST(ImageIo, Png16RoundTripWithinHalfAStep) {
  test::TempDir dir;
  const Image img = ramp(16, 9, 3);
  write_image(img, dir / "n.png", PixelFormat::uint16);
  const Image back = read_image(dir / "n.png");
  ASSERT_EQ(back.channels, 3);
  for (size_t i = 0; i < img.pixels.size(); ++i) EXPECT_NEAR(back.pixels[i], img.pixels[i], 0.5 / 65535.0 + 1e-7);
}

TEST(ImageIo, Png8RoundTripWithinHalfAStep) {
  test::TempDir dir;
  const Image img = ramp(8, 8, 4);
  write_image(img, dir / "o.png", PixelFormat::uint8);
  const Image back = read_image(dir / "o.png");
  for (size_t i = 0; i < img.pixels.size(); ++i) EXPECT_NEAR(back.pixels[i], img.pixels[i], 0.5 / 255.0 + 1e-7);
}

TEST(ImageIo, RowsAreTopFirst) {
  test::TempDir dir;
  Image img(2, 2, 1, 0.0f);
  img.at(0, 0) = 1.0f;  // top-left
  write_image(img, dir / "t.exr", PixelFormat::float32);
  const Image back = read_image(dir / "t.exr");
  EXPECT_EQ(back.at(0, 0), 1.0f);
  EXPECT_EQ(back.at(0, 1), 0.0f);
}

TEST(ImageIo, RefusesToWriteNaN) {
  test::TempDir dir;
  Image img(2, 2, 1, 0.0f);
  img.pixels[3] = std::nanf("");
  EXPECT_THROW(write_image(img, dir / "bad.exr", PixelFormat::float32), InternalError);
}

// Inf too, and in half any value half would store as Inf; the message names the file the user
// asked for, not the temporary it is written under.
TEST(ImageIo, RefusesToWriteInfAndNamesTheOutput) {
  test::TempDir dir;
  Image img(2, 2, 1, 0.0f);
  img.pixels[1] = -std::numeric_limits<float>::infinity();
  EXPECT_THROW(write_image(img, dir / "inf.exr", PixelFormat::float32), InternalError);
  img.pixels[1] = 70000.0f;
  write_image(img, dir / "big.exr", PixelFormat::float32);  // float holds it
  try {
    write_image(img, dir / ".meso-tmp-123-0-big.exr", PixelFormat::half);
    ADD_FAILURE() << "70000 is Inf in half";
  } catch (const InternalError& e) {
    EXPECT_EQ(std::string(e.what()).find(".meso-tmp"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find((dir / "big.exr").string()), std::string::npos) << e.what();
  }
  img.pixels[1] = 65504.0f;
  write_image(img, dir / "edge.exr", PixelFormat::half);
  EXPECT_EQ(read_image(dir / "edge.exr").pixels[1], 65504.0f);
}

TEST(ImageIo, MissingAndGarbageFilesAreInputErrors) {
  test::TempDir dir;
  EXPECT_THROW(read_image(dir / "missing.exr"), InputError);
  test::write_text(dir / "garbage.png", "not a png");
  EXPECT_THROW(read_image(dir / "garbage.png"), InputError);
}

// Files cut short. A float TIFF: libtiff reports the missing strip, but OpenImageIO's
// read_image() still returned true with those rows at zero. A PNG: its chunks are walked
// first (libpng's own error path prints to stderr and, in OIIO 2.4, leaks).
TEST(ImageIo, TruncatedFilesAreInputErrors) {
  test::TempDir dir;
  const std::vector<std::pair<std::string, std::string>> cases = {
      {"cut.tif", "cannot read image data"}, {"cut.exr", "cannot read image data"}, {"cut.png", "cut short: its IDAT chunk"}};
  for (const auto& [name, message] : cases) {
    write_image(ramp(64, 64, 1), dir / name, name == "cut.png" ? PixelFormat::uint16 : PixelFormat::float32);
    EXPECT_NO_THROW(read_image(dir / name)) << name;
    std::filesystem::resize_file(dir / name, std::filesystem::file_size(dir / name) * 2 / 3);
    try {
      read_image(dir / name);
      ADD_FAILURE() << name << ": a truncated image must be refused";
    } catch (const InputError& e) {
      EXPECT_NE(std::string(e.what()).find(message), std::string::npos) << e.what();
    }
  }
}

// A PNG whose compressed data is damaged: libpng's error reaches meso through OIIO, and
// libpng's own lines on stderr are muted (tests/cli_test.cpp checks meso prints one line).
// Not under ASan: OIIO 2.4 leaks a string on libpng's error path.
TEST(ImageIo, DamagedPngIsAnInputError) {
#if defined(__SANITIZE_ADDRESS__)
  GTEST_SKIP() << "OpenImageIO 2.4 leaks on libpng's error path";
#endif
  test::TempDir dir;
  write_image(ramp(64, 64, 1), dir / "bad.png", PixelFormat::uint16);
  std::string bytes = test::read_text(dir / "bad.png");
  const size_t idat = bytes.find("IDAT");
  ASSERT_NE(idat, std::string::npos);
  bytes[idat + 200] = static_cast<char>(bytes[idat + 200] ^ 0x55);
  test::write_text(dir / "bad.png", bytes);
  try {
    read_image(dir / "bad.png");
    ADD_FAILURE() << "a damaged PNG must be refused";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("bad.png: cannot read image data"), std::string::npos) << e.what();
  }
}

// TIFF has no free-form attributes: the metadata travels in ImageDescription and reads back
// as text, as PNG's does (the previewer's 8-bit height TIFF needs its bias and scale).
TEST(ImageIo, TiffKeepsMetadataAsText) {
  test::TempDir dir;
  Image img = ramp(8, 4, 4);
  img.metadata = {{"method", std::string("pom")}, {"height_scale", 0.125f}, {"iterations", 32}};
  write_image(img, dir / "h.tif", PixelFormat::uint8);
  const Image back = read_image(dir / "h.tif");
  ASSERT_EQ(back.metadata.size(), 3u);
  EXPECT_EQ(std::get<std::string>(back.metadata.at("method")), "pom");
  EXPECT_EQ(std::stof(std::get<std::string>(back.metadata.at("height_scale"))), 0.125f);
  EXPECT_EQ(std::get<std::string>(back.metadata.at("iterations")), "32");
  write_image(img, dir / "g.tif", PixelFormat::uint8);
  EXPECT_EQ(test::read_text(dir / "h.tif"), test::read_text(dir / "g.tif"));
  // A line ending in CR, as a description another tool rewrote with CRLF line ends has them,
  // reads the same (the last line's LF turned CR, keeping the file's length and offsets).
  std::string crlf = test::read_text(dir / "h.tif");
  const std::string lf = "meso:method=pom\n";
  const size_t at = crlf.find(lf);
  ASSERT_NE(at, std::string::npos);
  crlf.replace(at, lf.size(), "meso:method=pom\r");  // same length: the TIFF's offsets hold
  test::write_text(dir / "crlf.tif", crlf);
  EXPECT_EQ(std::get<std::string>(read_image(dir / "crlf.tif").metadata.at("method")), "pom");
}

// A full disk: every image writer reports the failed write (exit 4) and returns. /dev/full
// fails every write with ENOSPC; a link to it gives the extension that picks the format.
// (OpenEXR's tiled writer, MIP levels, had waited forever on its tile tasks.)
TEST(ImageIo, AFullDiskFailsEveryWriter) {
  if (!std::filesystem::exists("/dev/full")) GTEST_SKIP() << "no /dev/full";
  test::TempDir dir;
  const Image img = ramp(64, 64, 2);
  auto full = [&](const std::string& name) {
    const auto path = dir / name;
    std::filesystem::create_symlink("/dev/full", path);
    return path;
  };
  auto expect_failure = [](const std::string& what, auto&& write) {
    try {
      write();
      ADD_FAILURE() << what << ": the write to a full disk was reported as done";
    } catch (const Error& e) {
      EXPECT_EQ(e.code(), ExitCode::internal) << what << ": " << e.what();
    }
  };
  expect_failure("levels", [&] { write_image_levels({img, ramp(32, 32, 2), ramp(16, 16, 2)}, full("l.exr"), PixelFormat::float32); });
  expect_failure("parts", [&] { write_image_parts({img, ramp(8, 1, 1)}, full("p.exr"), PixelFormat::half); });
  expect_failure("exr", [&] { write_image(img, full("i.exr"), PixelFormat::float32); });
  expect_failure("png", [&] { write_image(img, full("i.png"), PixelFormat::uint16); });
  expect_failure("tif", [&] { write_image(img, full("i.tif"), PixelFormat::uint8); });
}

TEST(ImageIo, WritesAreDeterministic) {
  test::TempDir dir;
  Image img = ramp(64, 32, 1);
  img.metadata = {{"units", std::string("object")}};
  write_image(img, dir / "a.exr", PixelFormat::float32);
  write_image(img, dir / "b.exr", PixelFormat::float32);
  EXPECT_EQ(test::read_text(dir / "a.exr"), test::read_text(dir / "b.exr"));
  // No clock in the header (two writes within one second would not show it).
  char stamp[16];
  const std::time_t now = std::time(nullptr);
  std::strftime(stamp, sizeof stamp, "%Y:%m:", std::gmtime(&now));
  EXPECT_EQ(test::read_text(dir / "a.exr").find(stamp), std::string::npos);
  write_image(img, dir / "a.png", PixelFormat::uint16);
  write_image(img, dir / "b.png", PixelFormat::uint16);
  EXPECT_EQ(test::read_text(dir / "a.png"), test::read_text(dir / "b.png"));
}

// A PNG whose header claims more pixels than any machine's memory holds as floats (CRC fixed)
// is refused before the pixels are allocated from it (65536 x 65536 had run the machine out
// of memory, exit 4); a pipe or a device in place of an image is refused before it is opened (a FIFO
// had blocked the reader).
TEST(ImageIo, HeadersThatClaimTooMuchAndNonFilesAreRefused) {
  test::TempDir dir;
  write_image(Image(16, 16, 3, 0.5f), dir / "small.png", PixelFormat::uint8);
  std::string png = test::read_text(dir / "small.png");
  ASSERT_EQ(png.substr(12, 4), "IHDR");
  for (size_t i : {16u, 20u}) png.replace(i, 4, std::string("\x00\x0F\x42\x40", 4));  // width, height 1,000,000: 12 TB as floats
  png.replace(29, 4, big_endian(png_crc(png.substr(12, 4 + 13))));
  test::write_text(dir / "huge.png", png);
  try {
    read_image(dir / "huge.png");
    ADD_FAILURE() << "read";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("huge.png: its header claims 1000000 x 1000000 pixels of 3 channels: 12000.0 GB as floats, more than this machine's"),
              std::string::npos)
        << e.what();
  }
  const std::filesystem::path fifo = dir / "fifo.exr";
  ASSERT_EQ(::mkfifo(fifo.c_str(), 0600), 0);
  for (const std::filesystem::path& path : {fifo, std::filesystem::path("/dev/zero")}) {
    try {
      read_image(path);
      ADD_FAILURE() << path;
    } catch (const InputError& e) {
      EXPECT_EQ(std::string(e.what()), path.string() + ": is not a regular file (a pipe, socket or device)");
    }
  }
}

}  // namespace
}  // namespace meso

namespace meso {
namespace {

TEST(ImageIo, MipLevelsRoundTripInOneExr) {
  test::TempDir dir;
  std::vector<Image> levels;
  for (int w = 13, h = 6; ; w = std::max(1, w / 2), h = std::max(1, h / 2)) {
    levels.push_back(ramp(w, h, 2));
    if (w == 1 && h == 1) break;
  }
  levels[0].metadata = {{"border", std::string("wrap")}};
  write_image_levels(levels, dir / "p.exr", PixelFormat::float32);
  const auto back = read_image_levels(dir / "p.exr");
  ASSERT_EQ(back.size(), levels.size());
  for (size_t k = 0; k < levels.size(); ++k) {
    EXPECT_EQ(back[k].width, levels[k].width);
    EXPECT_EQ(back[k].height, levels[k].height);
    EXPECT_EQ(back[k].pixels, levels[k].pixels) << "level " << k;
  }
  EXPECT_EQ(std::get<std::string>(back[0].metadata.at("border")), "wrap");
  // Sizes that do not halve are refused.
  levels[1] = ramp(5, 3, 2);
  EXPECT_THROW(write_image_levels(levels, dir / "q.exr", PixelFormat::float32), InternalError);
}

// An EXR of one float channel Y whose data window (x0, y0)-(x1, y1) differs from its display
// window (fx0, fy0)-(fx1, fy1), written with OpenEXR itself; sample (x, y) = 1 + x + 100 y in
// the file's pixel coordinates.
void write_windowed_exr(const std::filesystem::path& path, int fx0, int fy0, int fx1, int fy1, int x0, int y0, int x1, int y1) {
  Imf::Header header(Imath::Box2i({fx0, fy0}, {fx1, fy1}), Imath::Box2i({x0, y0}, {x1, y1}));
  header.channels().insert("Y", Imf::Channel(Imf::FLOAT));
  const int w = x1 - x0 + 1, h = y1 - y0 + 1;
  std::vector<float> samples(static_cast<size_t>(w * h));
  for (int y = y0; y <= y1; ++y)
    for (int x = x0; x <= x1; ++x) samples[static_cast<size_t>((y - y0) * w + (x - x0))] = static_cast<float>(1 + x + 100 * y);
  Imf::FrameBuffer frame;
  // OpenEXR addresses pixel (x, y) at base + x * xStride + y * yStride.
  char* base = reinterpret_cast<char*>(samples.data()) - (static_cast<ptrdiff_t>(x0) + static_cast<ptrdiff_t>(y0) * w) * static_cast<ptrdiff_t>(sizeof(float));
  frame.insert("Y", Imf::Slice(Imf::FLOAT, base, sizeof(float), sizeof(float) * static_cast<size_t>(w)));
  Imf::OutputFile file(path.c_str(), header);
  file.setFrameBuffer(frame);
  file.writePixels(h);
}

// A cropped map (data window inside the display window) is read at the display window's size
// with its samples where they belong and zeros around; overscan (data beyond the display
// window) is cut away; a display window away from the origin is the frame all the same.
TEST(ImageIo, DataWindowIsPlacedInTheDisplayWindow) {
  test::TempDir dir;
  auto expect_frame = [](const Image& img, int fx0, int fy0, int x0, int y0, int x1, int y1, const char* what) {
    for (int y = 0; y < img.height; ++y)
      for (int x = 0; x < img.width; ++x) {
        const int px = x + fx0, py = y + fy0;  // the file's pixel coordinates
        const bool data = px >= x0 && px <= x1 && py >= y0 && py <= y1;
        EXPECT_EQ(img.at(x, y), data ? static_cast<float>(1 + px + 100 * py) : 0.0f) << what << " at " << x << ", " << y;
      }
  };
  write_windowed_exr(dir / "crop.exr", 0, 0, 7, 5, 2, 1, 4, 3);
  Image img = read_image(dir / "crop.exr");
  ASSERT_EQ(img.width, 8);
  ASSERT_EQ(img.height, 6);
  ASSERT_EQ(img.channels, 1);
  expect_frame(img, 0, 0, 2, 1, 4, 3, "crop");

  write_windowed_exr(dir / "overscan.exr", 0, 0, 3, 3, -2, -1, 5, 6);
  img = read_image(dir / "overscan.exr");
  ASSERT_EQ(img.width, 4);
  ASSERT_EQ(img.height, 4);
  expect_frame(img, 0, 0, -2, -1, 5, 6, "overscan");

  write_windowed_exr(dir / "offset.exr", 10, 20, 14, 23, 12, 19, 20, 21);  // partly above and right of the frame
  img = read_image(dir / "offset.exr");
  ASSERT_EQ(img.width, 5);
  ASSERT_EQ(img.height, 4);
  expect_frame(img, 10, 20, 12, 19, 20, 21, "offset");

  write_windowed_exr(dir / "apart.exr", 0, 0, 3, 3, 10, 10, 12, 12);  // no overlap: all zero
  img = read_image(dir / "apart.exr");
  ASSERT_EQ(img.width, 4);
  expect_frame(img, 0, 0, 10, 10, 12, 12, "apart");

  // A PNG's oFFs chunk (ImageMagick's crops, GIMP's layer offsets) places the image on a
  // page: it is read as it is, not moved out of its own frame.
  const Image small = ramp(5, 3, 1);
  write_image(small, dir / "page.png", PixelFormat::uint16);
  std::string png = test::read_text(dir / "page.png");
  const std::string offs = std::string("oFFs") + big_endian(5) + big_endian(7) + std::string(1, '\0');  // (5, 7) pixels
  png.insert(8 + 25, big_endian(9) + offs + big_endian(png_crc(offs)));  // after the signature and IHDR
  test::write_text(dir / "page.png", png);
  img = read_image(dir / "page.png");
  ASSERT_EQ(img.width, 5);
  ASSERT_EQ(img.height, 3);
  for (size_t i = 0; i < small.pixels.size(); ++i) EXPECT_NEAR(img.pixels[i], small.pixels[i], 1.0 / 65535) << i;
}

TEST(ImageIo, HalfExrKeepsHalfPrecision) {
  test::TempDir dir;
  const Image img = ramp(9, 4, 1);
  write_image(img, dir / "h.exr", PixelFormat::half);
  const Image back = read_image(dir / "h.exr");
  for (size_t i = 0; i < img.pixels.size(); ++i) EXPECT_NEAR(back.pixels[i], img.pixels[i], 1.0 / 2048);
}

}  // namespace
}  // namespace meso
