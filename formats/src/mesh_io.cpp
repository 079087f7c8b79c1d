#include "meso/formats/mesh_io.hpp"
#include "meso/formats/atomic_file.hpp"

#include "meso/core/error.hpp"
#include "meso/core/input_file.hpp"
#include "meso/core/mesh_extent.hpp"
#include "meso/core/mesh_arrays.hpp"

#include <OpenMesh/Core/IO/MeshIO.hh>
#include <assimp/DefaultLogger.hpp>
#include <assimp/Importer.hpp>
#include <assimp/LogStream.hpp>
#include <assimp/config.h>
#include <assimp/fast_atof.h>
#include <assimp/postprocess.h>
#include <assimp/scene.h>

#include <nlohmann/json.hpp>

#include <algorithm>
#include <array>
#include <cctype>
#include <charconv>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <limits>
#include <fstream>
#include <mutex>
#include <sstream>
#include <stdexcept>
#include <string>
#include <string_view>
#include <unordered_map>
#include <vector>

// assimp checks its own invariants with ai_assert, which Debian's build keeps and which
// aborts the process by default: a truncated PLY whose header announces more faces than it
// holds trips TriangulateProcess's check (exit 134, no message of meso's). libassimp calls
// this function through its PLT, so the executable's definition takes the place of the
// library's (upstream's setAiAssertHandler is neither exported nor installed here): it
// throws, and read_mesh reports the file as unreadable (exit 3).
namespace Assimp {
void aiAssertViolation(const char* expression, const char* file, int line);
void aiAssertViolation(const char* expression, const char* file, int line) {
  throw std::runtime_error(std::string("inconsistent data (assimp's check '") + expression + "' failed at " + file + ":" + std::to_string(line) + ")");
}
}  // namespace Assimp

namespace meso {

namespace fs = std::filesystem;

namespace {

struct PosKey {
  uint32_t b[3];
  bool operator==(const PosKey& o) const { return b[0] == o.b[0] && b[1] == o.b[1] && b[2] == o.b[2]; }
};
struct PosKeyHash {
  size_t operator()(const PosKey& k) const {
    uint64_t h = 1469598103934665603ull;
    for (uint32_t x : k.b) h = (h ^ x) * 1099511628211ull;
    return static_cast<size_t>(h);
  }
};
PosKey key_of(const Vec3f& p) {
  PosKey k;
  for (int i = 0; i < 3; ++i) {
    const float v = p[i] + 0.0f;  // folds -0 into +0 so both weld
    std::memcpy(&k.b[i], &v, 4);
  }
  return k;
}

// OpenMesh logs to stdout (which belongs to --json reports) and stderr (where meso prints
// its own one-line messages); meso reports what matters itself, so mute it while it works.
class SilenceOpenMesh {
 public:
  SilenceOpenMesh() : log_(omlog().is_enabled()), out_(omout().is_enabled()), err_(omerr().is_enabled()) {
    omlog().disable();
    omout().disable();
    omerr().disable();
  }
  ~SilenceOpenMesh() {
    if (log_) omlog().enable();
    if (out_) omout().enable();
    if (err_) omerr().enable();
  }
  SilenceOpenMesh(const SilenceOpenMesh&) = delete;
  SilenceOpenMesh& operator=(const SilenceOpenMesh&) = delete;

