// Running another program (sbatch, scontrol) and reading what it printed.
#pragma once

#include <string>
#include <vector>

namespace magbake::cli {

/// What a finished program left: its exit code (128 + signal when killed, -1 when it could not
/// be started) and its stdout and stderr.
struct ProcessResult {
  int code = -1;
  std::string out, err;
};

/// Runs argv[0] (looked up in PATH) with the arguments, no shell, and waits for it.
ProcessResult run_process(const std::vector<std::string>& argv);

/// The absolute path of `name` in PATH, or "" when it is not there (a name with a slash is
/// checked as it is).
std::string find_in_path(const std::string& name);

}  // namespace magbake::cli
