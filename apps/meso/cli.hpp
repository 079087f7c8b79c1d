// What every subcommand of `meso` shares: global options, the progress bar, reporting.
// apps/ only parses arguments and calls the stage libraries.
#pragma once

#include "meso/core/progress.hpp"

#include <CLI/CLI.hpp>
#include <nlohmann/json.hpp>

#include <functional>
#include <memory>
#include <string>
#include <utility>
#include <vector>

namespace meso::cli {

struct Globals {
  int threads = 0;  // 0: all cores
  bool quiet = false;
  bool json = false;
  // Informational and warning lines, printed on stderr only when the run succeeds, so that a
  // failing run prints exactly one line: its error.
  std::vector<std::pair<bool, std::string>> messages;  // (is_warning, text)
};

// A subcommand's run function fills `report` (printed on stdout with --json) and may
// return a non-zero exit code for a failed check (ExitCode::check_failed).
using RunFn = std::function<int(nlohmann::json& report, Progress& progress)>;

struct Context {
  Globals& globals;
  // Set by the subcommand that CLI11 selected.
  RunFn run;
};

// Subcommand registration, one file each (cmd_*.cpp).
void add_meshreduce(CLI::App& app, Context& ctx);
void add_uvpack(CLI::App& app, Context& ctx);
void add_bake(CLI::App& app, Context& ctx);
void add_frames(CLI::App& app, Context& ctx);
void add_streams(CLI::App& app, Context& ctx);
void add_preview(CLI::App& app, Context& ctx);

// Informational lines and warnings on stderr ("meso: info: ...", "meso: warning: ..."),
// silenced by --quiet, held back until the run has succeeded.
void info(Globals& g, const std::string& message);
void warn(Globals& g, const std::string& message);

// A validator for floating-point options: refuses NaN and infinities.
extern const CLI::Validator Finite;
// Finite and above 0; finite and 0 or more.
extern const CLI::Validator Positive;
extern const CLI::Validator NonNegative;
// A finite number in [lo, hi], or in (lo, hi] with above_lo, for floating-point options.
// Why not CLI::Range: it lets NaN through (every comparison with NaN is false) and prints
// its bounds with six decimals ("not in range 0.000000 to 89.900000").
CLI::Validator InRange(double lo, double hi, bool above_lo = false);
// A file name write_image takes (.png, .exr, .tif).
extern const CLI::Validator ImageOutput;

// "512" or "512x256" -> width, height. Throws UsageError.
void parse_size(const std::string& text, int& width, int& height);

// The whole of `text` as a finite number, or false (nothing is thrown).
bool parse_finite(const std::string& text, float& value);

// A path's extension in lower case, with its dot (".exr"; "" for none).
std::string lower_extension(const std::string& path);

// Throws UsageError when `output` names the same file as one of `inputs` (also through a
// link or another spelling of the path): the run would replace its own input. Empty names
// are skipped.
void refuse_overwriting_input(const std::string& output, const std::vector<std::string>& inputs);

// Throws UsageError when `bytes` (an estimate of what a run will hold at once) exceeds this
// machine's physical memory, saying `what` needs it: refused before the work instead of
// swapping for minutes or being killed by the kernel.
void refuse_beyond_memory(const std::string& what, double bytes);

// Six significant digits at any scale, for messages (std::to_string's fixed six decimals
// print a distance of 1e-9 as 0.000000).
std::string short_number(double v);

}  // namespace meso::cli

#include "meso/core/mesh.hpp"

namespace meso::cli {
// Whether any face of `mesh` has area (face_area in double): a mesh whose faces are all
// degenerate has no surface to draw, unwrap or measure.
bool has_surface_area(const Mesh& mesh);

// Reads a mesh file, warns about what import had to repair, and records counts in `report`.
Mesh load_mesh(Globals& g, const std::string& path, nlohmann::json& report);
}  // namespace meso::cli
