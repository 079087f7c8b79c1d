// Errors and the exit codes the `meso` command maps them to (documented in the README).
#pragma once

#include <stdexcept>
#include <string>

namespace meso {

enum class ExitCode : int {
  ok = 0,
  check_failed = 1,  // the run worked but a requested check failed (--fail-on, --max-miss-rate)
  usage = 2,         // bad command line
  bad_input = 3,     // unreadable or invalid input file, missing data the stage needs
  internal = 4,      // a bug or an environment failure (no OpenGL, disk full, ...)
};

// Base of every error meso reports. what() is one line, naming the file where one is involved.
class Error : public std::runtime_error {
 public:
  Error(ExitCode code, const std::string& message) : std::runtime_error(message), code_(code) {}
  ExitCode code() const { return code_; }

 private:
  ExitCode code_;
};

// Invalid input data: "FILE: PROBLEM".
class InputError : public Error {
 public:
  InputError(const std::string& file, const std::string& problem)
      : Error(ExitCode::bad_input, file.empty() ? problem : file + ": " + problem) {}
};

class UsageError : public Error {
 public:
  explicit UsageError(const std::string& message) : Error(ExitCode::usage, message) {}
};

class InternalError : public Error {
 public:
  explicit InternalError(const std::string& message) : Error(ExitCode::internal, message) {}
};

}  // namespace meso
