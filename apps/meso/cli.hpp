// What every subcommand of `meso` shares: global options, the progress bar, reporting.
// apps/ only parses arguments and calls the stage libraries.
#pragma once

#include "meso/core/progress.hpp"

#include <CLI/CLI.hpp>
#include <nlohmann/json.hpp>

#include <functional>
#include <memory>
#include <string>

namespace meso::cli {

struct Globals {
  int threads = 0;  // 0: all cores
  bool quiet = false;
  bool json = false;
};

// A subcommand's run function fills `report` (printed on stdout with --json) and may
// return a non-zero exit code for a failed check (ExitCode::check_failed).
using RunFn = std::function<int(nlohmann::json& report, Progress& progress)>;

struct Context {
  const Globals& globals;
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

// Informational lines on stderr ("meso: ..."), silenced by --quiet.
void info(const Globals& g, const std::string& message);
void warn(const Globals& g, const std::string& message);

// "512" or "512x256" -> width, height. Throws UsageError.
void parse_size(const std::string& text, int& width, int& height);

}  // namespace meso::cli

#include "meso/core/mesh.hpp"

namespace meso::cli {
// Reads a mesh file, warns about what import had to repair, and records counts in `report`.
Mesh load_mesh(const Globals& g, const std::string& path, nlohmann::json& report);
}  // namespace meso::cli
