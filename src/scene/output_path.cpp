#include "output_path.h"

#include <filesystem>

namespace magbake::scene {

std::optional<std::string> scene_name_error(const std::string& name) {
  if (name.empty()) return "the scene name is empty";
  if (name.size() > 200) return "the scene name is longer than 200 bytes";
  if (name == "." || name == "..") return "the scene name cannot be '" + name + "'";
  for (const char ch : name) {
    const auto u = static_cast<unsigned char>(ch);
    if (ch == '/' || ch == '\\') return "the scene name names the cache file: it cannot contain '/' or '\\' (use outputs.cache for a folder)";
    if (u < 0x20 || u == 0x7f) return "the scene name contains a control character";
  }
  return std::nullopt;
}

std::optional<std::string> output_path_error(const std::string& path, bool allow_absolute) {
  if (path.empty()) return "empty output path";
  for (const char ch : path) {
    if (ch == '\0') return "output path contains a NUL character";
  }
  const std::filesystem::path p(path);
  if (p.is_absolute() || p.has_root_name() || p.has_root_directory()) {
    if (allow_absolute) return std::nullopt;
    return "absolute output path '" + path +
           "': a scene writes inside the output folder; make it relative, give -o, or pass --allow-absolute-outputs";
  }
  for (const auto& part : p) {
    if (part == "..") return "output path '" + path + "' leaves the output folder ('..'); make it relative without '..'";
  }
  return std::nullopt;
}

}  // namespace magbake::scene
