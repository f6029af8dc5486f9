#include "support/shell.h"

#include <sys/wait.h>
#include <unistd.h>

#include <array>
#include <cstdio>

namespace magbake::testing {

std::filesystem::path fresh_temp_dir(const std::string& stem) {
  const std::filesystem::path dir = std::filesystem::temp_directory_path() / (stem + "_" + std::to_string(::getpid()));
  std::filesystem::remove_all(dir);
  std::filesystem::create_directories(dir);
  return dir;
}

Outcome sh(const std::string& cmd) {
  Outcome r;
  FILE* p = popen((cmd + " 2>&1").c_str(), "r");
  if (!p) return r;
  std::array<char, 4096> buf;
  while (std::fgets(buf.data(), buf.size(), p)) r.out += buf.data();
  const int st = pclose(p);
  r.code = WIFEXITED(st) ? WEXITSTATUS(st) : -1;
  return r;
}

}  // namespace magbake::testing
