// Running magbake (or any command) from tests.
#pragma once

#include <filesystem>
#include <string>

namespace magbake::testing {

/// A finished command: its exit code (-1 if it did not exit normally) and its output.
struct Outcome {
  int code = -1;
  std::string out;  ///< stdout and stderr, interleaved as written
};

/// A fresh, empty folder for one test process: <tmp>/<stem>_<pid>. ctest runs each test in its
/// own process, two at a time, and CI may share /tmp with other runs: names must not collide.
std::filesystem::path fresh_temp_dir(const std::string& stem);

/// Runs `cmd` through the shell with stderr merged into stdout and waits for it.
Outcome sh(const std::string& cmd);

}  // namespace magbake::testing
