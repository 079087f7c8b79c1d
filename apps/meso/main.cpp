// meso: the command-line front end. Exit codes: 0 success, 1 a requested check failed,
// 2 bad usage, 3 bad input, 4 internal error (meso/core/error.hpp).
#include "cli.hpp"

#include "meso/formats/atomic_file.hpp"
#include "meso/formats/image_io.hpp"

#include "meso/core/error.hpp"
#include "meso/core/memory.hpp"

#include <spdlog/sinks/stdout_color_sinks.h>
#include <spdlog/spdlog.h>
#include <tbb/global_control.h>
#include <unistd.h>

#include <cctype>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <iostream>
#include <optional>
#include <sstream>

#ifndef MESO_VERSION
#define MESO_VERSION "0.0.0"
#endif

namespace meso::cli {

void info(Globals& g, const std::string& message) {
  if (!g.quiet) g.messages.emplace_back(false, message);
}
void warn(Globals& g, const std::string& message) {
  if (!g.quiet) g.messages.emplace_back(true, message);
}

const CLI::Validator Finite(
    [](std::string& text) -> std::string {
      try {
        size_t used = 0;
        const double v = std::stod(text, &used);
        if (used == text.size() && std::isfinite(v)) return {};
      } catch (const std::exception&) {
      }
      return "'" + text + "' is not a finite number";
    },
    "FINITE");

// CLI11's PositiveNumber and NonNegativeNumber are ranges up to DBL_MAX, and say so in full
// (a 309-digit bound) when they refuse a value.
namespace {
CLI::Validator sign_check(bool zero_allowed, const char* what, const char* name) {
  return CLI::Validator(
      [=](std::string& text) -> std::string {
        try {
          size_t used = 0;
          const double v = std::stod(text, &used);
          if (used == text.size() && std::isfinite(v) && (v > 0 || (zero_allowed && v == 0))) return {};
        } catch (const std::exception&) {
        }
        return "'" + text + "' is not " + what;
      },
      name);
}
}  // namespace
const CLI::Validator ImageOutput(
    [](std::string& text) -> std::string {
      return is_writable_image_extension(text) ? std::string() : "'" + text + "': unknown image extension (use .png, .exr or .tif)";
    },
    "IMAGE");
CLI::Validator InRange(double lo, double hi, bool above_lo) {
  auto bound = [](double v) {
    std::ostringstream text;
    text << v;  // shortest of %g's six digits: 89.9, 1e+06
    return text.str();
  };
  const std::string range = (above_lo ? "(" : "[") + bound(lo) + ", " + bound(hi) + "]";
  return CLI::Validator(
      [=](std::string& text) -> std::string {
        try {
          size_t used = 0;
          const double v = std::stod(text, &used);
          if (used == text.size() && std::isfinite(v) && (above_lo ? v > lo : v >= lo) && v <= hi) return {};
        } catch (const std::exception&) {
        }
        return "'" + text + "' is not a number in " + range;
      },
      "in " + range, "RANGE");
}
const CLI::Validator Positive = sign_check(false, "a finite number above 0", "POSITIVE");
const CLI::Validator NonNegative = sign_check(true, "a finite number of 0 or more", "NONNEGATIVE");

std::string lower_extension(const std::string& path) {
  std::string ext = std::filesystem::path(path).extension().string();
  for (char& c : ext) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return ext;
}

void refuse_overwriting_input(const std::string& output, const std::vector<std::string>& inputs) {
  if (output.empty()) return;
  const std::filesystem::path out(output);
  for (const std::string& input : inputs) {
    if (input.empty()) continue;
    std::error_code ec;  // either missing: not the same file (equivalent() is false)
    if (std::filesystem::equivalent(out, input, ec))
      throw UsageError(output + ": is also the input " + input + "; write the output under another name");
  }
}

void refuse_beyond_memory(const std::string& what, double bytes) {
  const double physical = physical_memory_bytes();
  if (physical > 0 && bytes > physical) {
    char text[160];
    std::snprintf(text, sizeof text, " needs about %.1f GB of memory, more than this machine's %.1f GB", bytes / 1e9, physical / 1e9);
    throw UsageError(what + text);
  }
}

bool has_surface_area(const Mesh& mesh) {
  for (auto f : mesh.faces())
    if (face_area(mesh, f) > 0) return true;
  return false;
}

std::string short_number(double v) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.6g", v);
  return buf;
}

bool parse_finite(const std::string& text, float& value) {
  size_t used = 0;
  try {
    value = std::stof(text, &used);
  } catch (const std::exception&) {
    return false;
  }
  return !text.empty() && used == text.size() && std::isfinite(value);
}