 private:
  bool log_, out_, err_;
};

std::string lower_ext(const fs::path& p) {
  std::string e = p.extension().string();
  std::transform(e.begin(), e.end(), e.begin(), [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  return e;
}

// The whole file, for the checks below.
std::string file_text(const fs::path& path, const std::string& name) {
  std::ifstream in(path, std::ios::binary);
  std::string text;
  text.resize(static_cast<size_t>(fs::file_size(path)));
  if (!in.read(text.data(), static_cast<std::streamsize>(text.size()))) throw InputError(name, "cannot read the file");
  return text;
}

// A token of a numeric field as a message shows it: bytes outside printable ASCII (a damaged
// file's control bytes, which a terminal would not show) as \xNN.
std::string shown_token(std::string_view token) {
  std::string out;
  for (const char c : token) {
    const auto b = static_cast<unsigned char>(c);
    if (b >= 0x20 && b < 0x7f) {
      out += c;
    } else {
      char hex[5];
      std::snprintf(hex, sizeof hex, "\\x%02X", b);
      out += hex;
    }
  }
  return out;
}

// assimp's OBJ reader turns a texture coordinate it cannot parse ("nan", "inf", "0,5") into 0,
// and when a face names a texture coordinate the file does not have it drops every UV of the
// file, without a word either time: a bake would then read a wrong or missing mapping; a `v`
// line it cannot parse ("v abc 0 0", "v 0 0") it drops, and the faces then fail with "vertex
// index out of range". So an OBJ's `v` and `vt` values and the texture indices of its `f`
// lines are checked first, naming the line (one pass over the file, about 1.5 s per GB).
// Returns the triangles of faces without texture indices when the file has some `vt` (assimp
// gives their corners UV 0,0 silently).
// Whether [t, end) is a number finite as a float, as meso stores it (1e39 would be read as
// inf). One too small for a double (1e-400) is 0 to assimp, and here.
bool float_number(const char* t, const char* end) {
  const char* a = t + (*t == '+' ? 1 : 0);
  if (a > t && a < end && (*a == '-' || *a == '+')) return false;  // "+-1": from_chars would read -1, assimp nothing
  double value = 0;
  const auto [ptr, ec] = std::from_chars(a, end, value);
  if (ptr != end) return false;
  if (ec == std::errc::result_out_of_range) {
    const char* e = std::find_if(a, end, [](char c) { return c == 'e' || c == 'E'; });
    return e + 1 < end && e[1] == '-';  // underflow, not overflow
  }
  return ec == std::errc() && std::isfinite(static_cast<float>(value));
}

// assimp parses an OBJ's numbers with its own fast_atof, which is not correctly rounded: 7.5 %
// of the values of MeshIo.ObjReadsEveryShortestFloatTextExactly (scales 1e-12 to 1.7e7), among
// them "9.63967e-06", which meso's own writer prints for that float, came back one float step
// off, so a file meso wrote did not read back bit for bit, and a command that does not move
// vertices (uvpack pack) moved them by a step. The scan below reads every `v` and `vt` both
// ways (fast_atof from assimp's header, the inline function its OBJ reader calls; from_chars
// into a float, correctly rounded) and keeps the values assimp misreads, keyed by what assimp
// read: read_mesh puts the right ones back. A key is dropped when it is ambiguous, i.e. when
// two texts that read differently were misread to it, or when some text assimp read right
// (or a `v x y z w`, which assimp divides by w) gives it too: that vertex must stay as it is.
template <size_t N>
struct ObjFix {
  std::array<uint32_t, N> read, exact;  // float bits: as assimp reads the values, as the text says
};
template <size_t N>
using ObjFixes = std::vector<ObjFix<N>>;

struct ObjScan {
  size_t untextured = 0;  // triangles of faces without texture indices when the file has some `vt`
  ObjFixes<3> positions;
  ObjFixes<2> texcoords;
};

// fast_atof's errors are exceptions of assimp's type, whose constructor libassimp does not
// export: they throw this instead, and such a value is left to assimp, which refuses the file.
struct FastAtofError : std::runtime_error {
  template <typename... T>
  explicit FastAtofError(T&&...) : std::runtime_error("fast_atof") {}
};

uint32_t float_bits(float x) {
  uint32_t b = 0;
  std::memcpy(&b, &x, sizeof b);
  return b;
}

// A position's bits as read_mesh sees them: the node transform (the identity for an OBJ)
// turns -0 into +0.
uint32_t position_bits(float x) { return float_bits(x == 0.0f ? 0.0f : x); }

template <size_t N>
uint64_t key_hash(const std::array<uint32_t, N>& k) {
  uint64_t h = 0x9E3779B97F4A7C15ull;
  for (uint32_t b : k) {
    h ^= b;
    h *= 0xBF58476D1CE4E5B9ull;
    h ^= h >> 31;
  }
  return h;
}

// Sorted by what assimp reads; ambiguous keys dropped (`right`: hashes of keys that texts
// assimp read right also give; a hash collision only drops a correction, never adds one).
template <size_t N>
void settle(ObjFixes<N>& fixes, std::vector<uint64_t>& right) {
  std::sort(right.begin(), right.end());
  std::sort(fixes.begin(), fixes.end(), [](const ObjFix<N>& a, const ObjFix<N>& b) { return a.read < b.read || (a.read == b.read && a.exact < b.exact); });
  ObjFixes<N> out;
  for (size_t i = 0; i < fixes.size();) {
    size_t j = i + 1;
    bool same = true;
    for (; j < fixes.size() && fixes[j].read == fixes[i].read; ++j) same = same && fixes[j].exact == fixes[i].exact;
    if (same && !std::binary_search(right.begin(), right.end(), key_hash(fixes[i].read))) out.push_back(fixes[i]);
    i = j;
  }
  fixes.swap(out);
  right = std::vector<uint64_t>();
}

// `values` with the right bits where assimp misread them (`key`: the bits of `values` as the
// table is keyed).
template <size_t N>
void correct(const ObjFixes<N>& fixes, const std::array<uint32_t, N>& key, float* values) {
  const auto it = std::lower_bound(fixes.begin(), fixes.end(), key, [](const ObjFix<N>& f, const std::array<uint32_t, N>& k) { return f.read < k; });
  if (it == fixes.end() || it->read != key) return;
  for (size_t k = 0; k < N; ++k) std::memcpy(&values[k], &it->exact[k], sizeof(float));
}

// The number [t, end) (checked by float_number) as assimp reads it (false: fast_atof refuses
// it) and as the text says, correctly rounded.
bool read_both(const char* t, const char* end, float& read, float& exact) {
  std::from_chars(t + (*t == '+' ? 1 : 0), end, exact);
  try {
    ai_real r = 0;
    Assimp::fast_atoreal_move<ai_real, FastAtofError>(t, r);
    read = static_cast<float>(r);
    return true;
  } catch (const FastAtofError&) {
    return false;
  }
}

ObjScan check_obj_lines(const std::string& text, const std::string& name) {
  // A binary file named .obj: assimp's OBJ reader skips what it cannot parse and said only
  // "Ignoring empty face".
  if (std::memchr(text.data(), '\0', text.size())) throw InputError(name, "is not a text file (an OBJ is text), so not an OBJ mesh");
  const auto blank = [](char c) { return c == ' ' || c == '\t' || c == '\r'; };
  ObjScan scan;
  std::vector<uint64_t> right_positions, right_texcoords;  // keys assimp read right (settle())
  long long texcoords = 0, largest = 0;
  size_t line = 0, largest_line = 0, untextured = 0;
  std::string largest_token;
  // A statement continued over lines ending in '\' (assimp joins them): gathered in `joined`,
  // then read from `statement`, named by its first line.
  std::string joined, statement;
  size_t first_line = 0;
  for (const char *p = text.data(), *end = p + text.size(); p < end;) {
    const char* eol = static_cast<const char*>(std::memchr(p, '\n', static_cast<size_t>(end - p)));
    if (!eol) eol = end;
    ++line;
    const char* q = p;
    p = eol + 1;
    const char* stop = static_cast<const char*>(std::memchr(q, '#', static_cast<size_t>(eol - q)));
    if (!stop) stop = eol;
    const char* last = stop;
    while (last > q && blank(last[-1])) --last;
    if (last > q && last[-1] == '\\') {
      if (joined.empty()) first_line = line;
      joined.append(q, last - 1);
      joined += ' ';
      continue;
    }
    size_t statement_line = line;
    if (!joined.empty()) {
      joined.append(q, stop);
      statement.swap(joined);
      joined.clear();
      q = statement.data();
      stop = q + statement.size();
      statement_line = first_line;
    }
    while (q < stop && blank(*q)) ++q;
    const bool vt = stop - q > 2 && q[0] == 'v' && q[1] == 't' && blank(q[2]);
    const bool v = stop - q > 1 && q[0] == 'v' && blank(q[1]);
    const bool f = stop - q >= 1 && q[0] == 'f' && (stop - q == 1 || blank(q[1]));
    if (!vt && !v && !f) continue;
    q += vt ? 2 : 1;
    const auto where = [&] { return "line " + std::to_string(statement_line); };
    size_t corners = 0, textured = 0, with_normal = 0, values = 0;
    float read[4] = {0, 0, 0, 0}, exact[4] = {0, 0, 0, 0};  // a `v`'s first four values, a `vt`'s first two
    bool readable = true;  // by fast_atof
    while (q < stop) {
      while (q < stop && blank(*q)) ++q;
      const char* t = q;
      while (q < stop && !blank(*q)) ++q;
      if (t == q) break;
      const std::string_view token(t, static_cast<size_t>(q - t));
      if (v) {
        // x y z, then an optional w or r g b, which assimp reads or ignores: only the position's
        // three values are checked.
        if (++values > 3) {
          if (values == 4 && float_number(t, q)) readable = read_both(t, q, read[3], exact[3]) && readable;
          continue;
        }
        if (!float_number(t, q))
          throw InputError(name, where() + ": vertex coordinate '" + shown_token(token) + "' is not a finite number (as a float)");
        readable = read_both(t, q, read[values - 1], exact[values - 1]) && readable;
        continue;
      }
      if (vt) {
        if (!float_number(t, q))
          throw InputError(name, where() + ": texture coordinate '" + shown_token(token) + "' is not a finite number (as a float)");
        if (++values <= 2) readable = read_both(t, q, read[values - 1], exact[values - 1]) && readable;
        continue;
      }
      // v, v/vt, v/vt/vn or v//vn: only the vt index is checked here (assimp checks v's).
      ++corners;
      const size_t slash = token.find('/');
      if (slash != std::string_view::npos) {
        const size_t second = token.find('/', slash + 1);
        with_normal += second != std::string_view::npos && second + 1 < token.size();
      }
      if (slash == std::string_view::npos || slash + 1 >= token.size() || token[slash + 1] == '/') continue;
      const char* a = t + slash + 1;
      long long index = 0;
      const auto [ptr, ec] = std::from_chars(a, q, index);
      // A negative index counts back from the latest `vt` (-1 is the latest); a positive one
      // may name a `vt` further down (assimp resolves them after the whole file), so the
      // largest is checked at the end.
      const bool parsed = ec == std::errc() && (ptr == q || *ptr == '/');
      if (!parsed) {
        const char* index_end = static_cast<const char*>(std::memchr(a, '/', static_cast<size_t>(q - a)));
        const bool too_large = ec == std::errc::result_out_of_range && (ptr == q || *ptr == '/');
        throw InputError(name, where() + ": face corner '" + shown_token(token) + "': its texture coordinate index '" +
                                   shown_token(std::string_view(a, static_cast<size_t>((index_end ? index_end : q) - a))) +
                                   (too_large ? "' is out of range" : "' is not an integer"));
      }
      if (index == 0 || (index < 0 && texcoords + index < 0))
        throw InputError(name, where() + ": face corner '" + shown_token(token) + "' names texture coordinate " +
                                   std::string(a, ptr) + ", but the file has " + std::to_string(texcoords) +
                                   " before it");
      if (index > largest) largest = index, largest_line = line, largest_token = token;
      ++textured;
    }
    if (v && values < 3) throw InputError(name, where() + ": a vertex needs three coordinates (x y z)");
    // assimp takes x y z as they are from 3 values (and x y z r g b), x/w y/w z/w from 4 (those
    // are not corrected, but their keys must not be), the first two of a `vt`'s 2 or 3.
    if (v && readable && (values == 3 || values == 4 || values == 6)) {
      ObjFix<3> fix;
      for (size_t k = 0; k < 3; ++k) {
        fix.read[k] = position_bits(values == 4 ? read[k] / read[3] : read[k]);
        fix.exact[k] = position_bits(exact[k]);
      }
      if (values != 4 && fix.read != fix.exact)
        scan.positions.push_back(fix);
      else
        right_positions.push_back(key_hash(fix.read));
    }
    if (vt && readable && values >= 2) {
      const ObjFix<2> fix{{float_bits(read[0]), float_bits(read[1])}, {float_bits(exact[0]), float_bits(exact[1])}};
      if (fix.read != fix.exact)
        scan.texcoords.push_back(fix);
      else
        right_texcoords.push_back(key_hash(fix.read));
    }
    // (A file cut inside its last face statement is caught here when the cut leaves fewer than
    // three corners: assimp reads such a face as a point or line and drops it.)
    if (f && corners < 3) throw InputError(name, where() + ": a face needs at least three vertices");
    // The OBJ format gives every corner of a face the same form. assimp reads a face whose
    // corners mix them (f 1/1 2 3/3) by position in its lists, so each corner after the
    // first without one takes the next corner's texture coordinate (or normal): refused.
    if (f && textured > 0 && textured < corners)
      throw InputError(name, where() + ": " + std::to_string(textured) + " of the face's " + std::to_string(corners) +
                                 " corners name a texture coordinate (v/vt), the others none: give every corner one, or none");
    if (f && with_normal > 0 && with_normal < corners)
      throw InputError(name, where() + ": " + std::to_string(with_normal) + " of the face's " + std::to_string(corners) +
                                 " corners name a normal (v/vt/vn or v//vn), the others none: give every corner one, or none");
    if (vt) ++texcoords;
    if (f && textured == 0 && corners >= 3) untextured += corners - 2;  // assimp fans a polygon into n - 2 triangles
  }
  if (largest > texcoords)
    throw InputError(name, "line " + std::to_string(largest_line) + ": face corner '" + largest_token + "' names texture coordinate " +
                               std::to_string(largest) + ", but the file has " + std::to_string(texcoords));
  scan.untextured = texcoords > 0 ? untextured : 0;
  settle(scan.positions, right_positions);
  settle(scan.texcoords, right_texcoords);
  return scan;
}

// assimp's ASCII PLY reader, given fewer elements than the header announces, makes up the
// missing ones (a face short of the count comes back as a copy of the last), and its binary
// reader allocates what the header announces before reading (4e9 vertices: bad_alloc): the
// file is cut short and is refused. The body is walked as the header's elements and
// properties lay it out (a list property: its count, then that many values): token by token
// in ASCII; in binary, elements without lists in one step, lists by their counts.
void check_ply(const std::string& text, const std::string& name) {
  const size_t header_end = text.find("end_header");
  if (text.compare(0, 3, "ply") != 0) return;  // assimp says what is wrong
  // assimp 5.2's PLY reader never returns from a header without its end (a file cut inside
  // its header, or a hand-written one): refused here.
  if (header_end == std::string::npos) throw InputError(name, "its header has no end_header line (the file is cut short or damaged)");
  struct Property {
    bool list = false;
    size_t size = 0;       // bytes of the value, or of a list's count (0: a type assimp will refuse)
    size_t item_size = 0;  // bytes of each list item
  };
  struct Element {
    std::string name;
    long long count = 0;
    std::vector<Property> properties;
  };
  // Bytes of a PLY scalar type.
  const auto type_size = [](const std::string& t) -> size_t {
    if (t == "char" || t == "uchar" || t == "int8" || t == "uint8") return 1;
    if (t == "short" || t == "ushort" || t == "int16" || t == "uint16") return 2;
    if (t == "int" || t == "uint" || t == "int32" || t == "uint32" || t == "float" || t == "float32") return 4;
    if (t == "double" || t == "float64") return 8;
    return 0;
  };
  std::vector<Element> elements;
  std::string format;
  size_t pos = 0;
  while (pos < header_end) {
    size_t eol = text.find('\n', pos);
    if (eol == std::string::npos || eol > header_end) eol = header_end;
    std::istringstream line(text.substr(pos, eol - pos));
    pos = eol + 1;
    std::string word;
    line >> word;
    if (word == "format") {
      line >> format;
    } else if (word == "element") {
      Element e;
      line >> e.name >> e.count;
      elements.push_back(e);
    } else if (word == "property" && !elements.empty()) {
      Property p;
      line >> word;
      p.list = word == "list";
      if (p.list) {
        line >> word;
        p.size = type_size(word);
        line >> word;
        p.item_size = type_size(word);
      } else {
        p.size = type_size(word);
      }
      elements.back().properties.push_back(p);
    }
  }
  const size_t body = text.find('\n', header_end);
  // A face's first list is its corners: fewer than three make no surface (assimp dropped such
  // faces, or with none said "inconsistent data"), refused as the OBJ check does.
  const auto check_corners = [&](const Element& e, const Property& p, long long i, unsigned long long n) {
    if (e.name != "face" || !p.list || &p != &*std::find_if(e.properties.begin(), e.properties.end(), [](const Property& q) { return q.list; })) return;
    if (n < 3) throw InputError(name, "face " + std::to_string(i) + " has " + std::to_string(n) + " corners (a face needs at least three)");
  };
  const auto cut_short = [&](const Element& e, long long i) {
    return InputError(name, "cut short: it ends inside " + e.name + " " + std::to_string(i) + " of the " + std::to_string(e.count) +
                                " its header announces");
  };
  if (format == "binary_little_endian" || format == "binary_big_endian") {
    const bool big = format == "binary_big_endian";
    const size_t size = text.size();
    size_t at = body == std::string::npos ? size : body + 1;
    for (const Element& e : elements) {
      size_t fixed = 0;
      bool lists = false;
      for (const Property& p : e.properties) {
        if (p.size == 0 || (p.list && p.item_size == 0)) return;  // an unknown type: assimp says what is wrong
        lists |= p.list;
        fixed += p.size;
      }
      if (!lists) {
        // count * fixed may pass 2^64: compared by division.
        if (e.count > 0 && fixed > 0 && static_cast<unsigned long long>(e.count) > (size - at) / fixed)
          throw cut_short(e, static_cast<long long>((size - at) / fixed));
        at += static_cast<size_t>(std::max(0LL, e.count)) * fixed;
        continue;
      }
      for (long long i = 0; i < e.count; ++i)
        for (const Property& p : e.properties) {
          if (p.size > size - at) throw cut_short(e, i);
          size_t n = 1;
          if (p.list) {
            // The list's count, as an unsigned number of p.size bytes in the file's byte order.
            n = 0;
            for (size_t k = 0; k < p.size; ++k) n = (n << 8) | static_cast<unsigned char>(text[at + (big ? k : p.size - 1 - k)]);
            at += p.size;
            check_corners(e, p, i, n);
            if (n > (size - at) / p.item_size) throw cut_short(e, i);
            at += n * p.item_size;
          } else {
            at += p.size;
          }
        }
    }
    return;
  }
  if (format != "ascii") return;
  const char* end = text.data() + text.size();
  const char* p = body == std::string::npos ? end : text.data() + body + 1;
  // The next token, or false at the end of the file.
  const auto next = [&](std::string_view& token) {
    while (p < end && std::isspace(static_cast<unsigned char>(*p))) ++p;
    const char* t = p;
    while (p < end && !std::isspace(static_cast<unsigned char>(*p))) ++p;
    token = std::string_view(t, static_cast<size_t>(p - t));
    return p > t;
  };
  for (const Element& e : elements)
    for (long long i = 0; i < e.count && !e.properties.empty(); ++i)  // an element without properties takes no tokens
      for (const Property& property : e.properties) {
        const bool list = property.list;
        std::string_view token;
        long long n = 1;
        bool ok = next(token);
        if (ok && list) {
          const auto [ptr, ec] = std::from_chars(token.data(), token.data() + token.size(), n);
          ok = ec == std::errc() && ptr == token.data() + token.size() && n >= 0;
          if (ok) check_corners(e, property, i, static_cast<unsigned long long>(n));
        }
        for (long long k = 0; ok && k < (list ? n : 0); ++k) ok = next(token);
        if (!ok) throw cut_short(e, i);
      }
  // Data past what the header announces (a vertex count too small: assimp said
  // "inconsistent data").
  std::string_view extra;
  if (next(extra))
    throw InputError(name, "has more data than its header announces (from '" + std::string(extra.substr(0, 24)) + "' on)");
}

// What assimp 5.2's glTF 2.0 reader would read wrong without failing, refused: a required
// extension it does not implement (KHR_mesh_quantization's integer positions came in 1e-39
// across, EXT_meshopt_compression's buffers as if plain), and positions, normals or texture
// coordinates stored as normalised integers, which core glTF allows for texture coordinates
// (it takes their bytes for floats: UVs of 9e-41, or NaN). Extensions of materials, textures
// and lights leave the geometry as it is and are let through. JSON that does not parse is
// refused here too, saying where (assimp said only "No suitable reader found"), and so is a
// binary glTF 2.0 whose header or chunks run past the end of the file (a download or copy
// cut short; assimp said the same). glTF 1.0's binary layout is left to assimp.
void check_gltf(const std::string& text, const std::string& name) {
  std::string_view json = text;
  if (text.compare(0, 4, "glTF") == 0) {
    // Binary glTF 2.0 (the spec's "GLB File Format Specification"): a 12-byte header (magic,
    // version, total length), then chunks of (length, type, data), the first one JSON.
    auto u32 = [&](size_t at) {
      uint32_t v = 0;
      std::memcpy(&v, text.data() + at, 4);  // little-endian, as the machines meso runs on
      return v;
    };
    const std::string held = std::to_string(text.size()) + " bytes";
    if (text.size() < 12) throw InputError(name, "is cut short: " + held + ", less than a binary glTF header (12)");
    const uint32_t version = u32(4);
    if (version == 1) return;
    if (version != 2) throw InputError(name, "is binary glTF version " + std::to_string(version) + ", which meso cannot read (2 or 1)");
    if (u32(8) > text.size())
      throw InputError(name, "is cut short: its binary glTF header announces " + std::to_string(u32(8)) + " bytes, the file holds " + held);
    // The chunks within the announced length (bytes past it are not the glTF's).
    const size_t end = u32(8);
    if (end < 20) throw InputError(name, "its binary glTF header announces " + std::to_string(end) + " bytes, less than a header and a chunk");
    if (text.compare(16, 4, "JSON") != 0) throw InputError(name, "its first binary glTF chunk is not JSON");
    for (size_t at = 12; at < end;) {
      if (end - at < 8) throw InputError(name, "its binary glTF chunks end inside a chunk header (at byte " + std::to_string(at) + ")");
      const uint32_t length = u32(at);
      if (length > end - at - 8)
        throw InputError(name, "is cut short: its binary glTF chunk at byte " + std::to_string(at) + " announces " + std::to_string(length) +
                                   " bytes, " + std::to_string(end - at - 8) + " follow its header");
      at += 8 + static_cast<size_t>(length);
    }
    json = std::string_view(text.data() + 20, u32(12));
  }
  nlohmann::json doc;
  try {
    doc = nlohmann::json::parse(json.begin(), json.end());
  } catch (const nlohmann::json::parse_error& e) {
    // (assimp said "No suitable reader found for the file format".)
    std::string why = e.what();  // "[json.exception.parse_error.101] parse error at line 1, ..."
    if (const size_t cut = why.find("] "); cut != std::string::npos) why.erase(0, cut + 2);
    throw InputError(name, "its glTF JSON does not parse (" + why + ")");
  }
  if (!doc.is_object()) throw InputError(name, "its glTF JSON is not an object");
  if (const auto it = doc.find("extensionsRequired"); it != doc.end() && it->is_array())
    for (const auto& e : *it) {
      if (!e.is_string()) continue;
      const std::string ext = e.get<std::string>();
      if (ext.rfind("KHR_materials_", 0) == 0 || ext == "KHR_texture_transform" || ext == "KHR_texture_basisu" || ext == "EXT_texture_webp" ||
          ext == "KHR_lights_punctual")
        continue;
      throw InputError(name, "requires the glTF extension " + ext + ", which meso cannot read (export without it)");
    }
  const auto meshes = doc.find("meshes");
  const auto accessors = doc.find("accessors");
  if (meshes == doc.end() || !meshes->is_array() || accessors == doc.end() || !accessors->is_array()) return;
  const auto type_name = [](int t) -> std::string {
    switch (t) {
      case 5120: return "bytes";
      case 5121: return "unsigned bytes";
      case 5122: return "shorts";
      case 5123: return "unsigned shorts";
      case 5125: return "unsigned ints";
      default: return "component type " + std::to_string(t);
    }
  };
  for (size_t m = 0; m < meshes->size(); ++m) {
    const auto& mesh = (*meshes)[m];
    if (!mesh.is_object() || !mesh.contains("primitives") || !mesh["primitives"].is_array()) continue;
    for (const auto& primitive : mesh["primitives"]) {
      if (!primitive.is_object() || !primitive.contains("attributes") || !primitive["attributes"].is_object()) continue;
      for (const char* attribute : {"POSITION", "NORMAL", "TEXCOORD_0"}) {
        const auto a = primitive["attributes"].find(attribute);
        if (a == primitive["attributes"].end() || !a->is_number_unsigned()) continue;
        const size_t index = a->get<size_t>();
        if (index >= accessors->size() || !(*accessors)[index].is_object()) continue;  // assimp refuses it
        const auto type = (*accessors)[index].find("componentType");
        if (type == (*accessors)[index].end() || !type->is_number_integer() || type->get<int>() == 5126) continue;
        const std::string mesh_name = mesh.contains("name") && mesh["name"].is_string() ? "'" + mesh["name"].get<std::string>() + "'" : std::to_string(m);
        throw InputError(name, "mesh " + mesh_name + " stores " + attribute + " as " + type_name(type->get<int>()) +
                                   ", which meso's glTF reader (assimp 5.2) misreads: export it as floats");
      }
    }
  }
}

// Some of assimp's readers repair a file without failing: they drop faces whose indices are
// out of range (glTF) or point them elsewhere (OFF), and only say so in their log. A file
// meso would read differently from what it says is refused, so assimp's log is collected
// while it reads: a message that reports dropped or out-of-range data ends the read (other
// messages, such as a material's missing texture image, do not). The logger is
// process-wide: reads are serialised by a mutex.
class AssimpLog {
 public:
  AssimpLog() : lock_(mutex()) {
    Assimp::DefaultLogger::create("", Assimp::Logger::NORMAL, 0);  // no file, no console
    Assimp::DefaultLogger::get()->attachStream(new Stream(entries_), Assimp::Logger::Warn | Assimp::Logger::Err);
  }
  ~AssimpLog() { Assimp::DefaultLogger::kill(); }
  AssimpLog(const AssimpLog&) = delete;
  AssimpLog& operator=(const AssimpLog&) = delete;

  // The error logged just before the last "Validation failed" one, or "": a failed
  // validation is often the symptom of what a reader logged before it (an OFF short of faces
  // leaves a face without indices).
  std::string cause_of_validation_failure() const {
    std::string before;
    for (const Entry& e : entries_) {
      if (!e.error) continue;
      if (e.text.rfind("Validation failed", 0) == 0) return before;
      before = e.text;
    }
    return {};
  }
  // The first message of data dropped or out of range, or "".
  std::string first_repair() const {
    for (const Entry& e : entries_) {
      std::string lower = e.text;
      std::transform(lower.begin(), lower.end(), lower.begin(), [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
      if (lower.find("dropped") != std::string::npos || lower.find("out of range") != std::string::npos ||
          lower.find("out-of-range") != std::string::npos)
        return e.text;
    }
    return {};
  }

 private:
  struct Entry {
    bool error;
    std::string text;
  };
  struct Stream : Assimp::LogStream {
    explicit Stream(std::vector<Entry>& out) : out_(out) {}
    // Messages arrive as "Warn,  T0: text\n" or "Error, T0: text\n".
    void write(const char* message) override {
      std::string m(message);
      const bool error = m.rfind("Error", 0) == 0;
      const size_t colon = m.find(": ");
      if (colon != std::string::npos) m.erase(0, colon + 2);
      m = m.substr(0, m.find('\n'));
      out_.push_back({error, m});
    }
    std::vector<Entry>& out_;
  };
  static std::mutex& mutex() {
    static std::mutex m;
    return m;
  }
  std::lock_guard<std::mutex> lock_;
  std::vector<Entry> entries_;
};

// One input mesh instanced by one node, with the node's accumulated transform.
struct Instance {
  const aiMesh* mesh;
  aiMatrix4x4 transform;
  std::string name;
};

void collect(const aiScene* scene, const aiNode* node, const aiMatrix4x4& parent, std::vector<Instance>& out) {
  const aiMatrix4x4 m = parent * node->mTransformation;
  for (unsigned i = 0; i < node->mNumMeshes; ++i) {
    const aiMesh* mesh = scene->mMeshes[node->mMeshes[i]];
    std::string name = mesh->mName.length ? mesh->mName.C_Str() : node->mName.C_Str();
    out.push_back({mesh, m, name});
  }
  for (unsigned i = 0; i < node->mNumChildren; ++i) collect(scene, node->mChildren[i], m, out);
}

// Splits the polygon with corners idx[0..n) (indices into pos, in winding order) into n - 2
// triangles of its winding, appended to out. Why not assimp's aiProcess_Triangulate: its
// split of concave polygons can fold them (an L-shaped hexagon came out as four triangles
// over an area of 4 instead of 3, one facing back).
// Ear clipping (Meisters 1975) in the plane that drops the largest axis of the polygon's
// Newell normal: a corner b between a and c is an ear when a -> b -> c turns the polygon's
// way and no reflex corner lies in or on the triangle abc (only reflex corners can). The
// search starts at corner 1 and goes on from the corner after each ear, so a convex polygon
// comes out as the fan from corner 0 (as assimp split convex quads; its split of larger
// polygons differed) and a concave quad along the diagonal from its reflex corner (as assimp
// split it). A polygon without an ear (self-
// intersecting, or degenerate in that plane) loses a corner that turns its way, else any:
// n - 2 triangles always, which the caller checks like any others.
void triangulate_polygon(const aiVector3D* pos, const unsigned* idx, unsigned n, std::vector<std::array<unsigned, 3>>& out) {
  if (n < 3) return;
  // Newell's normal (in double).
  double normal[3] = {0, 0, 0};
  for (unsigned i = 0; i < n; ++i) {
    const aiVector3D& p = pos[idx[i]];
    const aiVector3D& q = pos[idx[(i + 1) % n]];
    normal[0] += (static_cast<double>(p.y) - q.y) * (static_cast<double>(p.z) + q.z);
    normal[1] += (static_cast<double>(p.z) - q.z) * (static_cast<double>(p.x) + q.x);
    normal[2] += (static_cast<double>(p.x) - q.x) * (static_cast<double>(p.y) + q.y);
  }
  int axis = 0;
  for (int k = 1; k < 3; ++k)
    if (std::abs(normal[k]) > std::abs(normal[axis])) axis = k;
  // The other two axes in cyclic order: the projected polygon turns counter-clockwise where
  // the normal's component along `axis` is positive.
  const int ua = (axis + 1) % 3, va = (axis + 2) % 3;
  const double turn = normal[axis] < 0 ? -1.0 : 1.0;
  std::vector<double> u(n), v(n);
  for (unsigned i = 0; i < n; ++i) {
    u[i] = pos[idx[i]][static_cast<unsigned>(ua)];
    v[i] = pos[idx[i]][static_cast<unsigned>(va)];
  }
  // > 0 where a -> b -> c turns the polygon's way.
  const auto orient = [&](unsigned a, unsigned b, unsigned c) { return turn * ((u[b] - u[a]) * (v[c] - v[a]) - (v[b] - v[a]) * (u[c] - u[a])); };
  std::vector<unsigned> prev(n), next(n);
  for (unsigned i = 0; i < n; ++i) prev[i] = (i + n - 1) % n, next[i] = (i + 1) % n;
  const auto reflex = [&](unsigned b) { return !(orient(prev[b], b, next[b]) > 0); };
  std::vector<unsigned> reflexes;
  for (unsigned i = 0; i < n; ++i)
    if (reflex(i)) reflexes.push_back(i);
  std::vector<char> removed(n, 0);
  const auto is_ear = [&](unsigned b) {
    const unsigned a = prev[b], c = next[b];
    if (!(orient(a, b, c) > 0)) return false;
    for (const unsigned r : reflexes) {
      if (removed[r] || r == a || r == b || r == c) continue;
      if (orient(a, b, r) >= 0 && orient(b, c, r) >= 0 && orient(c, a, r) >= 0) return false;
    }
    return true;
  };
  unsigned cursor = 1, left = n;
  while (left > 3) {
    unsigned ear = cursor;
    bool found = false;
    for (unsigned k = 0, b = cursor; k < left; ++k, b = next[b])
      if (is_ear(b)) {
        ear = b, found = true;
        break;
      }
    if (!found)
      for (unsigned k = 0, b = cursor; k < left; ++k, b = next[b])
        if (orient(prev[b], b, next[b]) > 0) {
          ear = b;
          break;
        }
    const unsigned a = prev[ear], c = next[ear];
    out.push_back({idx[a], idx[ear], idx[c]});
    next[a] = c, prev[c] = a, removed[ear] = 1, --left;
    // a and c may have stopped being reflex; none becomes reflex by losing an ear.
    reflexes.erase(std::remove_if(reflexes.begin(), reflexes.end(), [&](unsigned r) { return removed[r] || ((r == a || r == c) && !reflex(r)); }),
                   reflexes.end());
    cursor = c;
  }
  out.push_back({idx[prev[cursor]], idx[cursor], idx[next[cursor]]});
}

}  // namespace

Mesh read_mesh(const fs::path& path, MeshReadReport* report) {
  const std::string name = path.string();
  require_input_file(path, "a mesh file");
  const bool obj = lower_ext(path) == ".obj";
  const std::string obj_text = obj ? file_text(path, name) : std::string();
  const ObjScan obj_scan = obj ? check_obj_lines(obj_text, name) : ObjScan();
  if (lower_ext(path) == ".ply") check_ply(file_text(path, name), name);
  if (lower_ext(path) == ".gltf" || lower_ext(path) == ".glb") {
    // assimp picks the glTF reader by the extension and refused a mislabelled file with "No
    // suitable reader found"; the content says which it is (a binary glTF starts "glTF").
    const std::string text = file_text(path, name);
    const bool binary = text.compare(0, 4, "glTF") == 0;
    const size_t first = text.find_first_not_of(" \t\r\n");
    if (lower_ext(path) == ".glb" && !binary && first != std::string::npos && text[first] == '{')
      throw InputError(name, "is a text (JSON) glTF, not a binary one: name it .gltf");
    if (lower_ext(path) == ".gltf" && binary) throw InputError(name, "is a binary glTF: name it .glb");
    check_gltf(text, name);
  }
  // A UTF-8 byte-order mark (some Windows tools write one) hides the OBJ's first line from
  // assimp, which then reports an index out of range: such a file is read from memory, past
  // the mark (its material library, which meso does not use, is then not looked for).
  const bool bom = obj && obj_text.compare(0, 3, "\xEF\xBB\xBF") == 0;
  Assimp::Importer importer;
  // Coordinates are the file's own: a COLLADA up_axis is not turned into a rotation, so a
  // .dae base mesh and an .obj high mesh of one asset stay aligned.
  importer.SetPropertyBool(AI_CONFIG_IMPORT_COLLADA_IGNORE_UP_DIRECTION, true);
  // Keep everything as the file has it (no welding by assimp, which would also merge corners
  // we want to keep, no reordering); polygons are split below (triangulate_polygon).
  const aiScene* scene = nullptr;
  std::string err, validation_cause, repair;
  {
    const AssimpLog log;
    try {
      const unsigned flags = aiProcess_ValidateDataStructure;
      scene = bom ? importer.ReadFileFromMemory(obj_text.data() + 3, obj_text.size() - 3, flags, "obj") : importer.ReadFile(name, flags);
    } catch (const std::exception& e) {  // aiAssertViolation's, if assimp lets it through
      err = e.what();
    }
    validation_cause = log.cause_of_validation_failure();
    repair = log.first_repair();
  }
  if (!scene || !scene->mRootNode) {
    if (err.empty()) err = importer.GetErrorString();
    if (err.rfind("Validation failed", 0) == 0 && !validation_cause.empty()) err = validation_cause;
    err = err.substr(0, err.find('\n'));
    if (err.find("contains no faces") != std::string::npos) throw InputError(name, "contains no faces");
    throw InputError(name, "cannot read mesh: " + (err.empty() ? std::string("unknown format") : err));
  }
  if (!repair.empty()) throw InputError(name, "damaged, not read (assimp: " + repair + ")");
  std::vector<Instance> instances;
  collect(scene, scene->mRootNode, aiMatrix4x4(), instances);

  MeshReadReport rep;
  const SilenceOpenMesh silence;  // add_face() complains about non-manifold faces; we count them
  Mesh mesh;
  bool any_uv = false, all_normals = true;
  for (const auto& inst : instances) {
    any_uv |= inst.mesh->HasTextureCoords(0);
    all_normals &= inst.mesh->HasNormals();
  }
  if (any_uv) mesh.request_halfedge_texcoords2D();

  std::unordered_map<PosKey, int, PosKeyHash> welded;
  std::vector<OpenMesh::Vec3d> normal_sum;
  std::vector<std::string> names;
  std::vector<int> groups;

  for (size_t g = 0; g < instances.size(); ++g) {
    const Instance& inst = instances[g];
    const aiMesh* am = inst.mesh;
    names.push_back(inst.name);
    aiMatrix3x3 normal_matrix(inst.transform);
    // A mirroring transform (negative determinant: a node scaled by -1 along an axis) turns
    // the winding: its triangles are turned back, so that they face outwards as the file's
    // did (and agree with its normals, which the inverse transpose carries over).
    const bool mirrored = normal_matrix.Determinant() < 0;
    normal_matrix.Inverse().Transpose();
    std::vector<VertexHandle> local(am->mNumVertices);
    std::vector<Vec3f> local_pos(am->mNumVertices);
    rep.file_vertices += am->mNumVertices;
    for (unsigned i = 0; i < am->mNumVertices; ++i) {
      const aiVector3D p = inst.transform * am->mVertices[i];
      Vec3f pf(p.x, p.y, p.z);
      if (!obj_scan.positions.empty())  // (an OBJ's transform is the identity)
        correct(obj_scan.positions, {position_bits(pf[0]), position_bits(pf[1]), position_bits(pf[2])}, pf.data());
      if (!std::isfinite(pf[0]) || !std::isfinite(pf[1]) || !std::isfinite(pf[2]))
        throw InputError(name, "vertex " + std::to_string(rep.file_vertices - am->mNumVertices + i) +
                                   " has a NaN or infinite coordinate");
      local_pos[i] = pf;
      auto [it, inserted] = welded.try_emplace(key_of(pf), 0);
      if (inserted) {
        it->second = mesh.add_vertex(pf).idx();
        normal_sum.emplace_back(0, 0, 0);
      }
      local[i] = VertexHandle(it->second);
      if (am->HasNormals()) {
        aiVector3D n = normal_matrix * am->mNormals[i];
        if (std::isfinite(n.x) && std::isfinite(n.y) && std::isfinite(n.z))
          normal_sum[static_cast<size_t>(it->second)] += OpenMesh::Vec3d(n.x, n.y, n.z).normalize_cond();
      }
    }
    std::vector<std::array<unsigned, 3>> triangles;  // those of the face at hand
    for (unsigned pi = 0; pi < am->mNumFaces; ++pi) {
      const aiFace& af = am->mFaces[pi];
      if (af.mNumIndices < 3) continue;  // points and lines carry no surface
      triangles.clear();
      if (af.mNumIndices == 3)
        triangles.push_back({af.mIndices[0], af.mIndices[1], af.mIndices[2]});
      else
        triangulate_polygon(am->mVertices, af.mIndices, af.mNumIndices, triangles);
      for (auto& idx : triangles) {
        if (mirrored) std::swap(idx[1], idx[2]);
        std::vector<VertexHandle> vs = {local[idx[0]], local[idx[1]], local[idx[2]]};
        FaceHandle f;
        if (vs[0] != vs[1] && vs[1] != vs[2] && vs[0] != vs[2]) f = mesh.add_face(vs);
        if (!f.is_valid()) {
          // Non-manifold or repeating a vertex: keep the face, in order, on its own vertices.
          for (int k = 0; k < 3; ++k) {
            vs[static_cast<size_t>(k)] = mesh.add_vertex(local_pos[idx[k]]);
            normal_sum.emplace_back(0, 0, 0);
          }
          f = mesh.add_face(vs);
          if (!f.is_valid()) throw InternalError(name + ": could not add isolated face " + std::to_string(mesh.n_faces()));
          ++rep.isolated_faces;
        }
        groups.push_back(static_cast<int>(g));
        if (any_uv) {
          for (auto h : face_halfedges(mesh, f)) {
            const auto v = mesh.to_vertex_handle(h);
            int k = v == vs[0] ? 0 : v == vs[1] ? 1 : 2;
            Vec2f uv(0, 0);
            if (am->HasTextureCoords(0)) {
              const aiVector3D t = am->mTextureCoords[0][idx[k]];
              uv = Vec2f(t.x, t.y);
              if (!obj_scan.texcoords.empty()) correct(obj_scan.texcoords, {float_bits(uv[0]), float_bits(uv[1])}, uv.data());
              if (!std::isfinite(uv[0]) || !std::isfinite(uv[1]))
                throw InputError(name, "face " + std::to_string(mesh.n_faces() - 1) + " has a NaN or infinite texture coordinate");
            }
            mesh.set_texcoord2D(h, uv);
          }
          if (!am->HasTextureCoords(0)) ++rep.faces_without_uv;
        }
      }
    }
  }
  {
    // meso computes in float where it must (Embree, OpenMesh points, the maps): refused here,
    // once, for every command (mesh_extent.hpp).
    const MeshExtent extent = check_mesh_extent(mesh, name);
    rep.largest_coordinate = extent.largest_coordinate;
    rep.float_step = extent.float_step;
    rep.step_per_edge = extent.step_per_edge;
  }
  // An OBJ's faces without `vt` inside a textured object are counted only by the scan (assimp
  // gives them UV 0,0); it also counts those of untextured objects, which the loop above saw.
  if (any_uv) rep.faces_without_uv = std::max(rep.faces_without_uv, obj_scan.untextured);
  if (any_uv) {
    // Boundary halfedges belong to no face and so got no UV above; OpenMesh leaves them
    // uninitialised. Zero them so nothing downstream reads indeterminate values.
    for (auto h : mesh.halfedges())
      if (mesh.is_boundary(h)) mesh.set_texcoord2D(h, Vec2f(0, 0));
  }
  rep.welded_vertices = mesh.n_vertices();
  rep.faces = mesh.n_faces();
  rep.had_normals = all_normals;
  set_face_groups(mesh, names, groups);

  compute_angle_weighted_normals(mesh);
  if (all_normals) {
    // Keep the file's normals (averaged where vertices were welded) when they are usable.
    for (auto v : mesh.vertices()) {
      OpenMesh::Vec3d n = normal_sum[static_cast<size_t>(v.idx())];
      if (n.norm() > 1e-12) mesh.set_normal(v, OpenMesh::vector_cast<Vec3f>(n.normalize()));
    }
  }
  if (report) *report = rep;
  return mesh;
}

bool is_writable_mesh_extension(const fs::path& path) {
  const std::string e = lower_ext(path);
  return e == ".obj" || e == ".ply" || e == ".gltf" || e == ".glb";
}

namespace {

void write_with_openmesh(const Mesh& mesh, const fs::path& path, OpenMesh::IO::Options opt) {
  const SilenceOpenMesh silence;
  // Through a stream of our own: OpenMesh's writers do not check the stream after writing,
  // so a full disk left a truncated file reported as written. (Binary PLY only: the
  // precision argument matters to OpenMesh's text writers, not used.)
  std::ofstream out(path, std::ios::binary);
  if (!out) throw InternalError(shown_output_name(path.string()) + ": cannot open for writing");
  if (!OpenMesh::IO::write_mesh(mesh, out, path.extension().string(), opt, 9)) throw InternalError(shown_output_name(path.string()) + ": cannot write mesh");
  out.close();
  if (!out) throw InternalError(shown_output_name(path.string()) + ": write failed");
}

void write_ply(const Mesh& mesh, const fs::path& path) {
  // PLY stores UVs per vertex: give each distinct corner attribute its own vertex.
  const CornerSplit split = split_corners(mesh);
  Mesh out;
  const bool uv = has_uvs(mesh);
  out.request_vertex_normals();
  if (uv) out.request_vertex_texcoords2D();
  for (size_t i = 0; i < split.corner.size(); ++i) {
    const VertexHandle src(static_cast<int>(split.vertex[i]));
    const auto v = out.add_vertex(mesh.point(src));
    if (mesh.has_vertex_normals()) out.set_normal(v, mesh.normal(src));
    if (uv) out.set_texcoord2D(v, mesh.texcoord2D(split.corner[i]));
  }
  size_t bad = 0;
  for (size_t f = 0; f < split.triangles.size() / 3; ++f) {
    std::vector<VertexHandle> vs;
    for (int k = 0; k < 3; ++k) vs.push_back(VertexHandle(static_cast<int>(split.triangles[3 * f + static_cast<size_t>(k)])));
    if (!out.add_face(vs).is_valid()) ++bad;
  }
  if (bad) throw InternalError(shown_output_name(path.string()) + ": " + std::to_string(bad) + " faces cannot be represented in PLY output");
  OpenMesh::IO::Options opt = OpenMesh::IO::Options::Binary;
  if (mesh.has_vertex_normals()) opt += OpenMesh::IO::Options::VertexNormal;
  if (uv) opt += OpenMesh::IO::Options::VertexTexCoord;
  write_with_openmesh(out, path, opt);
}

// OBJ, written here rather than by OpenMesh, whose writer prints a fixed number of decimals
// (9: a mesh at a scale of 1e-6 kept one or two significant digits, one at 1e-30 none).
// Numbers are the shortest text that reads back as the same float (std::to_chars), so every
// coordinate round-trips bit for bit at any scale. `v` (and `vn`) per vertex in handle order,
// `vt` per distinct corner UV in order of first use, faces in order from each face's first
// corner (the to-vertex of its halfedge).
void write_obj(const Mesh& mesh, const fs::path& path) {
  std::ofstream out(path, std::ios::binary);
  if (!out) throw InternalError(shown_output_name(path.string()) + ": cannot open for writing");
  const bool uv = has_uvs(mesh), normals = mesh.has_vertex_normals();
  std::string text;
  auto flush = [&] {
    out.write(text.data(), static_cast<std::streamsize>(text.size()));
    text.clear();
  };
  auto number = [&](float x) {
    char buf[32];
    const auto r = std::to_chars(buf, buf + sizeof buf, x);
    text += ' ';
    text.append(buf, r.ptr);
  };
  auto index = [&](size_t i) {
    char buf[24];
    const auto r = std::to_chars(buf, buf + sizeof buf, i + 1);
    text.append(buf, r.ptr);
  };
  text = "# " + std::to_string(mesh.n_vertices()) + " vertices, " + std::to_string(mesh.n_faces()) + " faces\n";
  std::vector<size_t> vindex(mesh.n_vertices(), 0);
  size_t nv = 0;
  for (auto v : mesh.vertices()) {
    vindex[static_cast<size_t>(v.idx())] = nv++;
    const Vec3f p = mesh.point(v);
    text += 'v';
    for (int k = 0; k < 3; ++k) number(p[k]);
    text += '\n';
    if (normals) {
      const Vec3f n = mesh.normal(v);
      text += "vn";
      for (int k = 0; k < 3; ++k) number(n[k]);
      text += '\n';
    }
    if (text.size() > (1u << 20)) flush();
  }
  // Corner UVs, deduplicated by their bits (so -0 and 0 stay apart, as they were).
  std::vector<size_t> tindex;
  if (uv) {
    std::unordered_map<uint64_t, size_t> seen;
    tindex.assign(mesh.n_halfedges(), 0);
    for (auto f : mesh.faces())
      for (auto h : face_halfedges(mesh, f)) {
        const Vec2f t = mesh.texcoord2D(h);
        uint32_t bits[2];
        std::memcpy(bits, t.data(), sizeof bits);
        const auto [it, inserted] = seen.try_emplace((uint64_t{bits[0]} << 32) | bits[1], seen.size());
        tindex[static_cast<size_t>(h.idx())] = it->second;
        if (!inserted) continue;
        text += "vt";
        number(t[0]);
        number(t[1]);
        text += '\n';
        if (text.size() > (1u << 20)) flush();
      }
  }
  for (auto f : mesh.faces()) {
    text += 'f';
    for (auto h : face_halfedges(mesh, f)) {
      const size_t v = vindex[static_cast<size_t>(mesh.to_vertex_handle(h).idx())];
      text += ' ';
      index(v);
      if (uv || normals) text += '/';
      if (uv) index(tindex[static_cast<size_t>(h.idx())]);
      if (normals) {
        text += '/';
        index(v);
      }
    }
    text += '\n';
    if (text.size() > (1u << 20)) flush();
  }
  flush();
  out.close();  // flush now: a full disk shows here, not after the file is committed
  if (!out) throw InternalError(shown_output_name(path.string()) + ": write failed");
}

void base64(const std::vector<uint8_t>& in, std::string& out) {
  static const char* t = "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
  out.reserve(out.size() + (in.size() + 2) / 3 * 4);
  size_t i = 0;
  for (; i + 2 < in.size(); i += 3) {
    const uint32_t n = (uint32_t(in[i]) << 16) | (uint32_t(in[i + 1]) << 8) | in[i + 2];
    out += t[(n >> 18) & 63]; out += t[(n >> 12) & 63]; out += t[(n >> 6) & 63]; out += t[n & 63];
  }
  if (i + 1 == in.size()) {
    const uint32_t n = uint32_t(in[i]) << 16;
    out += t[(n >> 18) & 63]; out += t[(n >> 12) & 63]; out += "==";
  } else if (i + 2 == in.size()) {
    const uint32_t n = (uint32_t(in[i]) << 16) | (uint32_t(in[i + 1]) << 8);
    out += t[(n >> 18) & 63]; out += t[(n >> 12) & 63]; out += t[(n >> 6) & 63]; out += '=';
  }
}

// glTF 2.0: one mesh, one primitive, vertices split at corner attribute changes.
// glTF puts the UV origin at the top-left: v is flipped on the way out.
void write_gltf(const Mesh& mesh, const fs::path& path, bool binary) {
  const CornerSplit split = split_corners(mesh);
  const bool uv = has_uvs(mesh);
  const auto tan = tangent_property(mesh);
  const size_t nv = split.corner.size();
  std::vector<uint8_t> buf;
  auto append = [&buf](const void* p, size_t n) {
    const auto* b = static_cast<const uint8_t*>(p);
    buf.insert(buf.end(), b, b + n);
    while (buf.size() % 4) buf.push_back(0);
  };
  nlohmann::json views = nlohmann::json::array(), accessors = nlohmann::json::array(), attributes;
  auto add_view = [&](const void* p, size_t n, int target) {
    const size_t offset = buf.size();
    append(p, n);
    views.push_back({{"buffer", 0}, {"byteOffset", offset}, {"byteLength", n}, {"target", target}});
    return views.size() - 1;
  };
  constexpr int kArray = 34962, kElements = 34963, kFloat = 5126, kUint = 5125;

  OpenMesh::VPropHandleT<OpenMesh::Vec2f> curv;
  OpenMesh::VPropHandleT<OpenMesh::Vec3f> pdir;
  const bool has_curv = mesh.get_property_handle(curv, kCurvatureProperty) && mesh.get_property_handle(pdir, kPrincipalDirectionProperty);
  std::vector<float> pos(nv * 3), nrm(nv * 3), tex(nv * 2), tng(nv * 4), cur(has_curv ? nv * 2 : 0), dir(has_curv ? nv * 3 : 0);
  Vec3f lo(0, 0, 0), hi(0, 0, 0);
  for (size_t i = 0; i < nv; ++i) {
    const VertexHandle v(static_cast<int>(split.vertex[i]));
    const Vec3f p = mesh.point(v);
    if (i == 0) lo = hi = p;
    lo.minimize(p);
    hi.maximize(p);
    const Vec3f n = mesh.has_vertex_normals() ? mesh.normal(v) : Vec3f(0, 0, 1);
    for (int k = 0; k < 3; ++k) {
      pos[3 * i + static_cast<size_t>(k)] = p[k];
      nrm[3 * i + static_cast<size_t>(k)] = n[k];
    }
    if (uv) {
      const Vec2f t = mesh.texcoord2D(split.corner[i]);
      tex[2 * i] = t[0];
      tex[2 * i + 1] = 1.0f - t[1];
    }
    if (tan.is_valid()) {
      const auto t4 = mesh.property(tan, split.corner[i]);
      for (int k = 0; k < 4; ++k) tng[4 * i + static_cast<size_t>(k)] = t4[k];
    }
    if (has_curv) {
      const auto k2 = mesh.property(curv, v);
      const auto d3 = mesh.property(pdir, v);
      for (int k = 0; k < 2; ++k) cur[2 * i + static_cast<size_t>(k)] = k2[k];
      for (int k = 0; k < 3; ++k) dir[3 * i + static_cast<size_t>(k)] = d3[k];
    }
  }
  auto accessor = [&](size_t view, size_t count, const char* type, int ctype) {
    accessors.push_back({{"bufferView", view}, {"componentType", ctype}, {"count", count}, {"type", type}});
    return accessors.size() - 1;
  };
  const size_t ipos = accessor(add_view(pos.data(), pos.size() * 4, kArray), nv, "VEC3", kFloat);
  accessors[ipos]["min"] = {lo[0], lo[1], lo[2]};
  accessors[ipos]["max"] = {hi[0], hi[1], hi[2]};
  attributes["POSITION"] = ipos;
  attributes["NORMAL"] = accessor(add_view(nrm.data(), nrm.size() * 4, kArray), nv, "VEC3", kFloat);
  if (uv) attributes["TEXCOORD_0"] = accessor(add_view(tex.data(), tex.size() * 4, kArray), nv, "VEC2", kFloat);
  if (tan.is_valid()) attributes["TANGENT"] = accessor(add_view(tng.data(), tng.size() * 4, kArray), nv, "VEC4", kFloat);
  if (has_curv) {
    // Application-specific attributes start with an underscore (glTF 2.0, 3.7.2.1).
    attributes["_CURVATURE"] = accessor(add_view(cur.data(), cur.size() * 4, kArray), nv, "VEC2", kFloat);
    attributes["_PRINCIPAL_DIRECTION"] = accessor(add_view(dir.data(), dir.size() * 4, kArray), nv, "VEC3", kFloat);
  }
  const size_t iidx =
      accessor(add_view(split.triangles.data(), split.triangles.size() * 4, kElements), split.triangles.size(), "SCALAR", kUint);

  nlohmann::json doc;
  doc["asset"] = {{"version", "2.0"}, {"generator", "meso"}};
  doc["scene"] = 0;
  doc["scenes"] = {{{"nodes", {0}}}};
  doc["nodes"] = {{{"mesh", 0}}};
  doc["meshes"] = {{{"primitives", {{{"attributes", attributes}, {"indices", iidx}, {"mode", 4}}}}}};
  doc["accessors"] = accessors;
  doc["bufferViews"] = views;
  nlohmann::json buffer = {{"byteLength", buf.size()}};
  std::ofstream out(path, std::ios::binary);
  if (!out) throw InternalError(shown_output_name(path.string()) + ": cannot open for writing");
  if (!binary) {
    std::string uri = "data:application/octet-stream;base64,";
    base64(buf, uri);
    buffer["uri"] = uri;
    doc["buffers"] = {buffer};
    out << doc.dump(1) << '\n';
  } else {
    doc["buffers"] = {buffer};
    std::string json = doc.dump();
    while (json.size() % 4) json += ' ';
    const uint32_t total = 12 + 8 + static_cast<uint32_t>(json.size()) + 8 + static_cast<uint32_t>(buf.size());
    auto u32 = [&out](uint32_t x) { out.write(reinterpret_cast<const char*>(&x), 4); };
    u32(0x46546C67);  // "glTF"
    u32(2);
    u32(total);
    u32(static_cast<uint32_t>(json.size()));
    u32(0x4E4F534A);  // "JSON"
    out.write(json.data(), static_cast<std::streamsize>(json.size()));
    u32(static_cast<uint32_t>(buf.size()));
    u32(0x004E4942);  // "BIN\0"
    out.write(reinterpret_cast<const char*>(buf.data()), static_cast<std::streamsize>(buf.size()));
  }
  out.close();  // flush now: a full disk shows here, not after the file is committed
  if (!out) throw InternalError(shown_output_name(path.string()) + ": write failed");
}

}  // namespace

void write_mesh(const Mesh& mesh, const fs::path& path) {
  const std::string e = lower_ext(path);
  if (e == ".obj") {
    write_obj(mesh, path);
  } else if (e == ".ply") {
    write_ply(mesh, path);
  } else if (e == ".gltf" || e == ".glb") {
    write_gltf(mesh, path, e == ".glb");
  } else {
    throw UsageError(path.string() + ": unknown mesh extension (use .obj, .ply, .gltf or .glb)");
  }
}

}  // namespace meso