void parse_size(const std::string& text, int& width, int& height) {
  const auto x = text.find('x');
  try {
    size_t used = 0;
    if (x == std::string::npos) {
      width = height = std::stoi(text, &used);
      if (used != text.size()) throw std::invalid_argument(text);
    } else {
      width = std::stoi(text.substr(0, x), &used);
      if (used != x) throw std::invalid_argument(text);
      height = std::stoi(text.substr(x + 1), &used);
      if (used != text.size() - x - 1) throw std::invalid_argument(text);
    }
  } catch (const std::out_of_range&) {  // digits beyond int: out of range, not malformed
    throw UsageError("size '" + text + "' is out of range (1 to 32768 per side)");
  } catch (const std::logic_error&) {
    throw UsageError("size '" + text + "' is not N or WxH");
  }
  if (width < 1 || height < 1 || width > 32768 || height > 32768)
    throw UsageError("size '" + text + "' is out of range (1 to 32768 per side)");
}

}  // namespace meso::cli

namespace {
// Library messages (OIIO, assimp) can span lines; the contract is one line per error.
std::string first_line(const std::string& text) { return text.substr(0, text.find('\n')); }
}  // namespace

int main(int argc, char** argv) {
  using namespace meso;
  // Ctrl-C or a build system's kill during a run leaves no temporary output behind.
  remove_outputs_on_signals();
  cli::Globals globals;
  cli::Context ctx{globals, {}};

  CLI::App app{"meso: an offline asset-baking toolchain for displacement mapping.\n"
               "Exit codes: 0 success, 1 a requested check failed, 2 bad usage, 3 bad input, 4 internal error."};
  app.set_version_flag("--version", std::string("meso ") + MESO_VERSION);
  app.require_subcommand(1);
  // Global options may also follow the subcommand (meso bake ... --json); subcommands added
  // below inherit this.
  app.fallthrough();
  // A usage error is one line, in meso's own form (CLI11's default adds a second).
  app.failure_message([](const CLI::App*, const CLI::Error& e) { return std::string("meso: error: ") + e.what() + " (see --help)\n"; });
  app.option_defaults()->always_capture_default();  // --help shows every default
  app.add_option("--threads", globals.threads, "Worker threads (0 = all cores); outputs do not depend on it")
      ->check(cli::NonNegative)
      ->check(CLI::Range(0, 65536));  // beyond int, CLI11 said only "Could not convert"
  app.add_flag("--quiet", globals.quiet, "No progress bar, information or warnings (errors still print)");
  app.add_flag("--json", globals.json, "Print a machine-readable JSON report of what was done on stdout");
  cli::add_meshreduce(app, ctx);
  cli::add_uvpack(app, ctx);
  cli::add_bake(app, ctx);
  cli::add_frames(app, ctx);
  cli::add_streams(app, ctx);
  cli::add_preview(app, ctx);

  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    const int code = app.exit(e);  // prints help, version or the error
    return code == 0 ? 0 : static_cast<int>(ExitCode::usage);
  }

  auto logger = spdlog::stderr_color_mt("meso");
  logger->set_pattern("meso: %^%l%$: %v");
  spdlog::set_default_logger(logger);

  std::optional<tbb::global_control> threads;
  if (globals.threads > 0) threads.emplace(tbb::global_control::max_allowed_parallelism, static_cast<size_t>(globals.threads));
  TerminalProgress progress(!globals.quiet && ::isatty(STDERR_FILENO));

  nlohmann::json report = nlohmann::json::object();
  int code = 0;
  try {
    if (!ctx.run) throw UsageError("no command given (see meso --help)");
    code = ctx.run(report, progress);
  } catch (const Error& e) {
    progress.abandon();
    std::fprintf(stderr, "meso: error: %s\n", first_line(e.what()).c_str());
    return static_cast<int>(e.code());
  } catch (const std::bad_alloc&) {
    progress.abandon();
    std::fprintf(stderr, "meso: error: out of memory\n");
    return static_cast<int>(ExitCode::internal);
  } catch (const std::exception& e) {
    progress.abandon();
    std::fprintf(stderr, "meso: internal error: %s\n", first_line(e.what()).c_str());
    return static_cast<int>(ExitCode::internal);
  }
  for (const auto& [is_warning, text] : globals.messages) {
    if (is_warning) spdlog::warn("{}", text);
    else spdlog::info("{}", text);
  }
  if (globals.json) std::cout << report.dump(2) << std::endl;
  return code;
}
